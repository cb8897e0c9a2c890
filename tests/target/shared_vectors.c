/*
 * The shared test vectors: one plain C99 program, built for the host, the ATmega128 and
 * the Cortex-M4, that pushes a fixed set of scans and destination bearings through
 * qnav_ctrl_step() with the probabilistic policy, three fixed networks (H = 12; H = 16 and
 * H = 32 with saturating hidden weights, H = 32 only where QNAV_MAX_HIDDEN allows it: not
 * in the ATmega128 build, whose CTest drops those lines from both sides) and table mode
 * (the H = 12 network compiled into vector_table.h, read from flash on AVR).
 * It prints one line per case: heading, speed, quality, flags and an FNV-1a hash of the 360
 * path qualities. CTest compares the output on every platform with the same committed file
 * (expected_vectors.txt), so x86, AVR and ARM must agree bit for bit. The program itself
 * also checks that every path quality of every step equals qnav_ctrl_quality() of that
 * path's (distance level, dtheta) and the chosen quality is their maximum, that table mode
 * equals network mode and that the committed table equals qnav_ctrl_quality() of its
 * network, and that the library's plain reference step (qnav_ctrl_step_plain: every path
 * evaluated) gives the same output and qualities as the fast step on every case, and
 * exits 1 if not.
 */
#include <stdint.h>

#include "qnav/ctrl.h"
#include "qnav/flash.h"
#include "target_io.h"
#include "vector_policy.h"
#include "vector_table.h"

typedef enum {
    SHAPE_RANDOM = 0, /* uniform in 0 .. 1.25 * max range: about a fifth get clipped */
    SHAPE_OPEN,       /* every sector at max range */
    SHAPE_WALL_AHEAD, /* sectors within 45 deg of straight ahead at a tenth of max range */
    SHAPE_CORRIDOR,   /* sides (60..120 deg either way) at 15 % of max range */
    SHAPE_ZERO,       /* every sector at 0 mm: no safe path */
    SHAPE_OVER        /* every sector at 65535 mm: all clipped */
} shape_t;

typedef struct {
    uint16_t n_sectors;
    uint16_t max_range_mm;
    uint8_t shape;
    int16_t goal_cdeg;
    uint32_t seed;
} scan_spec_t;

static const scan_spec_t scans[] = {
    {8u, 5000u, SHAPE_RANDOM, 0, 0x00000008ul},
    {8u, 5000u, SHAPE_WALL_AHEAD, 0, 1ul},
    {16u, 5000u, SHAPE_RANDOM, 9000, 0x00000016ul},
    {16u, 5000u, SHAPE_OPEN, -4550, 1ul},
    {16u, 3000u, SHAPE_CORRIDOR, 17999, 1ul},
    {16u, 5000u, SHAPE_ZERO, 0, 1ul},
    {32u, 5000u, SHAPE_RANDOM, -18000, 0x00000032ul},
    {32u, 5000u, SHAPE_RANDOM, 3050, 0x00003232ul},
    {32u, 5000u, SHAPE_WALL_AHEAD, 100, 1ul},
    {32u, 2000u, SHAPE_OVER, -32768, 1ul},
    {180u, 5000u, SHAPE_RANDOM, 32767, 0x00000180ul},
    {180u, 5000u, SHAPE_CORRIDOR, -9050, 1ul},
    {1u, 5000u, SHAPE_RANDOM, 4500, 0x00000001ul},
    {7u, 65535u, SHAPE_RANDOM, 27000, 0x00000007ul},
    {360u, 5000u, SHAPE_RANDOM, -12345, 0x00000360ul},
};

#define N_SCANS (sizeof scans / sizeof scans[0])

enum { POL_PROB = 0, POL_NET12, POL_NET16, POL_NET32, POL_TABLE, N_POLICIES };
static const char *const policy_names[N_POLICIES] = {"prob ", "net12", "net16", "net32", "table"};

/* Large buffers live here, not on the stack: the ATmega128 has 4 KB of RAM. */
static qnav_mm_t ranges[QNAV_MAX_SECTORS];
static qnav_q1_15_t qualities[QNAV_PATHS];
static uint8_t path_levels[QNAV_PATHS];
static qnav_policy_t policy;
static qnav_ctrl_t ctrl;

/* Is the sector centred at `centre_deg` (0..359) within `half_deg` of `axis_deg`? */
static uint8_t near_axis(uint32_t centre_deg, uint32_t axis_deg, uint32_t half_deg)
{
    uint32_t d = (centre_deg + 360u - axis_deg) % 360u;
    if (d > 180u) {
        d = 360u - d;
    }
    return (uint8_t)(d <= half_deg);
}

static void make_scan(const scan_spec_t *spec)
{
    uint32_t s = spec->seed;
    uint16_t i;
    uint32_t max = spec->max_range_mm;
    for (i = 0; i < spec->n_sectors; ++i) {
        uint32_t centre = ((uint32_t)i * 360u) / spec->n_sectors; /* whole degrees */
        uint32_t r;
        switch (spec->shape) {
        case SHAPE_RANDOM:
            r = qnav_vectors_rand(&s) % (max + max / 4u + 1u);
            break;
        case SHAPE_WALL_AHEAD:
            r = near_axis(centre, 0u, 45u) ? max / 10u : max;
            break;
        case SHAPE_CORRIDOR:
            r = (near_axis(centre, 90u, 30u) || near_axis(centre, 270u, 30u)) ? (max * 15u) / 100u
                                                                              : max;
            break;
        case SHAPE_ZERO:
            r = 0u;
            break;
        case SHAPE_OVER:
            r = 65535u;
            break;
        default:
            r = max;
            break;
        }
        ranges[i] = (qnav_mm_t)(r > 65535u ? 65535u : r);
    }
}

static uint32_t fnv1a_qualities(void)
{
    uint32_t h = 2166136261ul;
    uint16_t i;
    for (i = 0; i < QNAV_PATHS; ++i) {
        uint16_t q = (uint16_t)qualities[i];
        h = (h ^ (q & 0xffu)) * 16777619ul;
        h = (h ^ (uint32_t)(q >> 8)) * 16777619ul;
    }
    return h;
}

static qnav_status_t init_policy(uint8_t which, const qnav_ctrl_config_t *cfg)
{
    switch (which) {
    case POL_PROB:
        qnav_policy_prob_default(&policy);
        return qnav_ctrl_init(&ctrl, cfg, &policy);
    case POL_NET12:
        qnav_vectors_net_policy(&policy, 12u, QNAV_VECTORS_NET12_SEED, 0u);
        return qnav_ctrl_init(&ctrl, cfg, &policy);
    case POL_NET16:
        qnav_vectors_net_policy(&policy, 16u, QNAV_VECTORS_NET16_SEED, 1u);
        return qnav_ctrl_init(&ctrl, cfg, &policy);
    case POL_NET32:
        qnav_vectors_net_policy(&policy, 32u, QNAV_VECTORS_NET32_SEED, 1u);
        return qnav_ctrl_init(&ctrl, cfg, &policy);
    default:
        return qnav_ctrl_init_table(&ctrl, cfg, qnav_vectors_net12_table, QNAV_VECTORS_NET12_TABLE_RANK);
    }
}

static void put_result(const qnav_ctrl_output_t *out, uint32_t hash)
{
    qnav_target_put(" heading=");
    qnav_target_put_i32(out->heading_deg);
    qnav_target_put(" speed=");
    qnav_target_put_i32(out->speed);
    qnav_target_put(" quality=");
    qnav_target_put_i32(out->quality);
    qnav_target_put(" flags=");
    qnav_target_put_hex(out->flags, 2u);
    qnav_target_put(" qhash=");
    qnav_target_put_hex(hash, 8u);
    qnav_target_put("\n");
}

/* Paths whose quality from the step differs from qnav_ctrl_quality() of the path's own
 * (distance level after enlargement, dtheta), plus 1 if the chosen path's quality is not
 * that of the largest key: the step's fast paths (run bounds, table rows) must give
 * exactly what the policy function gives. */
static uint16_t step_inconsistencies(const scan_spec_t *spec, const qnav_ctrl_output_t *out)
{
    int32_t c = spec->goal_cdeg;
    int32_t g = (c >= 0) ? (c + 50) / 100 : -((-c + 50) / 100); /* nearest, halves away */
    uint16_t goal;
    uint16_t i;
    uint16_t bad = 0;
    qnav_qkey_t max_key = -32767;
    g %= 360;
    goal = (uint16_t)(g < 0 ? g + 360 : g);
    if (qnav_ctrl_path_levels(&ctrl, ranges, path_levels) & QNAV_FLAG_NOT_READY) {
        return 0; /* the bad-configuration case: nothing to compare */
    }
    (void)spec;
    for (i = 0; i < QNAV_PATHS; ++i) {
        uint8_t level = path_levels[i];
        uint16_t d = (uint16_t)((i + 360u - goal) % 360u);
        qnav_qkey_t k;
        if (d > 180u) {
            d = (uint16_t)(360u - d);
        }
        k = qnav_ctrl_key(&ctrl, level, (uint8_t)d);
        if (qnav_ctrl_key_quality(&ctrl, k) != qualities[i]) {
            ++bad;
        }
        if (k > max_key) {
            max_key = k;
        }
    }
    if (qnav_ctrl_key_quality(&ctrl, max_key) != out->quality) {
        ++bad;
    }
    return bad;
}

/* 1 if the plain reference step decides otherwise than the fast step's out and hash (its
 * qualities overwrite the fast step's: the ATmega128 has no RAM for a second copy). */
static uint16_t plain_differs(const qnav_ctrl_input_t *in, const qnav_ctrl_output_t *fast,
                              uint32_t fast_hash)
{
    qnav_ctrl_output_t plain;
    qnav_ctrl_step_plain(&ctrl, in, &plain, qualities);
    return (uint16_t)(plain.heading_deg != fast->heading_deg || plain.speed != fast->speed ||
                      plain.quality != fast->quality || plain.flags != fast->flags ||
                      fnv1a_qualities() != fast_hash);
}

/* Entries of the committed table that differ from the network evaluated directly. */
static uint16_t table_mismatches(void)
{
    qnav_ctrl_config_t cfg;
    uint16_t level;
    uint16_t dtheta;
    uint16_t bad = 0;
    qnav_ctrl_config_default(&cfg);
    if (init_policy(POL_NET12, &cfg) != QNAV_OK) {
        return QNAV_QTABLE_ENTRIES;
    }
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        for (dtheta = 0; dtheta <= QNAV_DTHETA_MAX; ++dtheta) {
            uint16_t k = (uint16_t)(level * (QNAV_DTHETA_MAX + 1u) + dtheta);
            if (QNAV_FLASH_READ_I16(&qnav_vectors_net12_table[k]) !=
                qnav_ctrl_key(&ctrl, (uint8_t)level, (uint8_t)dtheta)) {
                ++bad;
            }
        }
    }
    return bad;
}

/* What the cases found, summed over the run: main prints it at the end and fails on any
 * non-zero count. The network case's result is kept for the table case that follows it. */
typedef struct {
    uint8_t failed;
    uint16_t table_differs;
    uint16_t step_differs;
    uint16_t plain_steps_differ;
    qnav_ctrl_output_t net12_out;
    uint32_t net12_hash;
} tally_t;

static void put_case_name(uint16_t c, uint8_t p, const scan_spec_t *spec)
{
    qnav_target_put("v");
    qnav_target_put_u32(c);
    qnav_target_put(" ");
    qnav_target_put(policy_names[p]);
    qnav_target_put(" n=");
    qnav_target_put_u32(spec->n_sectors);
    qnav_target_put(" max=");
    qnav_target_put_u32(spec->max_range_mm);
    qnav_target_put(" goal=");
    qnav_target_put_i32(spec->goal_cdeg);
}

/* One line: scan c under policy p, then the checks of that step against
 * qnav_ctrl_quality(), the plain step and (table mode) the network it was made from. */
static void run_case(uint16_t c, uint8_t p, const qnav_ctrl_config_t *cfg,
                     const qnav_ctrl_input_t *in, tally_t *t)
{
    qnav_ctrl_output_t out;
    qnav_status_t st = init_policy(p, cfg);
    uint32_t hash;
    qnav_ctrl_step(&ctrl, in, &out, qualities);
    hash = fnv1a_qualities();
    put_case_name(c, p, &scans[c]);
    if (st != QNAV_OK) {
        qnav_target_put(" init=");
        qnav_target_put_i32(st);
        t->failed = 1;
    }
    put_result(&out, hash);
    t->step_differs = (uint16_t)(t->step_differs + step_inconsistencies(&scans[c], &out));
    t->plain_steps_differ = (uint16_t)(t->plain_steps_differ + plain_differs(in, &out, hash));
    if (p == POL_NET12) {
        t->net12_out = out;
        t->net12_hash = hash;
    } else if (p == POL_TABLE &&
               (out.heading_deg != t->net12_out.heading_deg || out.speed != t->net12_out.speed ||
                out.quality != t->net12_out.quality || out.flags != t->net12_out.flags ||
                hash != t->net12_hash)) {
        ++t->table_differs;
    }
}

static void run_scan(uint16_t c, tally_t *t)
{
    const scan_spec_t *spec = &scans[c];
    qnav_ctrl_config_t cfg;
    qnav_ctrl_input_t in = {0};
    uint8_t p;
    make_scan(spec);
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = spec->n_sectors;
    cfg.max_range_mm = spec->max_range_mm;
    in.ranges_mm = ranges;
    in.goal_bearing_cdeg = spec->goal_cdeg;
    in.prev_heading_cdeg = 0; /* 2-input policies ignore it */
    for (p = 0; p < N_POLICIES; ++p) {
        if (p == POL_NET32 && QNAV_MAX_HIDDEN < 32) {
            continue; /* the ATmega128 build holds 16 hidden units */
        }
        run_case(c, p, &cfg, &in, t);
    }
}

/* A controller whose init failed must command a stop. */
static void run_bad_config(tally_t *t)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 0u;
    qnav_policy_prob_default(&policy);
    qnav_target_put("bad-config init=");
    qnav_target_put_i32(qnav_ctrl_init(&ctrl, &cfg, &policy));
    make_scan(&scans[0]);
    in.ranges_mm = ranges;
    in.goal_bearing_cdeg = 0;
    in.prev_heading_cdeg = 0; /* 2-input policies ignore it */
    qnav_ctrl_step(&ctrl, &in, &out, qualities);
    put_result(&out, fnv1a_qualities());
    t->plain_steps_differ =
        (uint16_t)(t->plain_steps_differ + plain_differs(&in, &out, fnv1a_qualities()));
}

static void put_count(const char *before, uint32_t n, const char *after)
{
    qnav_target_put(before);
    qnav_target_put_u32(n);
    qnav_target_put(after);
}

int main(void)
{
    tally_t t = {0};
    uint16_t c;
    uint16_t bad;

    put_count("qnav shared vectors v2: ", N_SCANS,
              " scans x 5 policies (net32 where QNAV_MAX_HIDDEN >= 32)\n");
    for (c = 0; c < N_SCANS; ++c) {
        run_scan(c, &t);
    }
    run_bad_config(&t);

    put_count("step differs from qnav_ctrl_quality() on ", t.step_differs, " paths or choices\n");
    put_count("plain step differs from the fast step on ", t.plain_steps_differ, " cases\n");
    put_count("table mode differs from network mode on ", t.table_differs, " scans\n");
    bad = table_mismatches();
    put_count("committed table differs from its network on ", bad, " of ");
    put_count("", QNAV_QTABLE_ENTRIES, " entries\n");
    if (t.table_differs != 0u || bad != 0u || t.step_differs != 0u || t.plain_steps_differ != 0u) {
        t.failed = 1;
    }
    qnav_target_exit(t.failed);
    return t.failed;
}
