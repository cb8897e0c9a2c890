/*
 * Body-aware clearance (firmware/src/clearance.[ch]) against the computations the step made
 * before they were made faster. The references below are clearance.c's own code as it
 * stood at c6f786c, kept here so that the faster forms are checked to give the same values,
 * not merely close ones; each reading's own gamma against the walk that found it at 5d57e83.
 * Built for 32, 64, 2 and 23 distance levels (tests/firmware).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>
#include <math.h>

#include "clearance.h"
#include "qnav/ctrl.h"

/* ---- reference: the range-to-level mapping of c6f786c ----------------------------------- */

/* The scale qnav_clearance_setup kept. */
static uint32_t ref_scale(qnav_mm_t max_range_mm)
{
    return ((uint32_t)(QNAV_DIST_LEVELS - 1) * 65536u + max_range_mm / 2u) / max_range_mm;
}

/* level_of() of a range that its callers had clipped to the maximum range. */
static uint8_t ref_level(qnav_mm_t max_range_mm, uint32_t range_mm)
{
    qnav_mm_t r = (qnav_mm_t)(range_mm < max_range_mm ? range_mm : max_range_mm);
    uint32_t level = ((uint32_t)r * ref_scale(max_range_mm) + 32768u) >> 16;
    return (uint8_t)(level > QNAV_DIST_LEVELS - 1u ? QNAV_DIST_LEVELS - 1u : level);
}

/* ---- reference: the speed guard's cap of c6f786c, computed for every step -------------- */

#define REF_GUARD_REACTION_MS 100u

/* level_floor_mm(): the smallest range at level or above, by a binary search. */
static uint32_t ref_floor(qnav_mm_t max_range_mm, uint8_t level)
{
    uint32_t lo = 0;
    uint32_t hi = max_range_mm;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        if (ref_level(max_range_mm, mid) >= level) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

static uint32_t ref_isqrt32(uint32_t x)
{
    uint32_t r = 0;
    uint32_t bit = (uint32_t)1 << 30;
    while (bit > x) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return r;
}

static qnav_q1_15_t ref_stop_speed(uint32_t s_mm, uint32_t v_max_mm_s, uint32_t decel_mm_s2)
{
    uint32_t at = decel_mm_s2 * REF_GUARD_REACTION_MS / 1000u;
    uint32_t at2 = at * at;
    uint32_t v;
    if (s_mm > (0xFFFFFFFFu - at2) / (2u * decel_mm_s2)) {
        return QNAV_Q1_15_MAX;
    }
    v = ref_isqrt32(at2 + 2u * decel_mm_s2 * s_mm) - at;
    if (v >= v_max_mm_s) {
        return QNAV_Q1_15_MAX;
    }
    return (qnav_q1_15_t)((v * 32768u) / v_max_mm_s);
}

/* qnav_clearance_speed_cap() with qnav_clearance_init()'s fields spelt out from cfg; since
 * range_min_mm, a level whose floor is at or below the sonar's minimum range (the sonar
 * reads that range for anything nearer) is taken as range 0. */
static qnav_q1_15_t ref_speed_cap(const qnav_ctrl_config_t *cfg, uint8_t level)
{
    uint32_t margin = (uint32_t)cfg->body_radius_mm + cfg->safety_mm;
    uint32_t floor_mm = ref_floor(cfg->max_range_mm, level);
    uint32_t d;
    margin = margin > 65535u ? 65535u : margin;
    if (cfg->v_max_mm_s == 0u || cfg->decel_mm_s2 == 0u || level >= QNAV_DIST_LEVELS - 1u) {
        return QNAV_Q1_15_MAX;
    }
    d = (floor_mm <= cfg->range_min_mm ? 0u : floor_mm) + cfg->sensor_offset_mm;
    d = d > 65535u ? 65535u : d;
    return ref_stop_speed(d > margin ? d - margin : 0u, cfg->v_max_mm_s, cfg->decel_mm_s2);
}


/* ---- reference: each reading's own gamma as the step walked it down at 5d57e83 ---------- */

/* sin(g degrees) in units of 2^-15, g = 0..90, rounded and capped at 32767 as clearance.c's
 * table is said to be made: computed here from libm, not copied, so that the reference
 * checks the table too. */
static uint16_t ref_sin_q15(unsigned g)
{
    double v = floor(sin((double)g * 3.14159265358979323846 / 180.0) * 32768.0 + 0.5);
    return (uint16_t)(v > 32767.0 ? 32767.0 : v);
}

/* enlarge_deg(): the smallest whole degree g with sin(g) >= margin / d. */
static uint8_t ref_enlarge(uint32_t margin_mm, uint32_t d_mm)
{
    if (margin_mm == 0u) {
        return 0;
    }
    if (d_mm <= margin_mm) {
        return 90;
    }
    for (uint8_t g = 0; g < 90u; ++g) {
        if ((uint32_t)ref_sin_q15(g) * d_mm >= margin_mm * 32768u) {
            return g;
        }
    }
    return 90;
}

/* reading_gamma(): from the gamma of the reading's level's smallest range, down a degree
 * at a time while the reading's own distance still allows it. */
static uint8_t ref_reading_gamma(const qnav_ctrl_config_t *cfg, qnav_mm_t range_mm)
{
    uint32_t margin = (uint32_t)cfg->body_radius_mm + cfg->pass_mm;
    uint32_t floor_d = ref_floor(cfg->max_range_mm, ref_level(cfg->max_range_mm, range_mm)) +
                       cfg->sensor_offset_mm;
    uint32_t d = (uint32_t)range_mm + cfg->sensor_offset_mm;
    uint8_t g;
    margin = margin > 65535u ? 65535u : margin;
    g = ref_enlarge(margin, floor_d > 65535u ? 65535u : floor_d);
    d = d > 65535u ? 65535u : d;
    while (g > 0u && (uint32_t)ref_sin_q15(g - 1u) * d >= (margin << 15)) {
        --g;
    }
    return g;
}

/* ---- tests ------------------------------------------------------------------------------ */

/* A Pioneer 3-DX's body and sonar (5 m, from its 0.26 m rim) with safety distance safety_mm. */
static void pioneer_config(qnav_ctrl_config_t *cfg, uint16_t safety_mm)
{
    qnav_ctrl_config_default(cfg);
    cfg->max_range_mm = 5000u;
    cfg->body_radius_mm = 260u;
    cfg->safety_mm = safety_mm;
    cfg->sensor_offset_mm = 260u;
    cfg->v_max_mm_s = 1000u;
    cfg->decel_mm_s2 = 600u;
}

static void setup_range(qnav_clearance_t *c, qnav_mm_t max_range_mm)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    cfg.max_range_mm = max_range_mm;
    assert_int_equal(qnav_clearance_setup(c, &cfg), QNAV_OK);
}

/* Besides every maximum range 1..300 mm (those below L mm have a scale beyond 16 bits):
 * powers of two and their neighbours, the robots' sonars, the largest. */
static const qnav_mm_t more_ranges_mm[] = {
    1000, 1023, 1024, 1025, 2047, 2048, 2500, 3000, 4095, 5000, 8000, 12345, 16384,
    32767, 32768, 40000, 65534, 65535,
};

static void check_every_range(qnav_mm_t max_mm)
{
    qnav_clearance_t c;
    setup_range(&c, max_mm);
    for (uint32_t r = 0; r <= 65535u; ++r) {
        uint8_t got = qnav_clearance_level_of(&c, (qnav_mm_t)r);
        uint8_t want = ref_level(max_mm, r);
        if (got != want) {
            fail_msg("max_range_mm %u, range %u: level %u, formula %u", (unsigned)max_mm,
                     (unsigned)r, (unsigned)got, (unsigned)want);
        }
    }
}

/* The level depends on the configuration through max_range_mm only. */
static void test_level_of_equals_the_formula_for_every_range(void **state)
{
    (void)state;
    for (uint32_t m = 1; m <= 300u; ++m) {
        check_every_range((qnav_mm_t)m);
    }
    for (size_t i = 0; i < sizeof more_ranges_mm / sizeof more_ranges_mm[0]; ++i) {
        check_every_range(more_ranges_mm[i]);
    }
}

/* Configurations around every branch of the cap: no guard (v_max or decel 0), caps of 0,
 * of full speed, of 2 a s beyond 32 bits (decel 65535 at long range), and from one level
 * between 0 and full speed (the TekBot) to all of them (braking at 1 mm/s^2). */
static const qnav_mm_t guard_ranges_mm[] = {1, 5, 31, 32, 100, 2500, 5000, 65535};
static const qnav_mm_t guard_offsets_mm[] = {0, 120, 65535};
static const qnav_mm_t guard_radii_mm[][2] = {{0, 0}, {120, 50}, {260, 50}, {65535, 65535}};
static const uint16_t guard_v_max_mm_s[] = {0, 1, 500, 1000, 65535};
static const uint16_t guard_decel_mm_s2[] = {0, 1, 9, 100, 600, 2000, 65535};
static const qnav_mm_t guard_range_min_mm[] = {0, 30, 100, 4999};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static void check_caps(const qnav_ctrl_config_t *cfg, unsigned *between)
{
    qnav_clearance_t c;
    if (cfg->range_min_mm >= cfg->max_range_mm) {
        assert_int_equal(qnav_clearance_setup(&c, cfg), QNAV_E_RANGE);
        return;
    }
    assert_int_equal(qnav_clearance_setup(&c, cfg), QNAV_OK);
    for (uint8_t level = 0; level < QNAV_DIST_LEVELS; ++level) {
        qnav_q1_15_t want = ref_speed_cap(cfg, level);
        qnav_q1_15_t got = qnav_clearance_speed_cap(&c, level);
        if (got != want) {
            fail_msg("range %u min %u offset %u radius %u safety %u v_max %u decel %u level "
                     "%u: cap %d, computed %d", (unsigned)cfg->max_range_mm,
                     (unsigned)cfg->range_min_mm,
                     (unsigned)cfg->sensor_offset_mm, (unsigned)cfg->body_radius_mm,
                     (unsigned)cfg->safety_mm, (unsigned)cfg->v_max_mm_s,
                     (unsigned)cfg->decel_mm_s2, (unsigned)level, got, want);
        }
        *between += (unsigned)(want > 0 && want < QNAV_Q1_15_MAX);
    }
}

static void test_speed_cap_equals_the_computation_for_every_level(void **state)
{
    (void)state;
    unsigned between = 0;
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    for (size_t i = 0; i < COUNT(guard_ranges_mm); ++i) {
        for (size_t j = 0; j < COUNT(guard_offsets_mm); ++j) {
            for (size_t k = 0; k < COUNT(guard_radii_mm); ++k) {
                for (size_t v = 0; v < COUNT(guard_v_max_mm_s); ++v) {
                    for (size_t a = 0; a < COUNT(guard_decel_mm_s2); ++a) {
                        for (size_t m = 0; m < COUNT(guard_range_min_mm); ++m) {
                            cfg.max_range_mm = guard_ranges_mm[i];
                            cfg.sensor_offset_mm = guard_offsets_mm[j];
                            cfg.body_radius_mm = guard_radii_mm[k][0];
                            cfg.safety_mm = guard_radii_mm[k][1];
                            cfg.v_max_mm_s = guard_v_max_mm_s[v];
                            cfg.decel_mm_s2 = guard_decel_mm_s2[a];
                            cfg.range_min_mm = guard_range_min_mm[m];
                            check_caps(&cfg, &between);
                        }
                    }
                }
            }
        }
    }
    /* the levels that still compute their cap were reached too */
    assert_true(between > 100u);
}

/* A sonar reads its minimum range for anything that near or nearer: with the Pioneer's
 * figures (0.1 m, distance level 1 of a 5 m sonar, levels 161 mm wide) the level that
 * holds it caps the speed at 0, where its floor (81 mm) alone left 0.141 m/s to creep
 * into a wall; the next level's cap is its floor's, as without a minimum range. */
static void test_speed_cap_is_zero_at_the_level_of_the_minimum_range(void **state)
{
    (void)state;
    qnav_ctrl_config_t cfg;
    qnav_clearance_t with_min;
    qnav_clearance_t without;
    uint8_t level;
    pioneer_config(&cfg, 50u);
    assert_int_equal(qnav_clearance_setup(&without, &cfg), QNAV_OK);
    cfg.range_min_mm = 100u;
    assert_int_equal(qnav_clearance_setup(&with_min, &cfg), QNAV_OK);
    level = qnav_clearance_level_of(&with_min, cfg.range_min_mm);
    if (QNAV_DIST_LEVELS == 32u) { /* other level counts: the floor alone may give 0 already */
        assert_int_equal(level, 1);
        assert_int_equal(qnav_clearance_speed_cap(&without, level), 4620); /* 0.141 m/s */
    }
    assert_int_equal(qnav_clearance_speed_cap(&with_min, level), 0);
    if (level + 1u < QNAV_DIST_LEVELS) {
        assert_int_equal(qnav_clearance_speed_cap(&with_min, (uint8_t)(level + 1u)),
                         qnav_clearance_speed_cap(&without, (uint8_t)(level + 1u)));
    }
}

/* Each reading's gamma, read off the painted arc of a lone reading at 360 sectors (2 gamma + 1
 * paths), equals the old walk down from its level's gamma, for every range below the maximum
 * of sonars short and long, bodies from none to a metre and sensor offsets. */
static void test_reading_gamma_equals_the_walk_for_every_range(void **state)
{
    (void)state;
    static const qnav_mm_t max_mm[] = {40, 300, 1000, 2500, 5000, 12345};
    static const uint16_t body_mm[] = {0, 40, 120, 170, 400, 1000};
    static const qnav_mm_t offset_mm[] = {0, 120, 300};
    static qnav_mm_t ranges[QNAV_MAX_SECTORS];
    uint8_t lvl[QNAV_PATHS];
    for (unsigned m = 0; m < sizeof max_mm / sizeof max_mm[0]; ++m) {
        for (unsigned b = 0; b < sizeof body_mm / sizeof body_mm[0]; ++b) {
            for (unsigned o = 0; o < sizeof offset_mm / sizeof offset_mm[0]; ++o) {
                qnav_ctrl_config_t cfg;
                qnav_clearance_t c;
                qnav_ctrl_config_default(&cfg);
                cfg.n_sectors = QNAV_MAX_SECTORS;
                cfg.max_range_mm = max_mm[m];
                cfg.body_radius_mm = body_mm[b];
                cfg.pass_mm = (uint16_t)(body_mm[b] / 4u);
                cfg.safety_mm = (uint16_t)(body_mm[b] / 2u); /* the guard's, not gamma's */
                cfg.sensor_offset_mm = offset_mm[o];
                assert_int_equal(qnav_clearance_setup(&c, &cfg), QNAV_OK);
                for (uint16_t i = 0; i < QNAV_MAX_SECTORS; ++i) {
                    ranges[i] = cfg.max_range_mm;
                }
                for (uint32_t r = 0; r < cfg.max_range_mm; ++r) {
                    unsigned painted = 0;
                    unsigned want = 0;
                    ranges[0] = (qnav_mm_t)r;
                    qnav_clearance_levels(&c, ranges, c.n_sectors, lvl);
                    for (uint16_t p = 0; p < QNAV_PATHS; ++p) {
                        painted += lvl[p] != QNAV_DIST_LEVELS - 1u;
                    }
                    if (ref_level(cfg.max_range_mm, r) != QNAV_DIST_LEVELS - 1u) {
                        want = 2u * ref_reading_gamma(&cfg, (qnav_mm_t)r) + 1u;
                    }
                    if (painted != want) {
                        fail_msg("max %u mm, margin %u mm, offset %u mm, range %u mm: %u paths "
                                 "painted, the walk gives %u", (unsigned)cfg.max_range_mm,
                                 (unsigned)(body_mm[b] + body_mm[b] / 4u),
                                 (unsigned)offset_mm[o], (unsigned)r, painted, want);
                    }
                }
            }
        }
    }
}

/* Paths painted by a lone reading at 360 sectors (2 gamma + 1, or none). */
static unsigned lone_reading_paths(const qnav_clearance_t *c, qnav_mm_t max_mm, qnav_mm_t range_mm)
{
    static qnav_mm_t ranges[QNAV_MAX_SECTORS];
    uint8_t lvl[QNAV_PATHS];
    unsigned painted = 0;
    for (uint16_t i = 0; i < QNAV_MAX_SECTORS; ++i) {
        ranges[i] = max_mm;
    }
    ranges[0] = range_mm;
    qnav_clearance_levels(c, ranges, c->n_sectors, lvl);
    for (uint16_t p = 0; p < QNAV_PATHS; ++p) {
        painted += lvl[p] != QNAV_DIST_LEVELS - 1u;
    }
    return painted;
}

/* A reading at the sonar's minimum range (or below: it never reads less) says the obstacle is
 * that near or nearer, down to the safety distance the robot keeps: it blocks at least the
 * paths within asin(r / (r + d_s)) of it, which would touch an obstacle r + d_s from the
 * centre. A reading above the minimum keeps its own enlargement, and so does every reading
 * of a sonar without a minimum range or one whose minimum lies within r + d_s. The Pioneer
 * 3-DX (sonar on its 0.26 m rim, 0.1 m minimum, d_s 0.02 m): 2 x 69 + 1 paths at 0.1 m
 * (asin(0.26 / 0.28) = 68.2 deg), 2 x 51 + 1 at 0.101 m (asin(0.28 / 0.361)). */
static void test_a_reading_at_the_minimum_range_blocks_what_it_may_touch(void **state)
{
    (void)state;
    static const uint16_t body_mm[] = {0, 120, 260, 400};
    static const uint16_t safety_mm[] = {0, 20, 50};
    static const qnav_mm_t offset_mm[] = {0, 120, 260};
    static const qnav_mm_t min_mm[] = {0, 30, 100, 200};
    qnav_ctrl_config_t cfg;
    qnav_clearance_t c;
    pioneer_config(&cfg, 20u);
    cfg.n_sectors = QNAV_MAX_SECTORS;
    cfg.pass_mm = 20u;
    cfg.range_min_mm = 100u;
    assert_int_equal(qnav_clearance_setup(&c, &cfg), QNAV_OK);
    assert_int_equal(lone_reading_paths(&c, cfg.max_range_mm, 100u), 2u * 69u + 1u);
    assert_int_equal(lone_reading_paths(&c, cfg.max_range_mm, 101u), 2u * 51u + 1u);
    for (unsigned b = 0; b < sizeof body_mm / sizeof body_mm[0]; ++b) {
        for (unsigned s = 0; s < sizeof safety_mm / sizeof safety_mm[0]; ++s) {
            for (unsigned o = 0; o < sizeof offset_mm / sizeof offset_mm[0]; ++o) {
                for (unsigned m = 0; m < sizeof min_mm / sizeof min_mm[0]; ++m) {
                    const uint8_t touch = ref_enlarge(body_mm[b], (uint32_t)body_mm[b] + safety_mm[s]);
                    cfg.body_radius_mm = body_mm[b];
                    cfg.safety_mm = safety_mm[s];
                    cfg.pass_mm = (uint16_t)(safety_mm[s] / 2u);
                    cfg.sensor_offset_mm = offset_mm[o];
                    cfg.range_min_mm = min_mm[m];
                    assert_int_equal(qnav_clearance_setup(&c, &cfg), QNAV_OK);
                    for (uint32_t r = 0; r <= min_mm[m] + 40u; ++r) {
                        uint8_t g = ref_reading_gamma(&cfg, (qnav_mm_t)r);
                        if (min_mm[m] != 0u && r <= min_mm[m] && g < touch) {
                            g = touch;
                        }
                        if (lone_reading_paths(&c, cfg.max_range_mm, (qnav_mm_t)r) != 2u * g + 1u) {
                            fail_msg("body %u mm, safety %u mm, offset %u mm, minimum %u mm, range "
                                     "%u mm: want %u paths", (unsigned)body_mm[b],
                                     (unsigned)safety_mm[s], (unsigned)offset_mm[o],
                                     (unsigned)min_mm[m], (unsigned)r, 2u * g + 1u);
                        }
                    }
                }
            }
        }
    }
}

/* The two distances do one job each: pass_mm alone decides the enlargement (what a reading
 * paints), safety_mm alone what the speed guard leaves to stop in (a TekBot with a map:
 * safety 50 mm, pass 10 mm; docs/architecture.md, "Passing distance"). */
static void test_pass_sets_the_enlargement_and_safety_the_guard(void **state)
{
    static const qnav_mm_t reading_mm[] = {150, 330, 480, 700, 1200, 2400};
    static qnav_mm_t ranges[16];
    uint8_t lvl_a[QNAV_PATHS], lvl_b[QNAV_PATHS], lvl_c[QNAV_PATHS];
    qnav_clearance_t a, b, c; /* a: safety 50, pass 10; b: both 10; c: both 50 */
    qnav_ctrl_config_t cfg;
    unsigned wider = 0, slower = 0;
    (void)state;
    qnav_ctrl_config_default(&cfg);
    cfg.max_range_mm = 2500u;
    cfg.range_min_mm = 30u;
    cfg.pass_mm = 10u;
    assert_int_equal(qnav_clearance_setup(&a, &cfg), QNAV_OK);
    cfg.safety_mm = 10u;
    assert_int_equal(qnav_clearance_setup(&b, &cfg), QNAV_OK);
    cfg.safety_mm = 50u;
    cfg.pass_mm = 50u;
    assert_int_equal(qnav_clearance_setup(&c, &cfg), QNAV_OK);
    for (size_t i = 0; i < COUNT(reading_mm); ++i) {
        for (uint16_t k = 0; k < 16u; ++k) {
            ranges[k] = 2500u;
        }
        ranges[1] = reading_mm[i];
        qnav_clearance_levels(&a, ranges, 16u, lvl_a);
        qnav_clearance_levels(&b, ranges, 16u, lvl_b);
        qnav_clearance_levels(&c, ranges, 16u, lvl_c);
        assert_memory_equal(lvl_a, lvl_b, QNAV_PATHS);
        wider += memcmp(lvl_a, lvl_c, QNAV_PATHS) != 0;
    }
    for (uint8_t level = 0; level < QNAV_DIST_LEVELS; ++level) {
        assert_int_equal(qnav_clearance_speed_cap(&a, level), qnav_clearance_speed_cap(&c, level));
        slower += qnav_clearance_speed_cap(&a, level) != qnav_clearance_speed_cap(&b, level);
    }
    assert_true(wider > 0u);  /* pass 50 paints more than pass 10 */
    if (QNAV_DIST_LEVELS >= 16u) { /* two levels: no level lies between the two caps */
        assert_true(slower > 0u);  /* safety 50 caps where safety 10 does not */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_level_of_equals_the_formula_for_every_range),
        cmocka_unit_test(test_speed_cap_equals_the_computation_for_every_level),
        cmocka_unit_test(test_speed_cap_is_zero_at_the_level_of_the_minimum_range),
        cmocka_unit_test(test_reading_gamma_equals_the_walk_for_every_range),
        cmocka_unit_test(test_a_reading_at_the_minimum_range_blocks_what_it_may_touch),
        cmocka_unit_test(test_pass_sets_the_enlargement_and_safety_the_guard),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
