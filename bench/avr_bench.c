/*
 * Cycle benchmark of qnav_ctrl_step() on an ATmega128 at 16 MHz, run under simavr
 * (cycle-accurate), over the benchmark set (bench_grid.h). Timer1 counts every clock
 * (clk/1) and its overflow interrupt extends it to 32 bits; the fixed cost of starting
 * and stopping the timer is measured and subtracted, and a delay loop of known length
 * checks the method. The peak stack of a step is found by painting free RAM before every
 * measured step and looking for the high-water mark after it.
 *
 * One image cannot hold every compiled table (11 584 B of flash each) beside the scans,
 * and libqnav reads flash data with 16-bit addresses (LPM): QNAV_BENCH_TABLE_GROUP = 0
 * builds the network image (network, probabilistic and 3-input modes, the naive float
 * network and VFH+ for comparison), 1..7 a table image with that group's table (bench_tables.h).
 * The program refuses to run when its flash data reach past 64 KB.
 * simavr's console drops control characters, so M lines use '~' for TAB; bench/run-bench
 * turns it back.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <math.h>
#include <stdint.h>
#include <util/delay_basic.h>

#include "avr_clock.h"
#include "bench_grid.h"
#include "qnav/vfh.h"
#include "target_io.h"

#ifndef QNAV_BENCH_TABLE_GROUP
#define QNAV_BENCH_TABLE_GROUP 0
#endif
#if QNAV_BENCH_TABLE_GROUP
#include "bench_tables.h"
#endif

static uint32_t overhead;
static uint16_t peak_stack[QNAV_BENCH_MODES];
static uint32_t steps[QNAV_BENCH_MODES];

/* Paint free RAM, time one step, and record how many bytes below this frame's stack
 * pointer it wrote. */
static uint32_t measure(const qnav_ctrl_t *c, const qnav_ctrl_input_t *in,
                        qnav_ctrl_output_t *out, uint8_t mode)
{
    const uint16_t sp = qnav_avr_paint();
    uint32_t cycles;
    uint16_t used;
    qnav_avr_timer_start();
    qnav_ctrl_step(c, in, out, 0);
    cycles = qnav_avr_timer_stop() - overhead;
    used = qnav_avr_stack_used(sp);
    if (used > peak_stack[mode]) {
        peak_stack[mode] = used;
    }
    ++steps[mode];
    return cycles;
}

#if QNAV_BENCH_TABLE_GROUP
static const qnav_qkey_t *flash_table(uint8_t index, const qnav_policy_t *p, uint8_t *rank)
{
    uint8_t j;
    (void)p;
    for (j = 0; j < QNAV_BENCH_GROUP_TABLES; ++j) {
        if (qnav_bench_group_policy[j] == index) {
            *rank = qnav_bench_group_rank[j];
            return qnav_bench_group_table[j];
        }
    }
    return 0;
}
#endif

#if !QNAV_BENCH_TABLE_GROUP

/* ---- naive float network, for the ratio ---------------------------------------------- */

static float w_theta_f[12], w_dist_f[12], b_hidden_f[12], w_out_f[12], b_out_f; /* H = 12 */
static uint8_t hidden_f;

/* avr-libc's expf is exp on a 32-bit double: the conversions are spelled out. */
static float naive_expf(float x)
{
    return (float)exp((double)x);
}

static void naive_load(const qnav_policy_t *policy)
{
    uint8_t j;
    hidden_f = policy->u.net.hidden;
    for (j = 0; j < hidden_f; ++j) {
        w_theta_f[j] = (float)policy->u.net.w_theta[j] / 256.0f;
        w_dist_f[j] = (float)policy->u.net.w_dist[j] / 256.0f;
        b_hidden_f[j] = (float)policy->u.net.b_hidden[j] / 256.0f;
        w_out_f[j] = (float)policy->u.net.w_out[j] / 256.0f;
    }
    b_out_f = (float)policy->u.net.b_out / 256.0f;
}

/* The straightforward float controller: for every path, its sector's range, the angular
 * distance to the goal, two sigmoid layers with expf; keep the best. Returns the heading. */
__attribute__((noinline)) static int16_t naive_float_step(const qnav_mm_t *r, uint16_t n,
                                                         float goal_deg, float max_mm)
{
    float best_q = -1.0f;
    int16_t best = 0;
    int16_t i;
    uint8_t j;
    for (i = 0; i < 360; ++i) {
        uint16_t sector = (uint16_t)(((float)i * (float)n / 360.0f) + 0.5f) % n;
        float d = (float)r[sector];
        float dtheta = fabsf((float)i - goal_deg);
        float acc = b_out_f;
        float q;
        if (d > max_mm) {
            d = max_mm;
        }
        if (dtheta > 180.0f) {
            dtheta = 360.0f - dtheta;
        }
        for (j = 0; j < hidden_f; ++j) {
            float z = w_theta_f[j] * (dtheta / 180.0f) + w_dist_f[j] * (d / max_mm) + b_hidden_f[j];
            acc += w_out_f[j] / (1.0f + naive_expf(-z));
        }
        q = 1.0f / (1.0f + naive_expf(-acc));
        if (q > best_q) {
            best_q = q;
            best = i;
        }
    }
    return (int16_t)(best > 180 ? best - 360 : best);
}

/* Sort t[0..n-1] (a handful of values: insertion). */
static void sort_u32(uint32_t *t, uint8_t n)
{
    uint8_t i, j;
    for (i = 1; i < n; ++i) {
        uint32_t v = t[i];
        for (j = i; j > 0u && t[j - 1u] > v; --j) {
            t[j] = t[j - 1u];
        }
        t[j] = v;
    }
}

/* Up to this many policies of one hidden-unit count are timed. */
#define INIT_TIMED_MAX 24u

/* Times of qnav_ctrl_init (carried 0) or of qnav_ctrl_init_carried with the shapes the
 * policy carries (carried 1, made untimed first, as a host makes them) for every 2-input
 * network of H hidden units, sorted into t; their count. */
static uint8_t init_times_of(uint8_t hidden, uint8_t carried, uint32_t *t)
{
    static uint8_t shapes[QNAV_SHAPES_BYTES];
    qnav_ctrl_t *c = qnav_bench_scratch_ctrl();
    qnav_policy_t *p = qnav_bench_scratch_policy();
    char id[QNAV_BENCH_ID_LEN];
    qnav_ctrl_config_t cfg;
    uint8_t i, count = 0;
    qnav_bench_config(&cfg, 32u);
    for (i = 0; i < qnav_bench_policy_count() && count < INIT_TIMED_MAX; ++i) {
        qnav_status_t st;
        (void)qnav_bench_load_policy(i, p, id);
        if (p->kind != QNAV_POLICY_NET || p->u.net.hidden != hidden ||
            p->u.net.inputs != QNAV_NET_INPUTS_PAPER) {
            continue;
        }
        if (carried && (qnav_ctrl_init(c, &cfg, p) != QNAV_OK ||
                        qnav_ctrl_shapes_save(c, p, shapes) != QNAV_OK)) {
            continue;
        }
        qnav_avr_timer_start();
        st = carried ? qnav_ctrl_init_carried(c, &cfg, p, shapes, sizeof shapes)
                     : qnav_ctrl_init(c, &cfg, p);
        t[count] = qnav_avr_timer_stop() - overhead;
        if (carried && !qnav_ctrl_shapes_carried(c)) {
            PUT("init: carried shapes not taken: ");
            qnav_target_put(id);
            PUT("\n");
        }
        if (st == QNAV_OK) {
            ++count;
        }
    }
    sort_u32(t, count);
    return count;
}

/* What qnav_ctrl_init costs for every network of the set (2 inputs: it learns the shape
 * of each of the 32 rows of keys, docs/architecture.md "Row shapes"), and with the shapes
 * the policy carries (qnav_ctrl_init_carried); not a step, so not an M line: printed per
 * hidden-unit count as min / median (lower) / max. */
static void init_times(void)
{
    static const uint8_t hs[] = {4u, 8u, 12u, 16u};
    uint32_t t[INIT_TIMED_MAX];
    uint8_t h, carried;
    for (carried = 0; carried < 2u; ++carried) {
        for (h = 0; h < sizeof hs; ++h) {
            uint8_t count = init_times_of(hs[h], carried, t);
            if (count == 0u) {
                continue;
            }
            if (carried) {
                PUT("qnav_ctrl_init_carried, 2-input network H=");
            } else {
                PUT("qnav_ctrl_init, 2-input network H=");
            }
            qnav_target_put_u32(hs[h]);
            PUT(" (");
            qnav_target_put_u32(count);
            PUT(" policies): min ");
            qnav_avr_put_cycles(t[0]);
            PUT(", median ");
            qnav_avr_put_cycles(t[(count - 1u) / 2u]);
            PUT(", max ");
            qnav_avr_put_cycles(t[count - 1u]);
            PUT("\n");
        }
    }
}

/* The naive float network against the fixed-point network step, both on the first
 * evolved H = 12 policy, over every dense 32-sector scan. */
static void naive_comparison(void)
{
    qnav_mm_t *r = qnav_bench_scratch_ranges();
    qnav_ctrl_t *c = qnav_bench_scratch_ctrl();
    qnav_policy_t *p = qnav_bench_scratch_policy();
    char id[QNAV_BENCH_ID_LEN];
    qnav_ctrl_config_t cfg;
    volatile int16_t naive_heading; /* kept: the call must not be optimised away */
    uint32_t naive = 0, fixed = 0;
    uint8_t scans = 0, i = 0;
    uint16_t s;
    while (i < qnav_bench_policy_count() &&
           (qnav_bench_load_policy(i, p, id) != QNAV_BENCH_SET_EVOLVED ||
            p->kind != QNAV_POLICY_NET || p->u.net.hidden != 12u)) {
        ++i;
    }
    if (i == qnav_bench_policy_count()) {
        return;
    }
    naive_load(p);
    qnav_bench_config(&cfg, 32u);
    if (qnav_ctrl_init(c, &cfg, p) != QNAV_OK) {
        return;
    }
    for (s = 0; s < qnav_bench_scan_count(); ++s) {
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t out;
        uint8_t type, k;
        uint32_t t;
        if (qnav_bench_load_scan(s, r, &in.goal_bearing_cdeg, &type, &k) != 32u ||
            type != QNAV_BENCH_SCAN_DENSE) {
            continue;
        }
        in.ranges_mm = r;
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        qnav_avr_timer_start();
        naive_heading = naive_float_step(r, 32u, (float)in.goal_bearing_cdeg / 100.0f,
                               (float)qnav_bench_max_range_mm());
        t = qnav_avr_timer_stop() - overhead;
        naive += t;
        qnav_avr_timer_start();
        qnav_ctrl_step(c, &in, &out, 0);
        fixed += qnav_avr_timer_stop() - overhead;
        ++scans;
    }
    (void)naive_heading;
    PUT("naive float network (expf, 360 paths x H, per-sector ranges), ");
    qnav_target_put(id);
    PUT(", mean of ");
    qnav_target_put_u32(scans);
    PUT(" dense 32-sector scans: ");
    qnav_avr_put_cycles(naive / scans);
    PUT("; fixed-point network step ");
    qnav_avr_put_cycles(fixed / scans);
    PUT("; ratio ");
    qnav_target_put_u32((naive + fixed / 2u) / fixed);
    PUT(".");
    qnav_target_put_u32(((naive * 10u + fixed / 2u) / fixed) % 10u);
    PUT("\n");
}


/* What a decision that stood twice the stall time and stands again adds (a reading at
 * 1 mm straight ahead: every path's speed cap is 0): sent into a free window
 * (docs/architecture.md, "A robot that stands"), the same step with the count at 255
 * against 0, on scan r toward goal_cdeg. */
static uint32_t stood_cost(const qnav_ctrl_t *c, qnav_mm_t *r, qnav_cdeg_t goal_cdeg)
{
    const qnav_mm_t ahead = r[0];
    uint32_t fresh, stood;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    in.ranges_mm = r;
    in.goal_bearing_cdeg = goal_cdeg;
    in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
    in.goal_range_mm = 3000u;
    r[0] = 1u;
    qnav_avr_timer_start();
    qnav_ctrl_step(c, &in, &out, 0);
    fresh = qnav_avr_timer_stop() - overhead;
    in.escape.stood = 255u;
    qnav_avr_timer_start();
    qnav_ctrl_step(c, &in, &out, 0);
    stood = qnav_avr_timer_stop() - overhead;
    r[0] = ahead;
    return stood > fresh ? stood - fresh : 0u;
}

/* What the escape memory (docs/architecture.md, "Leaving dead ends") adds to a step: the
 * probabilistic policy on every 32-sector scan, the step without a distance (escape off)
 * against the same step while following a boundary (the skirt search every tick) and on
 * the tick a stall begins a follow (side choice + skirt search). */
static void escape_cost(void)
{
    qnav_mm_t *r = qnav_bench_scratch_ranges();
    qnav_ctrl_t *c = qnav_bench_scratch_ctrl();
    qnav_policy_t *p = qnav_bench_scratch_policy();
    qnav_ctrl_config_t cfg;
    uint32_t follow_max = 0, enter_max = 0, follow_sum = 0, unstand_max = 0;
    uint8_t n = 0;
    uint16_t s;
    qnav_policy_prob_default(p);
    qnav_bench_config(&cfg, 32u);
    if (qnav_ctrl_init(c, &cfg, p) != QNAV_OK) {
        PUT("escape: init failed\n");
        return;
    }
    for (s = 0; s < qnav_bench_scan_count(); ++s) {
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t out;
        uint8_t type, k;
        uint32_t off, follow, enter, t;
        if (qnav_bench_load_scan(s, r, &in.goal_bearing_cdeg, &type, &k) != 32u) {
            continue;
        }
        in.ranges_mm = r;
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        qnav_avr_timer_start();
        qnav_ctrl_step(c, &in, &out, 0);
        off = qnav_avr_timer_stop() - overhead;
        in.goal_range_mm = 3000u;
        in.escape.best_mm = 2000u;
        in.escape.hit_mm = 2000u;
        in.escape.side = 1;
        in.escape.last_side = 1;
        qnav_avr_timer_start();
        qnav_ctrl_step(c, &in, &out, 0);
        follow = qnav_avr_timer_stop() - overhead;
        in.escape.side = 0;
        in.escape.last_side = 0;
        in.escape.ticks = (uint16_t)(cfg.escape_stall_ticks - 1u);
        qnav_avr_timer_start();
        qnav_ctrl_step(c, &in, &out, 0);
        enter = qnav_avr_timer_stop() - overhead;
        t = stood_cost(c, r, in.goal_bearing_cdeg);
        unstand_max = t > unstand_max ? t : unstand_max;
        follow = follow > off ? follow - off : 0u;
        enter = enter > off ? enter - off : 0u;
        follow_sum += follow;
        follow_max = follow > follow_max ? follow : follow_max;
        enter_max = enter > enter_max ? enter : enter_max;
        ++n;
    }
    PUT("escape memory on the ");
    qnav_target_put_u32(n);
    PUT(" 32-sector scans, probabilistic policy: following adds mean ");
    qnav_avr_put_cycles(follow_sum / n);
    PUT(", max ");
    qnav_target_put_u32(follow_max);
    PUT(" cycles; the tick a follow begins adds max ");
    qnav_target_put_u32(enter_max);
    PUT(" cycles; a decision that stood twice the stall time, sent into a free window, max ");
    qnav_target_put_u32(unstand_max);
    PUT(" cycles; sizeof(qnav_escape_t) ");
    qnav_target_put_u32(sizeof(qnav_escape_t));
    PUT(" bytes\n");
}

/* What holding the heading (docs/architecture.md, "Holding the heading") adds to a step of
 * policy p (initialised once, keep_pct then set to 0 and to the TekBot profile's 15 for each
 * 32-sector scan): one key of the previous heading's path (a lookup for the probabilistic
 * policy, H units' evaluation for a network) and the comparison. A scan whose step got
 * cheaper counts as 0. */
static void keep_cost_of(const qnav_policy_t *p, const char *label)
{
    qnav_mm_t *r = qnav_bench_scratch_ranges();
    qnav_ctrl_t *c = qnav_bench_scratch_ctrl();
    qnav_ctrl_config_t cfg;
    uint32_t cost[2];
    uint32_t add_max = 0, add_sum = 0;
    uint8_t n = 0;
    uint16_t s;
    uint8_t keep;
    qnav_bench_config(&cfg, 32u);
    if (qnav_ctrl_init(c, &cfg, p) != QNAV_OK) {
        PUT("holding: init failed\n");
        return;
    }
    for (s = 0; s < qnav_bench_scan_count(); ++s) {
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t out;
        uint8_t type, k;
        if (qnav_bench_load_scan(s, r, &in.goal_bearing_cdeg, &type, &k) != 32u) {
            continue;
        }
        in.ranges_mm = r;
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        for (keep = 0; keep < 2u; ++keep) {
            c->keep_pct = (uint8_t)(keep ? 15u : 0u);
            qnav_avr_timer_start();
            qnav_ctrl_step(c, &in, &out, 0);
            cost[keep] = qnav_avr_timer_stop() - overhead;
        }
        cost[1] = cost[1] > cost[0] ? cost[1] - cost[0] : 0u;
        add_sum += cost[1];
        add_max = cost[1] > add_max ? cost[1] : add_max;
        ++n;
    }
    PUT("holding the heading (keep_pct 15) on the ");
    qnav_target_put_u32(n);
    PUT(" 32-sector scans, ");
    qnav_target_put(label);
    PUT(": adds mean ");
    qnav_avr_put_cycles(add_sum / n);
    PUT(", max ");
    qnav_target_put_u32(add_max);
    PUT(" cycles\n");
}

/* The hold's cost for the probabilistic policy and the first evolved H = 12 network. */
static void keep_cost(void)
{
    qnav_policy_t *p = qnav_bench_scratch_policy();
    char id[QNAV_BENCH_ID_LEN];
    uint8_t i = 0;
    qnav_policy_prob_default(p);
    keep_cost_of(p, "probabilistic policy");
    while (i < qnav_bench_policy_count() &&
           (qnav_bench_load_policy(i, p, id) != QNAV_BENCH_SET_EVOLVED ||
            p->kind != QNAV_POLICY_NET || p->u.net.hidden != 12u)) {
        ++i;
    }
    if (i < qnav_bench_policy_count()) {
        keep_cost_of(p, "evolved network (H = 12)");
    }
}

/* VFH+ (qnav/vfh.h), the second controller, on every 32-sector scan through its own step
 * (free text: the M lines are the path-quality controller's). */
static void vfh_comparison(void)
{
    static qnav_vfh_t vfh;
    static qnav_vfh_state_t vstate;
    qnav_mm_t *r = qnav_bench_scratch_ranges();
    qnav_vfh_config_t vcfg;
    uint32_t lo = 0xfffffffful, hi = 0, sum = 0;
    uint8_t n = 0;
    uint16_t s;
    qnav_vfh_config_default(&vcfg);
    vcfg.body.n_sectors = 32u;
    vcfg.body.max_range_mm = qnav_bench_max_range_mm();
    if (qnav_vfh_init(&vfh, &vcfg) != QNAV_OK) {
        PUT("VFH+ init failed\n");
        return;
    }
    for (s = 0; s < qnav_bench_scan_count(); ++s) {
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t out;
        uint8_t type, k;
        uint32_t c;
        if (qnav_bench_load_scan(s, r, &in.goal_bearing_cdeg, &type, &k) != 32u) {
            continue;
        }
        in.ranges_mm = r;
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        qnav_vfh_state_reset(&vstate);
        qnav_avr_timer_start();
        qnav_vfh_step(&vfh, &vstate, &in, &out);
        c = qnav_avr_timer_stop() - overhead;
        sum += c;
        lo = c < lo ? c : lo;
        hi = c > hi ? c : hi;
        ++n;
    }
    PUT("VFH+ (default config) on the ");
    qnav_target_put_u32(n);
    PUT(" 32-sector scans: mean ");
    qnav_avr_put_cycles(sum / n);
    PUT(", min ");
    qnav_target_put_u32(lo);
    PUT(", max ");
    qnav_target_put_u32(hi);
    PUT("; sizeof(qnav_vfh_t) + state ");
    qnav_target_put_u32(sizeof(qnav_vfh_t) + sizeof(qnav_vfh_state_t));
    PUT(" bytes\n");
}
#endif

int main(void)
{
    qnav_bench_hooks_t hooks;
    uint16_t bad;
    uint32_t c;
    uint8_t mode;

    if (qnav_avr_flash_data_too_far()) {
        qnav_target_exit(1u);
    }
    qnav_avr_timer_start();
    overhead = qnav_avr_timer_stop();
    PUT("qnav AVR benchmark: ATmega128, 16 MHz, simavr; image ");
    qnav_target_put_u32(QNAV_BENCH_TABLE_GROUP);
    if (QNAV_BENCH_TABLE_GROUP) {
        PUT(" (table group)\n");
    } else {
        PUT(" (network modes)\n");
    }
    PUT("timer overhead subtracted: ");
    qnav_target_put_u32(overhead);
    PUT(" cycles\n");
    qnav_avr_timer_start();
    _delay_loop_2(50000u); /* 4 cycles per count: 200000 */
    c = qnav_avr_timer_stop() - overhead;
    PUT("check: _delay_loop_2(50000), 200000 cycles by the datasheet, measured ");
    qnav_target_put_u32(c);
    PUT("\n");

    hooks.target = "avr";
    hooks.sep = '~';
    hooks.measure = measure;
    hooks.has_value = 1;
#if QNAV_BENCH_TABLE_GROUP
    hooks.modes = QNAV_BENCH_MODE_BIT(QNAV_BENCH_TABLE);
    hooks.table = flash_table;
#else
    hooks.modes = (uint8_t)(QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK) |
                            QNAV_BENCH_MODE_BIT(QNAV_BENCH_PROB) |
                            QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK3));
    hooks.table = 0;
#endif
    bad = qnav_bench_grid(&hooks);

    for (mode = 0; mode < QNAV_BENCH_MODES; ++mode) {
        if (steps[mode] == 0u) {
            continue;
        }
        PUT("peak step stack, ");
        qnav_target_put(qnav_bench_mode_name(mode));
        PUT(" (");
        qnav_target_put_u32(steps[mode]);
        PUT(" steps): ");
        qnav_target_put_u32(peak_stack[mode]);
        PUT(" bytes; sizeof(qnav_ctrl_t) ");
        qnav_target_put_u32(sizeof(qnav_ctrl_t));
        PUT(" bytes; controller RAM = sizeof + peak stack = ");
        qnav_target_put_u32(sizeof(qnav_ctrl_t) + peak_stack[mode]);
        PUT(" bytes (table in flash)\n");
    }
#if !QNAV_BENCH_TABLE_GROUP
    init_times();
    naive_comparison();
    vfh_comparison();
    escape_cost();
    keep_cost();
#endif
    if (bad != 0u) {
        PUT("MISMATCH count ");
        qnav_target_put_u32(bad);
        PUT("\n");
    }
    qnav_target_exit(bad ? 1u : 0u);
    return 0;
}
