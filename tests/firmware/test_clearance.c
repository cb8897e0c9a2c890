/*
 * Body-aware clearance (firmware/src/clearance.[ch]) against the computations the step made
 * before they were made faster. The references below are clearance.c's own code as it
 * stood at c6f786c, kept here so that the faster forms are checked to give the same values,
 * not merely close ones. Built for 32, 64, 2 and 23 distance levels (tests/firmware).
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

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

/* ---- tests ------------------------------------------------------------------------------ */

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_level_of_equals_the_formula_for_every_range),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
