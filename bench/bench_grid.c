/*
 * The benchmark grid (bench_grid.h): walks the fixtures, checks each measured heading
 * against the library's plain step (qnav_ctrl_step_plain), prints the M lines.
 */
#include "bench_grid.h"

/* The set the grid walks: the fixtures, or the adversarial set (bench/adversary/). */
#if defined(QNAV_BENCH_ADVERSARY) && QNAV_BENCH_ADVERSARY
#include "adversary/bench_policies.h"
#include "adversary/bench_scans.h"
#else
#include "bench_policies.h"
#include "bench_scans.h"
#endif
#include "target_io.h"

static const char *const mode_names[QNAV_BENCH_MODES] = {"network", "probabilistic", "table",
                                                          "network3"};
static const char *const set_names[QNAV_BENCH_SETS] = QNAV_BENCH_SET_NAMES;
static const char *const scan_names[QNAV_BENCH_SCAN_TYPES] = QNAV_BENCH_SCAN_NAMES;

/* Scratch in RAM: one scan, one policy, one controller. */
static qnav_mm_t ranges[QNAV_MAX_SECTORS];
static qnav_policy_t policy;
static qnav_ctrl_t ctrl;
static char policy_id[QNAV_BENCH_ID_LEN];

const char *qnav_bench_mode_name(uint8_t mode)
{
    return mode < QNAV_BENCH_MODES ? mode_names[mode] : "?";
}

qnav_mm_t *qnav_bench_scratch_ranges(void)
{
    return ranges;
}

qnav_ctrl_t *qnav_bench_scratch_ctrl(void)
{
    return &ctrl;
}

qnav_policy_t *qnav_bench_scratch_policy(void)
{
    return &policy;
}

uint16_t qnav_bench_scan_count(void)
{
    return QNAV_BENCH_SCAN_COUNT;
}

uint8_t qnav_bench_policy_count(void)
{
    return QNAV_BENCH_POLICY_COUNT;
}

qnav_mm_t qnav_bench_max_range_mm(void)
{
    return QNAV_BENCH_MAX_RANGE_MM;
}

void qnav_bench_config(qnav_ctrl_config_t *cfg, uint16_t n_sectors)
{
    qnav_ctrl_config_default(cfg);
    cfg->n_sectors = n_sectors;
    cfg->max_range_mm = QNAV_BENCH_MAX_RANGE_MM;
}

uint16_t qnav_bench_load_scan(uint16_t index, qnav_mm_t *r, qnav_cdeg_t *bearing, uint8_t *type,
                              uint8_t *k)
{
    qnav_bench_scan_t s;
    qnav_bench_flash_copy(&s, &qnav_bench_scans[index], sizeof s);
    qnav_bench_flash_copy(r, s.ranges, (size_t)s.n_sectors * sizeof r[0]);
    *bearing = s.goal_bearing_cdeg;
    *type = s.type;
    *k = s.k;
    return s.n_sectors;
}

uint8_t qnav_bench_load_policy(uint8_t index, qnav_policy_t *p, char *id)
{
    const qnav_bench_policy_t *f = &qnav_bench_policies[index];
    uint8_t set;
    qnav_bench_flash_copy(p, &f->policy, sizeof *p);
    qnav_bench_flash_copy(id, f->id, QNAV_BENCH_ID_LEN);
    qnav_bench_flash_copy(&set, &f->set, 1);
    return set;
}

#if !QNAV_TABLES_IN_FLASH
const qnav_qkey_t *qnav_bench_ram_table(uint8_t index, const qnav_policy_t *p, uint8_t *rank)
{
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    static uint8_t built = 0xffu;
    static qnav_ctrl_t builder;
    qnav_ctrl_config_t cfg;
    if (built != index) {
        qnav_bench_config(&cfg, 32u);
        if (qnav_ctrl_init(&builder, &cfg, p) != QNAV_OK ||
            qnav_ctrl_build_table(&builder, table) != QNAV_OK) {
            return 0;
        }
        built = index;
    }
    *rank = (uint8_t)qnav_ctrl_rank(&builder);
    return table;
}
#endif

/* The mode a policy is measured in besides table mode. */
static uint8_t own_mode(const qnav_policy_t *p)
{
    switch ((qnav_policy_kind_t)p->kind) {
    case QNAV_POLICY_PROB:
        return QNAV_BENCH_PROB;
    case QNAV_POLICY_NET:
        return p->u.net.inputs == QNAV_NET_INPUTS_PREV ? QNAV_BENCH_NETWORK3 : QNAV_BENCH_NETWORK;
    }
    return QNAV_BENCH_MODES;
}

static void put_field(char sep, const char *key, const char *value)
{
    char s[2];
    s[0] = sep;
    s[1] = '\0';
    qnav_target_put(s);
    qnav_target_put(key);
    qnav_target_put(value);
}

static void put_line(const qnav_bench_hooks_t *h, uint8_t mode, uint8_t set, uint16_t n,
                     uint8_t type, uint8_t k, uint32_t value)
{
    char s[2];
    s[0] = h->sep;
    s[1] = '\0';
    qnav_target_put("M");
    put_field(h->sep, "target=", h->target);
    put_field(h->sep, "mode=", mode_names[mode]);
    put_field(h->sep, "H=", "");
    switch ((qnav_policy_kind_t)policy.kind) {
    case QNAV_POLICY_NET:
        qnav_target_put_u32(policy.u.net.hidden);
        break;
    case QNAV_POLICY_PROB:
        qnav_target_put("-");
        break;
    }
    put_field(h->sep, "N=", "");
    qnav_target_put_u32(n);
    put_field(h->sep, "policy=", policy_id);
    put_field(h->sep, "set=", set_names[set]);
    put_field(h->sep, "scan=", scan_names[type]);
    qnav_target_put(":");
    qnav_target_put_u32(k);
    qnav_target_put(s);
    if (h->has_value) {
        qnav_target_put_u32(value);
    } else {
        qnav_target_put("-");
    }
    qnav_target_put("\n");
}

static void put_mismatch(const qnav_bench_hooks_t *h, uint8_t mode, uint16_t n, uint8_t type,
                         uint8_t k, int16_t got, int16_t want)
{
    qnav_target_put("MISMATCH target=");
    qnav_target_put(h->target);
    qnav_target_put(" mode=");
    qnav_target_put(mode_names[mode]);
    qnav_target_put(" policy=");
    qnav_target_put(policy_id);
    qnav_target_put(" N=");
    qnav_target_put_u32(n);
    qnav_target_put(" scan=");
    qnav_target_put(scan_names[type]);
    qnav_target_put(":");
    qnav_target_put_u32(k);
    qnav_target_put(": heading ");
    qnav_target_put_i32(got);
    qnav_target_put(", plain step ");
    qnav_target_put_i32(want);
    qnav_target_put("\n");
}

/* Initialise ctrl for a mode; the table (table mode) must be set. */
static qnav_status_t init_mode(uint8_t mode, uint16_t n, const qnav_qkey_t *table, uint8_t rank)
{
    qnav_ctrl_config_t cfg;
    qnav_bench_config(&cfg, n);
    if (mode == QNAV_BENCH_TABLE) {
        return qnav_ctrl_init_table(&ctrl, &cfg, table, (qnav_rank_t)rank);
    }
    return qnav_ctrl_init(&ctrl, &cfg, &policy);
}

/* One policy in one mode over every scan; returns the mismatches. The controller is made
 * once per sector count (a network's init evaluates every row of keys: about 0.8 s on the
 * ATmega128 at H = 12, docs/performance.md), and each measured step is checked against
 * the library's plain reference step (qnav_ctrl_step_plain: every path evaluated from its
 * own inputs) on the same controller: heading, speed, quality and flags must be equal. */
static uint16_t run_policy(const qnav_bench_hooks_t *h, uint8_t index, uint8_t mode, uint8_t set)
{
    const qnav_qkey_t *table = 0;
    uint8_t rank = 0;
    uint16_t bad = 0;
    uint16_t ready_n = 0;
    uint16_t s;
    if (mode == QNAV_BENCH_TABLE) {
        table = h->table ? h->table(index, &policy, &rank) : 0;
        if (!table) {
            return 0;
        }
    }
    for (s = 0; s < QNAV_BENCH_SCAN_COUNT; ++s) {
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t ref, out;
        uint8_t type, k;
        uint32_t v;
        uint16_t n = qnav_bench_load_scan(s, ranges, &in.goal_bearing_cdeg, &type, &k);
        in.ranges_mm = ranges;
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        if (n != ready_n) {
            if (init_mode(mode, n, table, rank) != QNAV_OK) {
                qnav_target_put("init failed: ");
                qnav_target_put(policy_id);
                qnav_target_put("\n");
                return (uint16_t)(bad + 1u);
            }
            ready_n = n;
        }
        qnav_ctrl_step_plain(&ctrl, &in, &ref, 0);
        v = h->measure(&ctrl, &in, &out, mode);
        put_line(h, mode, set, n, type, k, v);
        if (out.heading_deg != ref.heading_deg || out.speed != ref.speed ||
            out.quality != ref.quality || out.flags != ref.flags) {
            put_mismatch(h, mode, n, type, k, out.heading_deg, ref.heading_deg);
            ++bad;
        }
    }
    return bad;
}

uint16_t qnav_bench_grid(const qnav_bench_hooks_t *h)
{
    uint16_t bad = 0;
    uint8_t mode, i;
    for (mode = 0; mode < QNAV_BENCH_MODES; ++mode) {
        if (!(h->modes & QNAV_BENCH_MODE_BIT(mode))) {
            continue;
        }
        for (i = 0; i < QNAV_BENCH_POLICY_COUNT; ++i) {
            uint8_t set = qnav_bench_load_policy(i, &policy, policy_id);
            uint8_t own = own_mode(&policy);
            if (own == mode || (mode == QNAV_BENCH_TABLE && own == QNAV_BENCH_NETWORK)) {
                bad = (uint16_t)(bad + run_policy(h, i, mode, set));
            }
        }
    }
    return bad;
}
