/*
 * Unit tests of the controller: configuration checks, input quantization, path choice,
 * speed, saturation flags, agreement with the double-precision reference, and bit
 * identity of table mode with network and probabilistic mode.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>

#include "qnav/ctrl.h"
#include "qnav/fixed_host.h"
#include "reference.h"
#include "sigmoid_lut.h"
#include "test_rng.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Every weight of the network p already holds, drawn uniformly in [-max_raw, max_raw]. */
static void random_net_weights(qnav_policy_t *p, int32_t max_raw)
{
    for (uint16_t k = 0; k < qnav_net_weight_count(&p->u.net); ++k) {
        *qnav_net_weight(&p->u.net, k) = (qnav_q8_8_t)rng_range(-max_raw, max_raw);
    }
}

static void random_net(qnav_policy_t *p, uint8_t hidden, int32_t max_raw)
{
    qnav_policy_net_zero(p, hidden);
    random_net_weights(p, max_raw);
}

static void random_scan(qnav_mm_t *ranges, uint16_t n, qnav_mm_t max_mm)
{
    for (uint16_t s = 0; s < n; ++s) {
        /* a third of the sectors see nothing (max range or beyond), the rest an obstacle */
        uint32_t pick = rng_u32() % 3u;
        ranges[s] = pick == 0u ? (qnav_mm_t)(max_mm + rng_range(0, 500))
                               : (qnav_mm_t)rng_range(0, max_mm);
    }
}

static void init_or_fail(qnav_ctrl_t *c, uint16_t sectors, qnav_mm_t max_mm, const qnav_policy_t *p)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = sectors;
    cfg.max_range_mm = max_mm;
    assert_int_equal(qnav_ctrl_init(c, &cfg, p), QNAV_OK);
}

/* The paper read literally: a path sees its own sector, no speed guard, rank by quality. */
static void init_literal(qnav_ctrl_t *c, uint16_t sectors, qnav_mm_t max_mm, const qnav_policy_t *p)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = sectors;
    cfg.max_range_mm = max_mm;
    qnav_ctrl_config_literal(&cfg);
    assert_int_equal(cfg.body_radius_mm, 0);
    assert_int_equal(cfg.rank, QNAV_RANK_QUALITY);
    assert_int_equal(qnav_ctrl_init(c, &cfg, p), QNAV_OK);
}

static void fill(qnav_mm_t *ranges, uint16_t n, qnav_mm_t v)
{
    for (uint16_t s = 0; s < n; ++s) {
        ranges[s] = v;
    }
}

/* --- configuration --- */

static void test_init_rejects_bad_configuration(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_policy_prob_default(&p);

    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_SECTORS);
    cfg.n_sectors = 361;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_SECTORS);

    qnav_ctrl_config_default(&cfg);
    cfg.max_range_mm = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_RANGE);
    cfg.max_range_mm = 5000;
    cfg.range_min_mm = 5000; /* the minimum range must lie below the maximum */
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_RANGE);
    cfg.range_min_mm = 4999;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);

    qnav_ctrl_config_default(&cfg);
    cfg.full_speed_quality = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_SPEED);

    qnav_ctrl_config_default(&cfg);
    assert_int_equal(qnav_ctrl_init(NULL, &cfg, &p), QNAV_E_NULL);
    assert_int_equal(qnav_ctrl_init(&c, NULL, &p), QNAV_E_NULL);
    assert_int_equal(qnav_ctrl_init(&c, &cfg, NULL), QNAV_E_NULL);
    assert_int_equal(qnav_ctrl_init_table(&c, &cfg, NULL, QNAV_RANK_PREACT), QNAV_E_NULL);
    qnav_ctrl_config_default(&cfg);
    cfg.rank = 7;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_RANK);
    qnav_ctrl_config_default(&cfg);
    cfg.keep_pct = 101;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_KEEP);
}

static void test_init_rejects_bad_policies(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_config_default(&cfg);

    memset(&p, 0, sizeof p);
    p.kind = 7;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_POLICY_KIND);

    qnav_policy_net_zero(&p, 4);
    p.u.net.hidden = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_HIDDEN);
    p.u.net.hidden = QNAV_MAX_HIDDEN + 1;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_HIDDEN);

    qnav_policy_prob_default(&p);
    p.u.prob.k_goal = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_PROB_PARAM);
    qnav_policy_prob_default(&p);
    p.u.prob.k_safe = 64 * 256 + 1;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_PROB_PARAM);
    p.u.prob.k_safe = 64 * 256;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
}

static void test_failed_init_leaves_controller_commanding_stop(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_output_t out;
    qnav_q1_15_t q[QNAV_PATHS];
    qnav_mm_t ranges[16];
    qnav_ctrl_input_t in = {ranges, 0};

    qnav_policy_prob_default(&p);
    qnav_ctrl_config_default(&cfg);
    fill(ranges, 16, 5000);
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    cfg.n_sectors = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_SECTORS);

    memset(q, 0x55, sizeof q);
    qnav_ctrl_step(&c, &in, &out, q);
    assert_int_equal(out.speed, 0);
    assert_int_equal(out.heading_deg, 0);
    assert_int_equal(out.flags, QNAV_FLAG_NOT_READY);
    assert_int_equal(q[123], 0);
}

static void test_step_with_null_ranges_commands_stop(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_ctrl_output_t out;
    qnav_ctrl_input_t in = {NULL, 0};
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 16, 5000, &p);
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.speed, 0);
    assert_true(out.flags & QNAV_FLAG_NOT_READY);
}

/* --- input quantization --- */

static void test_sector_of_path_centres_sector_zero_straight_ahead(void **state)
{
    (void)state;
    /* 4 sectors of 90 deg: sector 0 covers [-45, 45), sector 1 [45, 135), ... */
    assert_int_equal(qnav_ctrl_sector_of_path(4, 0), 0);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 44), 0);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 45), 1);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 134), 1);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 135), 2);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 314), 3);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 315), 0);
    assert_int_equal(qnav_ctrl_sector_of_path(4, 359), 0);
    assert_int_equal(qnav_ctrl_sector_of_path(1, 200), 0);
    assert_int_equal(qnav_ctrl_sector_of_path(360, 200), 200);
    /* 7 sectors do not divide 360: still every path in exactly one sector, in order */
    for (uint16_t i = 1; i < 360; ++i) {
        uint16_t a = qnav_ctrl_sector_of_path(7, (uint16_t)(i - 1));
        uint16_t b = qnav_ctrl_sector_of_path(7, i);
        assert_true(b == a || b == (a + 1) % 7);
    }
}

static void test_level_maps_zero_and_max_range_to_the_ends(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 16, 3000, &p);
    assert_int_equal(qnav_ctrl_level(&c, 0), 0);
    assert_int_equal(qnav_ctrl_level(&c, 3000), QNAV_DIST_LEVELS - 1);
    assert_int_equal(qnav_ctrl_level(&c, 65535), QNAV_DIST_LEVELS - 1);
    /* half range: level (L-1)/2, whichever way its half is rounded */
    assert_in_range(qnav_ctrl_level(&c, 1500), (QNAV_DIST_LEVELS - 1) / 2, QNAV_DIST_LEVELS / 2);
    /* monotone in range */
    for (uint16_t r = 1; r <= 3000; ++r) {
        assert_true(qnav_ctrl_level(&c, r) >= qnav_ctrl_level(&c, (qnav_mm_t)(r - 1)));
    }
}

/* --- decisions --- */

static void test_ctrl_drives_at_goal_in_open_space(void **state)
{
    (void)state;
    static const qnav_cdeg_t bearings[] = {0, 4500, -9000, 17999, -17999, 32767, -30000, 1249};
    static const qnav_deg_t expect[] = {0, 45, -90, 180, 180, -32, 60, 12};
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[32];
    qnav_ctrl_output_t out;
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 32, 5000, &p);
    fill(ranges, 32, 5000);
    for (size_t k = 0; k < sizeof bearings / sizeof bearings[0]; ++k) {
        qnav_ctrl_input_t in = {ranges, bearings[k]};
        qnav_ctrl_step(&c, &in, &out, NULL);
        assert_int_equal(out.heading_deg, expect[k]);
        assert_int_equal(out.speed, QNAV_Q1_15_MAX);
        assert_true(out.flags & QNAV_FLAG_FULL_SPEED);
        assert_false(out.flags & QNAV_FLAG_RANGE_CLIPPED);
    }
}

static void test_ctrl_turns_away_from_near_obstacle(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t out;
    qnav_policy_prob_default(&p);
    init_literal(&c, 16, 5000, &p);
    fill(ranges, 16, 5000);
    ranges[0] = 150; /* wall straight ahead, goal straight ahead */
    qnav_ctrl_input_t in = {ranges, 0};
    qnav_ctrl_step(&c, &in, &out, NULL);
    /* sector 0 spans [-11.25, 11.25): the best path is the first one outside it */
    assert_true(out.heading_deg == 12 || out.heading_deg == -12);
    assert_int_equal(out.heading_deg, 12); /* tie goes counter-clockwise */
    assert_true(out.speed > 0);
}

/* --- holding the heading (keep_pct) --- */

static void init_keep(qnav_ctrl_t *c, uint8_t keep, uint8_t rank, const qnav_policy_t *p)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    qnav_ctrl_config_literal(&cfg);
    cfg.n_sectors = 16;
    cfg.max_range_mm = 5000;
    cfg.keep_pct = keep;
    cfg.rank = rank;
    assert_int_equal(qnav_ctrl_init(c, &cfg, p), QNAV_OK);
}

static qnav_deg_t heading_with_prev(const qnav_ctrl_t *c, const qnav_mm_t *ranges,
                                    qnav_cdeg_t prev_cdeg)
{
    qnav_ctrl_output_t out;
    qnav_ctrl_input_t in = {ranges, 0};
    in.prev_heading_cdeg = prev_cdeg;
    qnav_ctrl_step(c, &in, &out, NULL);
    return out.heading_deg;
}

/* The decision h is the turn that keeps the way round of the last decision prev. */
static int kept_turn(int prev, qnav_deg_t h)
{
    return (h == 179 && prev > 0) || (h == -179 && prev < 0);
}

/* A decision more than 90 degrees off straight ahead, on the other side from the last one,
 * with the shorter way between the two behind the robot, turns the same way round as the
 * last one: a robot turning in place toward a way behind it is not sent left and right on
 * alternate ticks (escape.h, qnav_escape_hold_turn). */
static void test_a_turn_keeps_its_way_round(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t out;
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 16, 5000, &p);
    fill(ranges, 16, 5000);
    for (int side = -1; side <= 1; side += 2) {
        qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)(-side * 15000)};
        const int expect[][2] = {
            {0, -side * 150},           /* the first tick: the destination's way */
            {-side * 120, -side * 150}, /* the last turn went that way round too */
            {side * 20, -side * 150},   /* the shorter way from the last passes in front */
            {side * 30, -side * 150},   /* 180 either way round: not held */
            {side * 31, side * 179},    /* the shorter way passes behind, by a degree */
            {side * 120, side * 179},   /* behind: keep turning the last way round */
            {side * 179, side * 179},
        };
        for (size_t k = 0; k < sizeof expect / sizeof expect[0]; ++k) {
            in.prev_heading_cdeg = (qnav_cdeg_t)(expect[k][0] * 100);
            qnav_ctrl_step(&c, &in, &out, NULL);
            assert_int_equal(out.heading_deg, expect[k][1]);
        }
    }
}

static void test_holding_keeps_the_previous_of_two_equal_ways(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_policy_prob_default(&p);
    fill(ranges, 16, 5000);
    ranges[0] = 150; /* wall straight ahead, goal straight ahead: 12 and -12 are equal */
    init_keep(&c, 0, QNAV_RANK_QUALITY, &p);
    assert_int_equal(heading_with_prev(&c, ranges, -1200), 12); /* off: the tie-break */
    init_keep(&c, 15, QNAV_RANK_QUALITY, &p);
    assert_int_equal(heading_with_prev(&c, ranges, -1200), -12); /* held */
    assert_int_equal(heading_with_prev(&c, ranges, 1200), 12);
    /* the previous heading into the wall is no way: not held */
    assert_int_equal(heading_with_prev(&c, ranges, 0), 12);
    /* one far off the goal is worse by more than the margin: not held, held with a wide one */
    assert_int_equal(heading_with_prev(&c, ranges, -9000), 12);
    init_keep(&c, 100, QNAV_RANK_QUALITY, &p);
    assert_int_equal(heading_with_prev(&c, ranges, -9000), -90);
}

/* Pre-activation keys (a 2-input network) are held in z: the previous heading's path
 * replaces the best when its key is at most keep_pct hundredths of z (keep_pct * 2048 / 100
 * key steps) below the best's and above 0; a 3-input network is never held. */
static void test_holding_preactivation_keys_within_a_margin_of_z(void **state)
{
    (void)state;
    qnav_ctrl_t off;
    qnav_ctrl_t on;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    uint8_t lvl[QNAV_PATHS];
    int held = 0;
    int not_held = 0;
    for (int k = 0; k < 400; ++k) {
        random_net(&p, 12, 1024);
        random_scan(ranges, 16, 5000);
        init_keep(&off, 0, QNAV_RANK_PREACT, &p);
        init_keep(&on, 15, QNAV_RANK_PREACT, &p);
        int prev = (int)rng_range(-179, 180);
        qnav_deg_t h_off = heading_with_prev(&off, ranges, (qnav_cdeg_t)(prev * 100));
        qnav_deg_t h_on = heading_with_prev(&on, ranges, (qnav_cdeg_t)(prev * 100));
        if (kept_turn(prev, h_off) || kept_turn(prev, h_on)) {
            continue; /* a turn kept its way round (its own test below): no path's key */
        }
        (void)qnav_ctrl_path_levels(&on, ranges, lvl);
        qnav_qkey_t kp = qnav_ctrl_key(&on, lvl[(prev + 360) % 360], (uint8_t)(prev < 0 ? -prev : prev));
        qnav_qkey_t kb = qnav_ctrl_key(&on, lvl[(h_off + 360) % 360], (uint8_t)(h_off < 0 ? -h_off : h_off));
        if (kp > 0 && (int32_t)kp >= (int32_t)kb - 15 * 2048 / 100) {
            assert_int_equal(h_on, prev);
            held += h_on != h_off;
        } else {
            assert_int_equal(h_on, h_off);
            ++not_held;
        }
        qnav_policy_net_zero_inputs(&p, 12, QNAV_NET_INPUTS_PREV);
        random_net_weights(&p, 1024);
        init_keep(&off, 0, QNAV_RANK_PREACT, &p);
        init_keep(&on, 100, QNAV_RANK_PREACT, &p);
        assert_int_equal(heading_with_prev(&on, ranges, (qnav_cdeg_t)(prev * 100)),
                         heading_with_prev(&off, ranges, (qnav_cdeg_t)(prev * 100)));
    }
    print_message("held %d of 400 (a heading other than the best's), not held %d\n", held, not_held);
    assert_true(held > 20);
    assert_true(not_held > 20);
}

static void test_ctrl_prefers_goal_over_far_obstacle(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t out;
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 16, 5000, &p);
    fill(ranges, 16, 5000);
    ranges[2] = 4000; /* something far off in the goal's direction */
    qnav_ctrl_input_t in = {ranges, 4500};
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.heading_deg, 45);
}

/* The destination in reach (docs/architecture.md): a wall just beyond the destination
 * does not block the way to it, one nearer than the destination plus the body's margin
 * does, and an unknown distance (0) changes nothing. */
static void test_a_wall_beyond_the_destination_does_not_block_the_way_to_it(void **state)
{
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_ctrl_config_t cfg;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t unknown, reach, short_of;
    qnav_q1_15_t q_unknown[QNAV_PATHS], q_reach[QNAV_PATHS], q_short[QNAV_PATHS];
    (void)state;
    qnav_policy_prob_default(&p);
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 16;
    cfg.max_range_mm = 2500;
    cfg.body_radius_mm = 120;
    cfg.safety_mm = 50; /* margin 170 mm */
    cfg.sensor_offset_mm = 0;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    fill(ranges, 16, 2500);
    ranges[15] = ranges[0] = ranges[1] = 900; /* a wall across the way, 0.9 m ahead */
    {
        qnav_ctrl_input_t in = {ranges, 0};
        qnav_ctrl_step(&c, &in, &unknown, q_unknown);
        in.goal_range_mm = 600; /* 0.3 m short of the wall: 900 >= 600 + 170 */
        qnav_ctrl_step(&c, &in, &reach, q_reach);
        in.goal_range_mm = 800; /* 900 < 800 + 170: the body would touch it first */
        qnav_ctrl_step(&c, &in, &short_of, q_short);
    }
    print_message("path 0: quality %d without a distance, %d with the destination in reach\n",
                  q_unknown[0], q_reach[0]);
    assert_true(q_reach[0] > q_unknown[0]);
    assert_int_equal(reach.heading_deg, 0);
    assert_true(reach.speed > 0);
    assert_memory_equal(q_short, q_unknown, sizeof q_unknown);
    assert_int_equal(short_of.heading_deg, unknown.heading_deg);

}

static void test_speed_is_linear_in_quality_up_to_full(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[1] = {5000};
    qnav_ctrl_output_t out;
    qnav_ctrl_input_t in = {ranges, 0};
    /* a network whose quality is the constant sigmoid(b_out): pick b_out = 0 -> 0.5 */
    qnav_policy_net_zero(&p, 1);
    init_or_fail(&c, 1, 5000, &p);
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.quality, 16384);
    /* F(0.5) = 0.5 / 0.9 = 0.5556 */
    assert_in_range(out.speed, 18200, 18206);
    assert_false(out.flags & QNAV_FLAG_FULL_SPEED);
}

/* One clear scan's output with this rank and quality_full_speed, in policy (compiled: table)
 * mode. The network's quality is the constant sigmoid(0) = 0.5 on every path. */
static qnav_ctrl_output_t constant_half_step(uint8_t rank, qnav_q1_15_t quality_full_speed, int compiled)
{
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_mm_t ranges[1] = {5000};
    qnav_ctrl_input_t in = {ranges, 0};
    qnav_ctrl_output_t out;
    qnav_policy_net_zero(&p, 1);
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 1;
    cfg.rank = rank;
    cfg.quality_full_speed = quality_full_speed;
    assert_int_equal(compiled ? qnav_ctrl_init_compiled(&c, &cfg, &p, table) : qnav_ctrl_init(&c, &cfg, &p),
                     QNAV_OK);
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.quality, 16384);
    return out;
}

/* Keys ranked by quality (the probabilistic policy's, always) reach full speed at their own
 * quality_full_speed when it is set, in policy and table mode alike; pre-activation keys
 * keep full_speed_quality; a negative value is refused. */
static void test_quality_ranked_keys_reach_full_speed_at_their_own_quality(void **state)
{
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t at_own, at_drive;
    qnav_ctrl_input_t in = {ranges, 4500};
    int compiled;
    (void)state;
    for (compiled = 0; compiled <= 1; ++compiled) {
        qnav_ctrl_output_t o = constant_half_step(QNAV_RANK_QUALITY, 16384, compiled);
        assert_int_equal(o.speed, QNAV_Q1_15_MAX); /* 0.5 >= 0.5: full */
        assert_true(o.flags & QNAV_FLAG_FULL_SPEED);
        o = constant_half_step(QNAV_RANK_QUALITY, 0, compiled);
        assert_in_range(o.speed, 18200, 18206); /* 0.5 / 0.9, as before */
        o = constant_half_step(QNAV_RANK_PREACT, 16384, compiled);
        assert_in_range(o.speed, 18200, 18206); /* not this rank's value */
        o = constant_half_step(QNAV_RANK_QUALITY, 29491, compiled);
        assert_in_range(o.speed, 18200, 18206); /* the same value as full_speed_quality */
    }
    /* the probabilistic policy ranks by quality whatever cfg.rank says */
    qnav_policy_prob_default(&p);
    qnav_ctrl_config_default(&cfg);
    cfg.rank = (uint8_t)QNAV_RANK_PREACT;
    fill(ranges, 16, 600);
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    qnav_ctrl_step(&c, &in, &at_drive, NULL);
    print_message("probabilistic policy: quality %d, speed %d at 0.9\n", at_drive.quality, at_drive.speed);
    cfg.quality_full_speed = 16384;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    qnav_ctrl_step(&c, &in, &at_own, NULL);
    assert_int_equal(at_own.heading_deg, at_drive.heading_deg);
    assert_int_equal(at_own.quality, at_drive.quality);
    assert_true(at_own.quality < 16384);
    /* quality / 0.5 against quality / 0.9: 1.8 times as fast, to a count's rounding */
    assert_in_range((int32_t)at_own.speed * 10, (int32_t)at_drive.speed * 18 - 40,
                    (int32_t)at_drive.speed * 18 + 40);
    cfg.quality_full_speed = -1;
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_SPEED);
}

static void test_equal_qualities_choose_the_goal_direction(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[8];
    qnav_ctrl_output_t out;
    qnav_q1_15_t q[QNAV_PATHS];
    qnav_policy_net_zero(&p, 3); /* 0.5 on every path */
    init_or_fail(&c, 8, 2000, &p);
    fill(ranges, 8, 100);
    for (int16_t b = -179; b <= 180; b += 7) {
        qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)(b * 100)};
        qnav_ctrl_step(&c, &in, &out, q);
        assert_int_equal(out.heading_deg, b);
        assert_int_equal(q[0], q[359]);
    }
}

static void test_ranges_beyond_max_are_clipped_and_flagged(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t a[8];
    qnav_mm_t b[8];
    qnav_ctrl_output_t oa;
    qnav_ctrl_output_t ob;
    qnav_q1_15_t qa[QNAV_PATHS];
    qnav_q1_15_t qb[QNAV_PATHS];
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 8, 2000, &p);
    fill(a, 8, 2000);
    fill(b, 8, 2000);
    b[3] = 65535;
    qnav_ctrl_input_t ia = {a, 3000};
    qnav_ctrl_input_t ib = {b, 3000};
    qnav_ctrl_step(&c, &ia, &oa, qa);
    qnav_ctrl_step(&c, &ib, &ob, qb);
    assert_false(oa.flags & QNAV_FLAG_RANGE_CLIPPED);
    assert_true(ob.flags & QNAV_FLAG_RANGE_CLIPPED);
    assert_memory_equal(qa, qb, sizeof qa);
    assert_int_equal(oa.heading_deg, ob.heading_deg);
}

static void test_all_zero_quality_stops_and_flags(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_policy_t p;
    qnav_mm_t ranges[4];
    qnav_ctrl_output_t out;
    qnav_policy_prob_default(&p);
    init_or_fail(&c, 4, 1000, &p);
    fill(ranges, 4, 0); /* touching everywhere: P_safe = 0 */
    qnav_ctrl_input_t in = {ranges, 0};
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.speed, 0);
    assert_true(out.flags & QNAV_FLAG_NO_PATH);
}

/* --- agreement with the reference --- */

static void check_quality_bound(const qnav_policy_t *p, double *worst_ratio)
{
    qnav_ctrl_t c;
    init_or_fail(&c, 16, 5000, p);
    double bound = ref_quality_bound(p);
    for (unsigned level = 0; level < QNAV_DIST_LEVELS; ++level) {
        for (unsigned dt = 0; dt <= 180; ++dt) {
            double fx = qnav_ctrl_quality(&c, (uint8_t)level, (uint8_t)dt) / 32768.0;
            double err = fabs(fx - ref_quality(p, level, dt));
            if (err / bound > *worst_ratio) {
                *worst_ratio = err / bound;
            }
            if (err > bound) {
                fail_msg("level %u dtheta %u: error %.6f exceeds bound %.6f", level, dt, err, bound);
            }
        }
    }
}

static void test_qualities_are_within_bound_of_double_reference(void **state)
{
    (void)state;
    double worst = 0.0;
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    check_quality_bound(&p, &worst);
    for (int k = 1; k <= 40; ++k) {
        p.u.prob.k_goal = (qnav_q8_8_t)rng_range(1, 64 * 256);
        p.u.prob.k_safe = (qnav_q8_8_t)rng_range(1, 64 * 256);
        check_quality_bound(&p, &worst);
    }
    static const int32_t scales[] = {256, 1024, 4096, 32767};
    for (size_t s = 0; s < 4; ++s) {
        for (int k = 0; k < 25; ++k) {
            random_net(&p, (uint8_t)rng_range(1, QNAV_MAX_HIDDEN), scales[s]);
            check_quality_bound(&p, &worst);
        }
    }
    print_message("worst error / bound = %.3f\n", worst);
}

/* Reference argmax with the controller's tie rule applied to exact double ties. */
static unsigned ref_argmax(const double q[QNAV_PATHS], unsigned goal)
{
    unsigned best = 0;
    for (unsigned i = 1; i < QNAV_PATHS; ++i) {
        int h = i <= 180 ? (int)i : (int)i - 360;
        int hb = best <= 180 ? (int)best : (int)best - 360;
        if (q[i] != q[best]) {
            if (q[i] > q[best]) best = i;
        } else if (ref_dtheta(i, goal) != ref_dtheta(best, goal)) {
            if (ref_dtheta(i, goal) < ref_dtheta(best, goal)) best = i;
        } else if (abs(h) != abs(hb)) {
            if (abs(h) < abs(hb)) best = i;
        } else if (h > hb) {
            best = i;
        }
    }
    return best;
}

/* A scan is a near tie when some path whose reference quality differs from the best's
 * comes within 4 LSB of Q1.15 (2^-13) of it: below the controller's output resolution
 * (and at the ends of [0, 1], where Q1.15 saturates) fixed point may rank them either way. */
#define NEAR_TIE (1.0 / 8192.0)
static int is_near_tie(const double ref[QNAV_PATHS], unsigned best, double near)
{
    for (unsigned i = 0; i < QNAV_PATHS; ++i) {
        if (ref[i] != ref[best] && ref[i] >= ref[best] - near) {
            return 1;
        }
    }
    return 0;
}

static void test_argmax_matches_reference_on_random_scans(void **state)
{
    (void)state;
    enum { SCANS = 4000 };
    static const uint16_t sectors[] = {8, 16, 32, 180};
    unsigned clear = 0, clear_same = 0, tie_same = 0, outside_bound = 0;
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_mm_t ranges[180];
    double ref[QNAV_PATHS];
    qnav_ctrl_output_t out;
    for (unsigned k = 0; k < SCANS; ++k) {
        uint16_t n = sectors[k % 4];
        if (k % 4 == 1) {
            qnav_policy_prob_default(&p);
        } else {
            random_net(&p, 12, 768);
        }
        init_or_fail(&c, n, 4000, &p);
        random_scan(ranges, n, 4000);
        qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)rng_range(-18000, 18000)};
        qnav_ctrl_step(&c, &in, &out, NULL);
        ref_path_qualities(&c, &p, &in, ref);
        /* networks rank by the pre-activation y: its bound, and the key's 1/128 steps
         * beyond |y| = 8; the probabilistic policy by its quality */
        int net = ref_is_network(&p);
        double bound = net ? ref_preact_bound(&p) : ref_quality_bound(&p);
        double near = net ? 2.0 * bound + 1.0 / 128.0 : NEAR_TIE;
        unsigned rbest = ref_argmax(ref, ref_goal_deg(in.goal_bearing_cdeg));
        unsigned fbest = (unsigned)((out.heading_deg + 360) % 360);
        if (out.flags & QNAV_FLAG_NO_PATH) {
            continue; /* every quality rounds to 0: a stop, whatever the order */
        }
        if (ref[fbest] < ref[rbest] - 2.0 * bound - (net ? 1.0 / 128.0 : 0.0)) {
            ++outside_bound;

        }
        if (is_near_tie(ref, rbest, near)) {
            tie_same += (fbest == rbest);
        } else {
            ++clear;
            clear_same += (fbest == rbest);
        }
    }
    print_message("argmax: %u of %u clear scans agree; %u of %u near ties agree\n", clear_same,
                  clear, tie_same, SCANS - clear);
    assert_int_equal(outside_bound, 0);
    assert_true(clear * 4u >= SCANS); /* the test must not be vacuous */
    assert_true(clear_same * 100u >= clear * 99u);
}

static void test_zero_margin_reads_each_path_from_its_own_sector(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_mm_t ranges[QNAV_MAX_SECTORS];
    qnav_q1_15_t q[QNAV_PATHS];
    qnav_ctrl_output_t out;
    random_net(&p, 6, 1024);
    for (uint16_t n = 1; n <= QNAV_MAX_SECTORS; n = (uint16_t)(n < 40 ? n + 1 : n + 23)) {
        init_literal(&c, n, 3000, &p);
        for (int k = 0; k < 3; ++k) {
            random_scan(ranges, n, 3000);
            qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)rng_range(-18000, 18000)};
            unsigned goal = ref_goal_deg(in.goal_bearing_cdeg);
            qnav_ctrl_step(&c, &in, &out, q);
            for (uint16_t i = 0; i < QNAV_PATHS; ++i) {
                uint8_t level = qnav_ctrl_level(&c, ranges[qnav_ctrl_sector_of_path(n, i)]);
                uint8_t dt = (uint8_t)ref_dtheta(i, goal);
                if (q[i] != qnav_ctrl_quality(&c, level, dt)) {
                    fail_msg("N %u path %u: quality %d, expected %d", n, i, q[i],
                             qnav_ctrl_quality(&c, level, dt));
                }
            }
        }
    }
}

/* --- clearance: enlargement and speed guard --- */

static void init_body(qnav_ctrl_t *c, uint16_t sectors, qnav_mm_t max_mm, qnav_mm_t radius,
                      qnav_mm_t safety, uint16_t decel, const qnav_policy_t *p)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = sectors;
    cfg.max_range_mm = max_mm;
    cfg.body_radius_mm = radius;
    cfg.safety_mm = safety;
    cfg.decel_mm_s2 = decel;
    assert_int_equal(qnav_ctrl_init(c, &cfg, p), QNAV_OK);
}

/* Smallest range (mm) that reads as level under c: what the enlargement assumes. */
static unsigned level_floor(const qnav_ctrl_t *c, unsigned level)
{
    unsigned r = 0;
    while (qnav_ctrl_level(c, (qnav_mm_t)r) < level) {
        ++r;
    }
    return r;
}

static void test_enlargement_blocks_paths_beside_a_near_obstacle(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_mm_t ranges[360];
    uint8_t lvl[QNAV_PATHS];
    qnav_policy_prob_default(&p);
    init_body(&c, 360, 3000, 120, 50, 0, &p);
    fill(ranges, 360, 3000);
    ranges[0] = 500; /* one 1-degree reading straight ahead, 0.5 m from the sonar (0.62 m from the centre) */
    assert_int_equal(qnav_ctrl_path_levels(&c, ranges, lvl), 0);
    uint8_t near = qnav_ctrl_level(&c, 500);
    /* the body (0.17 m with the margin) hits it on every path within asin(0.17 / D) */
    /* D from the centre: the reading itself (not its level's floor) plus the default
     * sensor offset (the body's rim, 120) */
    double gamma = asin(170.0 / (500.0 + 120.0)) * 180.0 / M_PI;
    for (unsigned i = 0; i < QNAV_PATHS; ++i) {
        unsigned off = i <= 180 ? i : 360 - i;
        if (off + 1e-9 < gamma) {
            if (lvl[i] != near) fail_msg("path %u (%.1f deg inside gamma %.2f) not blocked", i, (double)off, gamma);
        } else if (off > gamma + 1.0) {
            if (lvl[i] != QNAV_DIST_LEVELS - 1) fail_msg("path %u beyond gamma %.2f is blocked", i, gamma);
        }
    }
    /* and the policy steers past the enlarged obstacle, not along its edge at 1 degree */
    qnav_ctrl_input_t in = {ranges, 0};
    qnav_ctrl_output_t out;
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_true(abs(out.heading_deg) >= (int)gamma);
    qnav_ctrl_t lit;
    init_literal(&lit, 360, 3000, &p);
    qnav_ctrl_step(&lit, &in, &out, NULL);
    assert_int_equal(abs(out.heading_deg), 1);
}

static void test_enlargement_matches_asin_at_every_level(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_ctrl_t c;
    qnav_mm_t ranges[360];
    uint8_t lvl[QNAV_PATHS];
    qnav_policy_prob_default(&p);
    init_body(&c, 360, 2500, 120, 50, 0, &p);
    for (unsigned level = 0; level + 1 < QNAV_DIST_LEVELS; ++level) {
        /* the level's nearest and farthest readings: each is enlarged by its own distance */
        unsigned ends[2] = {level_floor(&c, level), level_floor(&c, level + 1u) - 1u};
        for (unsigned e = 0; e < 2u; ++e) {
            unsigned d = ends[e];
            double ratio = 170.0 / (d + 120.0);
            double g = ratio >= 1.0 ? 90.0 : asin(ratio) * 180.0 / M_PI;
            unsigned blocked = 0;
            fill(ranges, 360, 2500);
            ranges[0] = (qnav_mm_t)d;
            qnav_ctrl_path_levels(&c, ranges, lvl);
            for (unsigned i = 0; i < QNAV_PATHS; ++i) {
                blocked += lvl[i] == level;
            }
            /* whole degrees: gamma is the smallest g with sin g >= (r + d_s) / D */
            unsigned expect = 1u + 2u * (unsigned)ceil(g - 1e-6);
            if (blocked != expect && fabs(g - round(g)) > 0.01) {
                fail_msg("level %u (D %u mm): %u paths blocked, expected %u (gamma %.3f)", level,
                         d, blocked, expect, g);
            }
        }
    }
}

static void test_enlargement_lowers_collisions_with_sector_count_not_raises(void **state)
{
    /* the robot must see a near obstacle 25 degrees beside its path whatever N is: 0.25 m
     * from the sonar is 0.37 m from the centre and 0.156 m beside the straight path, within
     * the body's 0.17 m (radius + safety distance) */
    (void)state;
    static const uint16_t sectors[] = {8, 16, 32, 64, 180, 360};
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    for (size_t s = 0; s < sizeof sectors / sizeof sectors[0]; ++s) {
        uint16_t n = sectors[s];
        qnav_ctrl_t c;
        qnav_mm_t ranges[360];
        uint8_t lvl[QNAV_PATHS];
        init_body(&c, n, 2500, 120, 50, 0, &p);
        fill(ranges, n, 2500);
        ranges[qnav_ctrl_sector_of_path(n, 25)] = 250; /* 0.25 m away at 25 degrees */
        qnav_ctrl_path_levels(&c, ranges, lvl);
        assert_int_equal(lvl[25], qnav_ctrl_level(&c, 250));
        /* gamma(0.25 m + 0.12 m) = 28 degrees (+ the wedge): the straight path is blocked too */
        assert_int_equal(lvl[0], qnav_ctrl_level(&c, 250));
        if (n == 360) {
            /* a 1-degree reading is a point: 4 degrees the other way the body passes it */
            assert_int_equal(lvl[356], QNAV_DIST_LEVELS - 1);
        }
    }
}

static void test_speed_guard_caps_speed_to_stop_within_clearance(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_ctrl_t guarded;
    qnav_ctrl_t free_run;
    qnav_mm_t ranges[1];
    qnav_ctrl_output_t og;
    qnav_ctrl_output_t of;
    qnav_policy_net_zero(&p, 1);
    p.u.net.b_out = QNAV_Q8_8(4.0); /* quality 0.98 everywhere: full speed unguarded */
    init_body(&guarded, 1, 2500, 120, 50, 2000, &p);
    init_body(&free_run, 1, 2500, 120, 50, 0, &p);
    for (qnav_mm_t r = 100; r <= 2500; r = (qnav_mm_t)(r + 100)) {
        ranges[0] = r;
        qnav_ctrl_input_t in = {ranges, 0};
        qnav_ctrl_step(&guarded, &in, &og, NULL);
        qnav_ctrl_step(&free_run, &in, &of, NULL);
        assert_int_equal(of.speed, QNAV_Q1_15_MAX);
        assert_false(of.flags & QNAV_FLAG_SPEED_GUARD);
        /* v T + v^2 / (2 a) within the clearance D - r - d_s, D the level's nearest range */
        double s_mm = (double)level_floor(&guarded, qnav_ctrl_level(&guarded, r)) + 120.0 - 170.0;
        double v = s_mm <= 0 ? 0 : -200.0 + sqrt(200.0 * 200.0 + 4000.0 * s_mm);
        double cap = v / 500.0 * 32768.0;
        if (cap < 32767.0 && qnav_ctrl_level(&guarded, r) + 1 < QNAV_DIST_LEVELS) {
            assert_true(og.flags & QNAV_FLAG_SPEED_GUARD);
            /* the integer square root works in whole mm/s: 1 mm/s is 66 LSB of 500 mm/s */
            assert_in_range(og.speed, (int)floor(cap) - 70 < 0 ? 0 : (int)floor(cap) - 70, (int)cap);
        } else {
            assert_int_equal(og.speed, QNAV_Q1_15_MAX);
        }
    }
}

/* A network whose quality is pinned at Q1.15's top on every path: the pre-activation still
 * prefers far obstacles, the quality cannot. */
static void saturated_net(qnav_policy_t *p)
{
    qnav_policy_net_zero(p, 1);
    p->u.net.w_dist[0] = QNAV_Q8_8(8.0);
    p->u.net.b_hidden[0] = QNAV_Q8_8(-4.0);
    p->u.net.w_out[0] = QNAV_Q8_8(20.0);
    p->u.net.b_out = QNAV_Q8_8(20.0);
}

static void test_saturated_network_ranks_by_preactivation(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_ctrl_t by_key;
    qnav_ctrl_t by_quality;
    qnav_ctrl_config_t cfg;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t ok;
    qnav_ctrl_output_t oq;
    saturated_net(&p);
    qnav_ctrl_config_default(&cfg);
    cfg.max_range_mm = 2500;
    assert_int_equal(qnav_ctrl_init(&by_key, &cfg, &p), QNAV_OK);
    cfg.rank = (uint8_t)QNAV_RANK_QUALITY;
    assert_int_equal(qnav_ctrl_init(&by_quality, &cfg, &p), QNAV_OK);
    /* every path saturated: quality 32767 at level 0 as at level 31 */
    assert_int_equal(qnav_ctrl_quality(&by_key, 0, 0), QNAV_Q1_15_MAX);
    assert_int_equal(qnav_ctrl_quality(&by_key, QNAV_DIST_LEVELS - 1, 0), QNAV_Q1_15_MAX);
    assert_true(qnav_ctrl_key(&by_key, QNAV_DIST_LEVELS - 1, 0) > qnav_ctrl_key(&by_key, 0, 0));
    fill(ranges, 16, 2500);
    ranges[0] = 600; /* an obstacle in the goal's direction */
    qnav_ctrl_input_t in = {ranges, 0};
    qnav_ctrl_step(&by_quality, &in, &oq, NULL);
    qnav_ctrl_step(&by_key, &in, &ok, NULL);
    assert_int_equal(oq.heading_deg, 0); /* the tie order drives at the obstacle */
    assert_true(abs(ok.heading_deg) > 11); /* the order of z leaves its sector */
    assert_int_equal(ok.quality, QNAV_Q1_15_MAX);
}

static void test_preactivation_rank_agrees_with_float_network_on_saturated_nets(void **state)
{
    (void)state;
    enum { SCANS = 600 };
    unsigned agree[2] = {0, 0};
    unsigned clear = 0;
    qnav_policy_t p;
    qnav_mm_t ranges[32];
    double y[QNAV_PATHS];
    for (unsigned k = 0; k < SCANS; ++k) {
        qnav_ctrl_t c[2];
        qnav_ctrl_config_t cfg;
        qnav_ctrl_output_t out;
        random_net(&p, 12, 20 * 256); /* weights up to +-20: most networks saturate */
        qnav_ctrl_config_default(&cfg);
        cfg.n_sectors = 32;
        cfg.max_range_mm = 4000;
        assert_int_equal(qnav_ctrl_init(&c[0], &cfg, &p), QNAV_OK);
        cfg.rank = (uint8_t)QNAV_RANK_QUALITY;
        assert_int_equal(qnav_ctrl_init(&c[1], &cfg, &p), QNAV_OK);
        random_scan(ranges, 32, 4000);
        qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)rng_range(-18000, 18000)};
        ref_path_qualities(&c[0], &p, &in, y); /* the float network's y */
        unsigned rbest = ref_argmax(y, ref_goal_deg(in.goal_bearing_cdeg));
        double margin = 2.0 * ref_preact_bound(&p) + 2.0 / 128.0;
        /* keys saturate at |y| = 136; below y = -12 every quality rounds to 0: a stop */
        int tie = y[rbest] > 120.0 || y[rbest] < -11.0;
        for (unsigned i = 0; i < QNAV_PATHS; ++i) {
            tie |= y[i] != y[rbest] && y[i] >= y[rbest] - margin;
        }
        if (tie) continue;
        ++clear;
        for (int m = 0; m < 2; ++m) {
            qnav_ctrl_step(&c[m], &in, &out, NULL);
            agree[m] += (unsigned)((out.heading_deg + 360) % 360) == rbest;

        }
    }
    print_message("saturated nets: heading agrees with the float network on %u / %u clear scans "
                  "ranked by pre-activation, %u / %u ranked by quality\n",
                  agree[0], clear, agree[1], clear);
    assert_true(clear * 4u >= SCANS); /* enough clear scans to judge (about a third are) */
    assert_true(agree[0] * 100u >= clear * 99u);
    assert_true(agree[0] > agree[1]);
}

/* --- table mode --- */

static void assert_same_output(const qnav_ctrl_output_t *a, const qnav_ctrl_output_t *b)
{
    assert_int_equal(a->heading_deg, b->heading_deg);
    assert_int_equal(a->speed, b->speed);
    assert_int_equal(a->quality, b->quality);
    assert_int_equal(a->flags, b->flags);
}

static void check_table_mode_identical(const qnav_policy_t *p, uint16_t n)
{
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_t direct;
    qnav_ctrl_t tab;
    qnav_ctrl_config_t cfg;
    qnav_mm_t ranges[QNAV_MAX_SECTORS];
    qnav_q1_15_t qd[QNAV_PATHS];
    qnav_q1_15_t qt[QNAV_PATHS];
    qnav_ctrl_output_t od;
    qnav_ctrl_output_t ot;

    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = n;
    cfg.max_range_mm = 3000;
    assert_int_equal(qnav_ctrl_init(&direct, &cfg, p), QNAV_OK);
    assert_int_equal(qnav_ctrl_build_table(&direct, table), QNAV_OK);
    assert_int_equal(qnav_ctrl_init_table(&tab, &cfg, table, qnav_ctrl_rank(&direct)), QNAV_OK);
    for (int k = 0; k < 50; ++k) {
        random_scan(ranges, n, 3000);
        qnav_ctrl_input_t in = {ranges, (qnav_cdeg_t)rng_range(-32768, 32767)};
        qnav_ctrl_output_t on;
        qnav_ctrl_output_t otn;
        qnav_ctrl_step(&direct, &in, &od, qd);
        qnav_ctrl_step(&tab, &in, &ot, qt);
        assert_memory_equal(qd, qt, sizeof qd);
        /* without qualities the step searches best first: it must decide the same */
        qnav_ctrl_step(&direct, &in, &on, NULL);
        qnav_ctrl_step(&tab, &in, &otn, NULL);
        assert_same_output(&on, &od);
        assert_same_output(&otn, &od);
        assert_int_equal(od.heading_deg, ot.heading_deg);
        assert_int_equal(od.speed, ot.speed);
        assert_int_equal(od.quality, ot.quality);
        assert_int_equal(od.flags, ot.flags);
    }
}

/* The flat ends that the network's share and qnav_sigmoid_q5_11 skip the table for are
 * where the stored grid points give 0 and 32767, and nothing between them is flat. */
static void test_sigmoid_flat_ends_match_the_table(void **state)
{
    int16_t prev = 0;
    (void)state;
    assert_int_equal(qnav_sigmoid_q5_11_between(QNAV_SIGMOID_LAST_ZERO), 0);
    assert_int_equal(qnav_sigmoid_q5_11_between(QNAV_SIGMOID_FIRST_TOP), 32767);
    for (int32_t v = QNAV_SIGMOID_LAST_ZERO + 1; v < QNAV_SIGMOID_FIRST_TOP; ++v) {
        int16_t h = qnav_sigmoid_q5_11_between((int16_t)v);
        assert_true(h > 0 && h < 32767);
        assert_true(h >= prev);
        assert_int_equal(qnav_sigmoid_q5_11((int16_t)v), h);
        prev = h;
    }
    assert_int_equal(qnav_sigmoid_q5_11(-32768), 0);
    assert_int_equal(qnav_sigmoid_q5_11(QNAV_SIGMOID_LAST_ZERO), 0);
    assert_int_equal(qnav_sigmoid_q5_11(QNAV_SIGMOID_FIRST_TOP), 32767);
    assert_int_equal(qnav_sigmoid_q5_11(32767), 32767);
}

/* Scans with the structure real ones have (clear, one obstacle at the goal, a corridor, a
 * wall behind) besides random ones: the row-shape shortcuts and the run search meet
 * their ties and edge cases there. */
static void structured_scan(qnav_mm_t *ranges, uint16_t n, qnav_mm_t max_mm, unsigned kind,
                            qnav_cdeg_t *goal)
{
    int32_t g = rng_range(-18000, 18000);
    fill(ranges, n, max_mm);
    switch (kind % 5u) {
    case 0: /* clear; the goal on a whole degree, often exactly ahead or behind */
        g = (rng_u32() % 2u) ? 0 : (rng_u32() % 2u ? 18000 : rng_range(-180, 180) * 100);
        break;
    case 1: /* one obstacle straight at the goal */
        for (uint16_t s = 0; s < n; ++s) {
            int32_t deg = (int32_t)(s * 360u / n);
            int32_t off = deg - g / 100;
            off = ((off % 360) + 540) % 360 - 180;
            if (off >= -20 && off <= 20) {
                ranges[s] = (qnav_mm_t)rng_range(300, max_mm - 1);
            }
        }
        break;
    case 2: /* a corridor: walls on both sides, the goal along it */
        for (uint16_t s = 0; s < n; ++s) {
            uint32_t deg = s * 360u / n;
            if ((deg > 40u && deg < 140u) || (deg > 220u && deg < 320u)) {
                ranges[s] = (qnav_mm_t)rng_range(250, 900);
            }
        }
        g = rng_range(-1500, 1500);
        break;
    case 3: /* a wall behind, goal behind */
        for (uint16_t s = 0; s < n; ++s) {
            uint32_t deg = s * 360u / n;
            if (deg > 120u && deg < 240u) {
                ranges[s] = 600;
            }
        }
        g = 18000 - rng_range(0, 3000);
        break;
    default:
        random_scan(ranges, n, max_mm);
        break;
    }
    *goal = (qnav_cdeg_t)g;
}

/* A controller for the comparison with the plain step; k picks the kind (a 2-input network
 * from mild to saturated, a 3-input one, the probabilistic policy with random parameters,
 * table mode of a 2-input network), the rank (every third group of 32 the literal
 * configuration: keys are qualities, long runs of equal keys), holding the heading
 * (keep_pct 0..30) and a quick escape (stall after 3 ticks). */
static void plain_case_init(qnav_ctrl_t *c, qnav_qkey_t *table, unsigned k, uint16_t n)
{
    static const int32_t scales[] = {128, 768, 4096, 32767};
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_t direct;
    uint8_t hidden = (uint8_t)rng_range(1, QNAV_MAX_HIDDEN);
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = n;
    cfg.max_range_mm = 4000;
    if ((k / 32u) % 3u == 2u) {
        qnav_ctrl_config_literal(&cfg);
    }
    cfg.keep_pct = (uint8_t)((k / 8u) % 4u * 10u);
    cfg.escape_stall_ticks = 3u;
    if (k % 4u == 2u) {
        qnav_policy_prob_default(&p);
        p.u.prob.k_goal = (qnav_q8_8_t)rng_range(1, 64 * 256);
        p.u.prob.k_safe = (qnav_q8_8_t)rng_range(1, 64 * 256);
    } else {
        qnav_policy_net_zero_inputs(&p, hidden, k % 4u == 1u ? 3u : 2u);
        for (uint16_t w = 0; w < qnav_net_weight_count(&p.u.net); ++w) {
            int32_t s = scales[(k / 8u) % 4u];
            *qnav_net_weight(&p.u.net, w) = (qnav_q8_8_t)rng_range(-s, s);
        }
    }
    assert_int_equal(qnav_ctrl_init(c, &cfg, &p), QNAV_OK);
    if (k % 4u == 3u) {
        direct = *c;
        assert_int_equal(qnav_ctrl_build_table(&direct, table), QNAV_OK);
        assert_int_equal(qnav_ctrl_init_table(c, &cfg, table, qnav_ctrl_rank(&direct)), QNAV_OK);
    }
}

/* Five ticks of the fast and the plain step from the same input (each fed its own previous
 * output), which must agree in everything: heading, speed, quality, flags, escape memory,
 * and all 360 qualities on the ticks that ask for them. */
static void expect_steps_agree(qnav_ctrl_t *c, const qnav_mm_t *ranges, qnav_cdeg_t goal,
                               unsigned k, uint16_t n)
{
    static qnav_q1_15_t q_fast[QNAV_PATHS];
    static qnav_q1_15_t q_plain[QNAV_PATHS];
    qnav_ctrl_input_t in_fast = {0};
    qnav_ctrl_input_t in_plain = {0};
    qnav_ctrl_output_t fast;
    qnav_ctrl_output_t plain;
    in_fast.ranges_mm = ranges;
    in_fast.goal_bearing_cdeg = goal;
    in_fast.prev_heading_cdeg = (qnav_cdeg_t)rng_range(-18000, 18000);
    in_fast.goal_range_mm = (qnav_mm_t)rng_range(0, 6000);
    in_plain = in_fast;
    memset(&fast, 0, sizeof fast);
    memset(&plain, 0, sizeof plain);
    for (unsigned tick = 0; tick < 5u; ++tick) {
        qnav_ctrl_step(c, &in_fast, &fast, (k + tick) % 2u ? q_fast : NULL);
        qnav_ctrl_step_plain(c, &in_plain, &plain, (k + tick) % 2u ? q_plain : NULL);
        if (memcmp(&fast, &plain, sizeof fast) != 0 ||
            ((k + tick) % 2u && memcmp(q_fast, q_plain, sizeof q_fast) != 0)) {
            fail_msg("case %u tick %u (N = %u, kind %u): fast heading %d, plain %d", k, tick,
                     n, k % 4u, fast.heading_deg, plain.heading_deg);
        }
        in_fast.escape = fast.escape;
        in_plain.escape = plain.escape;
        in_fast.prev_heading_cdeg = (qnav_cdeg_t)(fast.heading_deg * 100);
        in_plain.prev_heading_cdeg = (qnav_cdeg_t)(plain.heading_deg * 100);
    }
}

/* The fast step (row shapes, settled levels, the run search; with qualities, every run
 * evaluated) must decide exactly as the library's plain step, which evaluates every path
 * from its own inputs, for every kind, both ranks, holding the heading, escapes, all
 * sector counts. */
static void test_fast_step_equals_plain_step(void **state)
{
    (void)state;
    static const uint16_t sectors[] = {1, 5, 8, 16, 32, 64, 180, 360};
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_mm_t ranges[360];
    for (unsigned k = 0; k < 3000; ++k) {
        uint16_t n = sectors[k % 8u];
        qnav_ctrl_t c;
        qnav_cdeg_t goal;
        plain_case_init(&c, table, k, n);
        structured_scan(ranges, n, 4000, k / 96u, &goal);
        expect_steps_agree(&c, ranges, goal, k, n);
    }
}

/*
 * The same on networks made to defeat the run search's bounds, so that the step's credit
 * runs out and the rest of a run is evaluated path by path (policy_net.c, search_rest):
 * units in pairs that cancel, the same unit twice with output weights of opposite sign
 * but for a small difference. Along a run one share of a pair rises and the other falls,
 * so a span's bound counts each pair's whole swing while the keys stay nearly flat: no
 * span but the shortest can be ruled out.
 */
static void test_fast_step_equals_plain_step_when_the_search_runs_out(void **state)
{
    (void)state;
    static const uint16_t sectors[] = {1, 8, 16, 32, 180, 360};
    qnav_mm_t ranges[360];
    for (unsigned k = 0; k < 600; ++k) {
        uint16_t n = sectors[k % 6u];
        qnav_ctrl_config_t cfg;
        qnav_policy_t p;
        qnav_ctrl_t c;
        qnav_cdeg_t goal;
        uint8_t hidden = (uint8_t)(2u * (2u + k % 7u));
        int32_t spread = rng_range(0, 48);
        qnav_ctrl_config_default(&cfg);
        cfg.n_sectors = n;
        cfg.max_range_mm = 4000;
        cfg.keep_pct = (uint8_t)(k % 3u * 10u);
        if (k % 4u == 3u) {
            qnav_ctrl_config_literal(&cfg);
        }
        qnav_policy_net_zero_inputs(&p, hidden, 2u);
        for (uint8_t j = 0; j < hidden; j = (uint8_t)(j + 2u)) {
            int32_t w = rng_range(-127 * 256, 127 * 256);
            int32_t out = rng_range(1024, 127 * 256);
            p.u.net.w_theta[j] = p.u.net.w_theta[j + 1u] = (qnav_q8_8_t)w;
            p.u.net.w_dist[j] = p.u.net.w_dist[j + 1u] = (qnav_q8_8_t)rng_range(-2048, 2048);
            /* the transition somewhere along dtheta */
            p.u.net.b_hidden[j] = p.u.net.b_hidden[j + 1u] =
                (qnav_q8_8_t)(-(w / 256) * rng_range(0, 256));
            p.u.net.w_out[j] = (qnav_q8_8_t)out;
            p.u.net.w_out[j + 1u] = (qnav_q8_8_t)(-out + rng_range(-spread, spread));
        }
        p.u.net.b_out = (qnav_q8_8_t)rng_range(-512, 512);
        assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
        structured_scan(ranges, n, 4000, k / 6u, &goal);
        expect_steps_agree(&c, ranges, goal, k, n);
    }
}

/* Not ready (no controller, no scan) is the same stop from both steps. */
static void test_plain_step_stops_when_not_ready(void **state)
{
    (void)state;
    qnav_ctrl_t c;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    qnav_q1_15_t q[QNAV_PATHS];
    memset(&c, 0, sizeof c);
    memset(q, 0x55, sizeof q);
    qnav_ctrl_step_plain(&c, &in, &out, q);
    assert_int_equal(out.flags, QNAV_FLAG_NOT_READY);
    assert_int_equal(out.speed, 0);
    assert_int_equal(q[17], 0);
    qnav_ctrl_step_plain(&c, &in, NULL, NULL); /* no output: nothing to write, no crash */
}

static void reference_levels_wedge(const qnav_ctrl_t *c, const qnav_ctrl_config_t *cfg,
                                   const qnav_mm_t *ranges, uint16_t n, unsigned pct,
                                   qnav_mm_t near_mm, uint8_t *lvl);

/* The smallest whole degree g with sin g >= margin / d (sin in units of 2^-15, d at most
 * 65535 mm); 0 without a margin. */
static int reference_asin_deg(unsigned long margin, unsigned long d)
{
    if (margin == 0u) {
        return 0;
    }
    if (d > 65535u) {
        d = 65535u;
    }
    for (int g = 0; g < 90; ++g) {
        long sq = lround(sin((double)g * M_PI / 180.0) * 32768.0);
        if (sq > 32767) {
            sq = 32767;
        }
        if ((unsigned long)sq * d >= margin * 32768u) {
            return g;
        }
    }
    return 90;
}

/* The enlargement of one reading as defined (clearance.h): the smallest whole degree g with
 * sin g >= (r + d_s) / D, D the reading's own distance from the centre (range + sensor
 * offset, at most 65535 mm), sin in units of 2^-15 as the library tabulates it; 90 when no
 * degree below 90 suffices, 0 without a margin. Computed here from the configuration, not
 * from the library's per-level table: the level's floor is not the reading. */
static int reference_gamma(const qnav_ctrl_t *c, qnav_mm_t range_mm)
{
    return reference_asin_deg((unsigned long)c->clr.margin_mm,
                              (unsigned long)range_mm + c->clr.sensor_offset_mm);
}

/* The first path whose levels differ (the arrays are known to differ). */
static unsigned first_difference(const uint8_t *got, const uint8_t *want)
{
    unsigned q = 0;
    while (got[q] == want[q]) {
        ++q;
    }
    return q;
}

/* The enlargement as first written: every obstacle sector lowers its own paths widened by
 * its level's gamma on both sides, one path at a time (the whole wedge). */
static void reference_levels(const qnav_ctrl_t *c, const qnav_mm_t *ranges, uint16_t n,
                             uint8_t *lvl)
{
    reference_levels_wedge(c, NULL, ranges, n, 100u, 0u, lvl); /* no edge left free */
}

/* The step paints each piece only where no neighbour already covers it at a level no
 * higher; the levels must be those of painting everything. Walls that rise, fall and stay
 * level, all-equal scans (the skip chain runs around the circle), random ones. */
static void test_path_levels_equal_painting_every_sector(void **state)
{
    (void)state;
    static const uint16_t sectors[] = {1, 2, 3, 4, 5, 7, 8, 12, 16, 31, 32, 64, 90, 179, 180,
                                       181, 240, 359, 360};
    qnav_mm_t ranges[360];
    uint8_t got[QNAV_PATHS];
    uint8_t want[QNAV_PATHS];
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    for (unsigned k = 0; k < 3000; ++k) {
        uint16_t n = sectors[k % (sizeof sectors / sizeof sectors[0])];
        qnav_ctrl_t c;
        init_or_fail(&c, n, 4000, &p);
        switch ((k / 19u) % 6u) {
        case 0:
            random_scan(ranges, n, 4000);
            break;
        case 1: /* one range everywhere */
            fill(ranges, n, (qnav_mm_t)rng_range(0, 4500));
            break;
        case 2: /* a wall that comes nearer, then recedes */
            for (uint16_t s2 = 0; s2 < n; ++s2) {
                int32_t d = (int32_t)s2 * 2 * 4000 / n - 4000;
                ranges[s2] = (qnav_mm_t)(d < 0 ? -d : d) + (qnav_mm_t)rng_range(0, 50);
            }
            break;
        case 3: /* steps: runs of equal ranges */
            for (uint16_t s2 = 0; s2 < n; ++s2) {
                ranges[s2] = (qnav_mm_t)(((s2 / 3u) * 377u) % 4200u);
            }
            break;
        default: {
            qnav_cdeg_t goal;
            structured_scan(ranges, n, 4000, k, &goal);
            break;
        }
        }
        assert_int_equal(qnav_ctrl_path_levels(&c, ranges, got) & QNAV_FLAG_NOT_READY, 0);
        reference_levels(&c, ranges, n, want);
        if (memcmp(got, want, sizeof got) != 0) {
            unsigned q = first_difference(got, want);
            fail_msg("scan %u (N = %u, kind %u): path %u level %u, painting everything %u", k,
                     n, (k / 19u) % 6u, q, got[q], want[q]);
        }
    }
}

/* Wedge placement as defined in words (ctrl.h, wedge_pct): a reading nearer than
 * wedge_near_mm blocks its whole wedge; a farther one leaves shrink paths free at each edge
 * of its sector (shrink = (100 - pct)% of half the 360/N wedge, at most so many that the
 * middle path stays, and with the speed guard on at most the enlargement asin((r + pass) /
 * D) at D = r + d_s + 2 v T + v^2 / (2 a), where the robot must brake), so path p is placed
 * when the paths shrink either side of it are still in its sector; then each placed path
 * is widened by its reading's gamma. */
static void reference_levels_wedge(const qnav_ctrl_t *c, const qnav_ctrl_config_t *cfg,
                                   const qnav_mm_t *ranges, uint16_t n, unsigned pct,
                                   qnav_mm_t near_mm, uint8_t *lvl)
{
    unsigned shrink = ((100u - pct) * 360u) / (200u * n);
    unsigned keep = (360u / n - 1u) / 2u;
    uint8_t near_level = qnav_ctrl_level(c, near_mm);
    if (shrink > keep) {
        shrink = keep;
    }
    if (cfg != NULL && cfg->v_max_mm_s != 0u && cfg->decel_mm_s2 != 0u) {
        const double v = cfg->v_max_mm_s, a = cfg->decel_mm_s2;
        double brake = cfg->body_radius_mm + cfg->safety_mm + 2.0 * v * 0.1 + v * v / (2.0 * a);
        unsigned cover;
        brake = floor(brake) > 65535.0 ? 65535.0 : floor(brake);
        cover = (unsigned)reference_asin_deg((unsigned long)cfg->body_radius_mm + cfg->pass_mm,
                                             (unsigned long)brake);
        shrink = shrink < cover ? shrink : cover;
    }
    for (unsigned p = 0; p < QNAV_PATHS; ++p) {
        lvl[p] = QNAV_DIST_LEVELS - 1;
    }
    for (unsigned p = 0; p < QNAV_PATHS; ++p) {
        uint16_t s = qnav_ctrl_sector_of_path(n, (uint16_t)p);
        uint8_t level = qnav_ctrl_level(c, ranges[s]);
        int gamma = reference_gamma(c, ranges[s]);
        unsigned sh = level < near_level ? 0u : shrink;
        /* one sector: its only edge lies between paths 179 and 180 */
        unsigned from_edge = p < 180u ? 179u - p : p - 180u;
        if (level == QNAV_DIST_LEVELS - 1 || (n == 1u && from_edge < sh) ||
            qnav_ctrl_sector_of_path(n, (uint16_t)((p + 360u - sh) % 360u)) != s ||
            qnav_ctrl_sector_of_path(n, (uint16_t)((p + sh) % 360u)) != s) {
            continue;
        }
        for (int d = -gamma; d <= gamma; ++d) {
            unsigned q = (unsigned)(((int)p + d + 720) % 360);
            lvl[q] = lvl[q] < level ? lvl[q] : level;
        }
    }
}

/* Readings on the central part of their wedge, with and without a near distance, for every
 * sector count shape: the step's painting equals the definition. */
static void test_wedge_placement_equals_its_definition(void **state)
{
    (void)state;
    static const uint16_t sectors[] = {1, 2, 3, 5, 7, 8, 12, 16, 31, 32, 64, 90, 179, 180,
                                       181, 240, 360};
    static const unsigned pcts[] = {0, 10, 25, 50, 75, 99, 100};
    qnav_mm_t ranges[360];
    uint8_t got[QNAV_PATHS];
    uint8_t want[QNAV_PATHS];
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    for (unsigned k = 0; k < 2000; ++k) {
        uint16_t n = sectors[k % (sizeof sectors / sizeof sectors[0])];
        unsigned pct = pcts[(k / 17u) % (sizeof pcts / sizeof pcts[0])];
        qnav_mm_t near_mm = (k / 7u) % 2u ? 0u : (qnav_mm_t)rng_range(0, 4000);
        qnav_ctrl_config_t cfg;
        qnav_ctrl_t c;
        qnav_cdeg_t goal;
        qnav_ctrl_config_default(&cfg);
        cfg.n_sectors = n;
        cfg.max_range_mm = 4000;
        cfg.wedge_pct = (uint8_t)pct;
        cfg.wedge_near_mm = near_mm;
        assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
        if (k % 2u) {
            random_scan(ranges, n, 4000);
        } else {
            structured_scan(ranges, n, 4000, k, &goal);
        }
        assert_int_equal(qnav_ctrl_path_levels(&c, ranges, got) & QNAV_FLAG_NOT_READY, 0);
        reference_levels_wedge(&c, &cfg, ranges, n, pct, near_mm, want);
        if (memcmp(got, want, sizeof got) != 0) {
            unsigned q = first_difference(got, want);
            fail_msg("scan %u (N = %u, pct %u, near %u): path %u level %u, definition %u", k, n,
                     pct, near_mm, q, got[q], want[q]);
        }
    }
    /* above 100 % is refused */
    {
        qnav_ctrl_config_t cfg;
        qnav_ctrl_t c;
        qnav_ctrl_config_default(&cfg);
        cfg.wedge_pct = 101;
        assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_E_WEDGE);
    }
}

static void test_table_mode_is_bit_identical_to_network_mode(void **state)
{
    (void)state;
    static const uint16_t sectors[] = {1, 2, 3, 7, 8, 16, 32, 64, 180, 359, 360};
    qnav_policy_t p;
    for (size_t s = 0; s < sizeof sectors / sizeof sectors[0]; ++s) {
        random_net(&p, (uint8_t)rng_range(1, QNAV_MAX_HIDDEN), 32767);
        check_table_mode_identical(&p, sectors[s]);
        random_net(&p, 12, 1024);
        check_table_mode_identical(&p, sectors[s]);
        random_net(&p, 12, 256);
        check_table_mode_identical(&p, sectors[s]);
    }
}

static void test_table_mode_is_bit_identical_to_probabilistic_mode(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_policy_prob_default(&p);
    check_table_mode_identical(&p, 16);
    check_table_mode_identical(&p, 32);
}

static void test_build_table_refuses_a_table_controller(void **state)
{
    (void)state;
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    assert_int_equal(qnav_ctrl_init_table(&c, &cfg, table, QNAV_RANK_PREACT), QNAV_OK);
    assert_int_equal(qnav_ctrl_build_table(&c, table), QNAV_E_POLICY_KIND);
}

/* qnav_ctrl_init_compiled is init, build and init_table in one: the same table and the
 * same controller, byte for byte, for networks of every scale and both ranks and the
 * probabilistic policy; a 3-input network, a null table or a bad configuration leave the
 * controller not ready. */
static void test_init_compiled_equals_init_then_build_then_init_table(void **state)
{
    (void)state;
    static qnav_qkey_t want_table[QNAV_QTABLE_ENTRIES];
    static qnav_qkey_t got_table[QNAV_QTABLE_ENTRIES];
    static const int32_t scales[] = {256, 1024, 32767};
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_t want;
    qnav_ctrl_t got;
    for (unsigned k = 0; k < 13u; ++k) {
        qnav_ctrl_config_default(&cfg);
        cfg.n_sectors = (uint16_t)(k % 2u ? 16u : 32u);
        cfg.rank = (uint8_t)(k % 3u == 0u ? QNAV_RANK_QUALITY : QNAV_RANK_PREACT);
        if (k == 12u) {
            qnav_policy_prob_default(&p);
        } else {
            random_net(&p, (uint8_t)rng_range(1, QNAV_MAX_HIDDEN), scales[k % 3u]);
        }
        memset(&want, 0, sizeof want);
        memset(&got, 0, sizeof got);
        memset(got_table, 0x5A, sizeof got_table);
        assert_int_equal(qnav_ctrl_init(&want, &cfg, &p), QNAV_OK);
        assert_int_equal(qnav_ctrl_build_table(&want, want_table), QNAV_OK);
        assert_int_equal(qnav_ctrl_init_table(&want, &cfg, want_table, qnav_ctrl_rank(&want)),
                         QNAV_OK);
        assert_int_equal(qnav_ctrl_init_compiled(&got, &cfg, &p, got_table), QNAV_OK);
        assert_memory_equal(got_table, want_table, sizeof want_table);
        /* the one field that differs by construction: where the table is */
        assert_ptr_equal(got.p.net.table, got_table);
        got.p.net.table = want_table;
        assert_memory_equal(&got, &want, sizeof want);
    }
    qnav_ctrl_config_default(&cfg);
    qnav_policy_net_zero_inputs(&p, 4, 3u);
    assert_int_equal(qnav_ctrl_init_compiled(&got, &cfg, &p, got_table), QNAV_E_NO_TABLE);
    {
        qnav_mm_t ranges[16];
        qnav_ctrl_input_t in = {0};
        qnav_ctrl_output_t out;
        fill(ranges, 16, 1000);
        in.ranges_mm = ranges;
        qnav_ctrl_step(&got, &in, &out, NULL);
        assert_int_equal(out.flags & QNAV_FLAG_NOT_READY, QNAV_FLAG_NOT_READY);
    }
    random_net(&p, 4, 1024);
    assert_int_equal(qnav_ctrl_init_compiled(&got, &cfg, &p, NULL), QNAV_E_NULL);
    assert_int_equal(qnav_ctrl_init_compiled(&got, NULL, &p, got_table), QNAV_E_NULL);
    cfg.keep_pct = 101u;
    assert_int_equal(qnav_ctrl_init_compiled(&got, &cfg, &p, got_table), QNAV_E_KEEP);
}

/* --- policy helpers --- */

static void test_net_weight_walks_the_flat_order(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_policy_net_zero(&p, 3);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 0), &p.u.net.w_theta[0]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 5), &p.u.net.w_dist[1]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 10), &p.u.net.b_hidden[2]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 11), &p.u.net.w_out[2]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 12), &p.u.net.b_out);
    assert_null(qnav_net_weight(&p.u.net, 13));
    assert_null(qnav_net_weight(&p.u.net, 4000));
}

static void test_zero_net_clamps_hidden_units(void **state)
{
    (void)state;
    qnav_policy_t p;
    qnav_policy_net_zero(&p, 0);
    assert_int_equal(p.u.net.hidden, 1);
    qnav_policy_net_zero(&p, 200);
    assert_int_equal(p.u.net.hidden, QNAV_MAX_HIDDEN);
}

/* Arrange: a fresh carry, zero input and output. */
static void carry_fresh(qnav_ctrl_carry_t *c, qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    memset(in, 0, sizeof *in);
    memset(out, 0, sizeof *out);
    qnav_ctrl_carry_reset(c);
}

/* The carry: a new destination clears the escape memory; the same one keeps it. */
static void test_carry_clears_escape_memory_only_for_a_new_goal(void **state)
{
    qnav_ctrl_carry_t c;
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    (void)state;
    carry_fresh(&c, &in, &out);
    qnav_ctrl_carry_input(&c, 7u, 3000u, 0, &in);
    out.escape.side = 1;
    out.escape.ticks = 42u;
    qnav_ctrl_carry_output(&c, &out);
    qnav_ctrl_carry_input(&c, 7u, 2900u, 0, &in);
    assert_int_equal(in.escape.side, 1);
    assert_int_equal(in.escape.ticks, 42);
    qnav_ctrl_carry_input(&c, 8u, 2900u, 0, &in);
    assert_int_equal(in.escape.side, 0);
    assert_int_equal(in.escape.ticks, 0);
}

/* The carry: the distance saturates at 65535 mm; 0 (a bearing goal) stays 0 (no escape). */
static void test_carry_saturates_goal_range(void **state)
{
    qnav_ctrl_carry_t c;
    qnav_ctrl_input_t in;
    (void)state;
    memset(&in, 0, sizeof in);
    qnav_ctrl_carry_reset(&c);
    qnav_ctrl_carry_input(&c, 1u, 70000u, 0, &in);
    assert_int_equal(in.goal_range_mm, 65535);
    qnav_ctrl_carry_input(&c, 1u, 0u, 0, &in);
    assert_int_equal(in.goal_range_mm, 0);
}

/* The carry: the previous heading is the last ready decision seen from the robot's new
 * heading, whatever the goal bearing did (a map moves it to its sub-goal); a not-ready
 * output leaves it as it was; the turn wraps across +-180 deg. */
static void test_carry_gives_previous_heading_of_last_ready_decision(void **state)
{
    qnav_ctrl_carry_t c;
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    (void)state;
    carry_fresh(&c, &in, &out);
    in.goal_bearing_cdeg = 1000;
    qnav_ctrl_carry_input(&c, 1u, 0u, 17900, &in);
    assert_int_equal(in.prev_heading_cdeg, 0);
    out.heading_deg = 30;
    qnav_ctrl_carry_output(&c, &out);
    out.heading_deg = -90;
    out.flags = QNAV_FLAG_NOT_READY;
    qnav_ctrl_carry_output(&c, &out);
    in.goal_bearing_cdeg = -4000;                      /* a sub-goal elsewhere: no matter */
    qnav_ctrl_carry_input(&c, 1u, 0u, -17600, &in);    /* the robot turned 5 deg left since */
    assert_int_equal(in.prev_heading_cdeg, 2500);
    out.flags = 0;
    qnav_ctrl_carry_output(&c, &out);                  /* decided -90 at heading -176 */
    qnav_ctrl_carry_input(&c, 1u, 0u, 17600, &in);     /* then turned 8 deg right */
    assert_int_equal(in.prev_heading_cdeg, -8200);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_rejects_bad_configuration),
        cmocka_unit_test(test_init_rejects_bad_policies),
        cmocka_unit_test(test_failed_init_leaves_controller_commanding_stop),
        cmocka_unit_test(test_step_with_null_ranges_commands_stop),
        cmocka_unit_test(test_sector_of_path_centres_sector_zero_straight_ahead),
        cmocka_unit_test(test_level_maps_zero_and_max_range_to_the_ends),
        cmocka_unit_test(test_ctrl_drives_at_goal_in_open_space),
        cmocka_unit_test(test_ctrl_turns_away_from_near_obstacle),
        cmocka_unit_test(test_a_turn_keeps_its_way_round),
        cmocka_unit_test(test_holding_keeps_the_previous_of_two_equal_ways),
        cmocka_unit_test(test_holding_preactivation_keys_within_a_margin_of_z),
        cmocka_unit_test(test_ctrl_prefers_goal_over_far_obstacle),
        cmocka_unit_test(test_a_wall_beyond_the_destination_does_not_block_the_way_to_it),
        cmocka_unit_test(test_speed_is_linear_in_quality_up_to_full),
        cmocka_unit_test(test_quality_ranked_keys_reach_full_speed_at_their_own_quality),
        cmocka_unit_test(test_equal_qualities_choose_the_goal_direction),
        cmocka_unit_test(test_ranges_beyond_max_are_clipped_and_flagged),
        cmocka_unit_test(test_all_zero_quality_stops_and_flags),
        cmocka_unit_test(test_qualities_are_within_bound_of_double_reference),
        cmocka_unit_test(test_argmax_matches_reference_on_random_scans),
        cmocka_unit_test(test_zero_margin_reads_each_path_from_its_own_sector),
        cmocka_unit_test(test_enlargement_blocks_paths_beside_a_near_obstacle),
        cmocka_unit_test(test_enlargement_matches_asin_at_every_level),
        cmocka_unit_test(test_enlargement_lowers_collisions_with_sector_count_not_raises),
        cmocka_unit_test(test_speed_guard_caps_speed_to_stop_within_clearance),
        cmocka_unit_test(test_saturated_network_ranks_by_preactivation),
        cmocka_unit_test(test_preactivation_rank_agrees_with_float_network_on_saturated_nets),
        cmocka_unit_test(test_sigmoid_flat_ends_match_the_table),
        cmocka_unit_test(test_fast_step_equals_plain_step),
        cmocka_unit_test(test_fast_step_equals_plain_step_when_the_search_runs_out),
        cmocka_unit_test(test_plain_step_stops_when_not_ready),
        cmocka_unit_test(test_path_levels_equal_painting_every_sector),
        cmocka_unit_test(test_wedge_placement_equals_its_definition),
        cmocka_unit_test(test_table_mode_is_bit_identical_to_network_mode),
        cmocka_unit_test(test_table_mode_is_bit_identical_to_probabilistic_mode),
        cmocka_unit_test(test_build_table_refuses_a_table_controller),
        cmocka_unit_test(test_init_compiled_equals_init_then_build_then_init_table),
        cmocka_unit_test(test_net_weight_walks_the_flat_order),
        cmocka_unit_test(test_zero_net_clamps_hidden_units),
        cmocka_unit_test(test_carry_clears_escape_memory_only_for_a_new_goal),
        cmocka_unit_test(test_carry_saturates_goal_range),
        cmocka_unit_test(test_carry_gives_previous_heading_of_last_ready_decision),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
