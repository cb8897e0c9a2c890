/*
 * libqnav's integer trigonometry (CORDIC, qnav/trig.h) against the C library: cos and sin
 * within 2/16384 over the whole circle, atan2 within 1 cdeg of the integer point's direction and lengths within 0.1 % + 2
 * over every quadrant, from a few millimetres to 2 km.
 */
#define _DEFAULT_SOURCE
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "qnav/trig.h"

static void test_cos_sin_are_within_two_counts_of_q14_over_the_circle(void **state)
{
    int32_t a;
    int worst = 0;
    (void)state;
    for (a = -36000; a <= 36000; a += 7) {
        int16_t c, s;
        double r = a * M_PI / 18000.0;
        int ec, es;
        qnav_cos_sin_q14(a, &c, &s);
        ec = abs(c - (int)lround(cos(r) * 16384.0));
        es = abs(s - (int)lround(sin(r) * 16384.0));
        worst = ec > worst ? ec : worst;
        worst = es > worst ? es : worst;
    }
    print_message("worst cos/sin error %d / 16384\n", worst);
    assert_true(worst <= 2);
}

static void test_atan2_is_within_one_cdeg_and_length_within_a_permille(void **state)
{
    static const int32_t radii[] = {7, 50, 999, 12345, 400000, 2000000};
    int32_t a;
    unsigned r;
    int worst = 0;
    (void)state;
    for (r = 0; r < sizeof radii / sizeof radii[0]; ++r) {
        for (a = -18000; a < 18000; a += 13) {
            double rad = a * M_PI / 18000.0;
            int32_t x = (int32_t)lround(radii[r] * cos(rad));
            int32_t y = (int32_t)lround(radii[r] * sin(rad));
            double want = atan2((double)y, (double)x) * 18000.0 / M_PI;
            double len = sqrt((double)x * x + (double)y * y);
            uint32_t dist;
            qnav_cdeg_t got = qnav_atan2_cdeg(y, x, &dist);
            double err = fabs(got - want);
            if (err > 18000.0) {
                err = 36000.0 - err; /* -18000 and 17999 are neighbours */
            }
            worst = (int)err > worst ? (int)err : worst;
            if (err > 1.0) {
                print_message("atan2(%d, %d) = %d, want %.2f\n", y, x, got, want);
            }
            assert_true(err <= 1.0);
            assert_true(fabs(dist - len) <= len * 0.001 + 2.0);
        }
    }
    assert_int_equal(qnav_atan2_cdeg(0, 0, NULL), 0);
    assert_int_equal(qnav_atan2_cdeg(0, -5000, NULL), -18000);
    assert_int_equal(qnav_atan2_cdeg(5000, 0, NULL), 9000);
    print_message("worst atan2 error %d cdeg\n", worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cos_sin_are_within_two_counts_of_q14_over_the_circle),
        cmocka_unit_test(test_atan2_is_within_one_cdeg_and_length_within_a_permille),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
