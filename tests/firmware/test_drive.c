/*
 * libqnav's mixer (qnav/drive.h): a decision as two wheel speeds, the forward part by the
 * heading's cosine, one factor for both parts at a wheel's limit (the arc kept), a brake
 * before a turn in place while the robot rolls, and the rolling speed from encoder travel.
 */
#define _DEFAULT_SOURCE
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include <cmocka.h>

#include "qnav/drive.h"

static void mix(int h, int speed, int rolling, qnav_q1_15_t *l, qnav_q1_15_t *r)
{
    qnav_drive_mix((qnav_deg_t)h, (qnav_q1_15_t)speed, (qnav_q1_15_t)rolling, 90, l, r);
}

static void test_a_counter_clockwise_heading_runs_the_right_wheel_faster(void **state)
{
    qnav_q1_15_t l, r;
    (void)state;
    mix(30, 20000, 0, &l, &r);
    assert_true(r > l);
    mix(-30, 20000, 0, &l, &r);
    assert_true(l > r);
    mix(0, 20000, 0, &l, &r);
    assert_int_equal(l, 20000);
    assert_int_equal(r, 20000);
    mix(0, 0, 0, &l, &r); /* no speed, no heading: no motion at all */
    assert_int_equal(l, 0);
    assert_int_equal(r, 0);
}

/* The mean of the wheels is speed * cos(heading) below a wheel's limit, their difference
 * heading / 90 of full speed; at 90 deg and beyond, and at speed 0, a turn in place. */
static void test_forward_falls_with_the_cosine_and_the_turn_with_the_heading(void **state)
{
    int h;
    qnav_q1_15_t l, r;
    (void)state;
    for (h = -180; h <= 180; ++h) {
        int mag = abs(h);
        double want_fwd = mag >= 90 ? 0.0 : 12000.0 * cos(mag * M_PI / 180.0);
        double want_turn = (mag >= 90 ? 32767.0 : 32767.0 * mag / 90.0) * (h < 0 ? -1 : 1);
        mix(h, 12000, 0, &l, &r);
        if (want_fwd + fabs(want_turn) <= 32767.0) {
            assert_true(fabs((l + r) / 2.0 - want_fwd) <= 3.0);
            assert_true(fabs((r - l) / 2.0 - want_turn) <= 2.0);
        }
        if (mag >= 90) {
            assert_int_equal(l, -r);
        }
        mix(h, 0, 0, &l, &r); /* no speed: a turn in place toward the heading */
        assert_int_equal(l, -r);
        assert_true(h > 0 ? r > 0 : (h < 0 ? l > 0 : r == 0));
    }
}

/* Past a wheel's limit both parts shrink by one factor: the faster wheel at full speed,
 * the ratio of turn to forward (the arc) as below the limit. */
static void test_at_a_wheels_limit_the_arc_is_kept(void **state)
{
    int h;
    qnav_q1_15_t l, r;
    (void)state;
    for (h = 1; h < 90; ++h) {
        double fwd = 32767.0 * cos(h * M_PI / 180.0);
        double turn = 32767.0 * h / 90.0;
        mix(h, 32767, 0, &l, &r);
        assert_true(r <= 32767 && l >= -32767);
        if (fwd + turn > 32767.0) {
            double got = (r - l) / (double)(r + l);
            /* the cosine's 2/16384 and two counts of truncation in each part, relative */
            double tol = (2.0 / 16384.0 / cos(h * M_PI / 180.0) + 4.0 / (r + l) + 4.0 / (r - l));
            assert_true(r >= 32765);
            if (fabs(got - turn / fwd) > tol * turn / fwd) {
                print_message("heading %d: turn/forward %.4f, want %.4f\n", h, got, turn / fwd);
            }
            assert_true(fabs(got - turn / fwd) <= tol * turn / fwd);
        }
    }
}

/* A turn in place while the robot still rolls forward at all brakes both wheels first,
 * then turns once it has stopped; rolling backward does not brake. Slower than the servo's
 * QNAV_DRIVE_STOPPED is not stopped: a robot that brakes slowly crept on (0.20.1). */
static void test_a_turn_in_place_brakes_first_while_the_robot_rolls(void **state)
{
    qnav_q1_15_t l, r;
    (void)state;
    mix(120, 32767, QNAV_DRIVE_STOPPED + 1, &l, &r); /* beyond 90 deg */
    assert_int_equal(l, 0);
    assert_int_equal(r, 0);
    mix(-45, 0, 30000, &l, &r); /* speed 0 */
    assert_int_equal(l, 0);
    assert_int_equal(r, 0);
    mix(-45, 0, QNAV_DRIVE_STOPPED, &l, &r);
    assert_int_equal(l, 0);
    assert_int_equal(r, 0);
    mix(-45, 0, 1, &l, &r); /* the least a board's encoders count */
    assert_int_equal(l, 0);
    assert_int_equal(r, 0);
    mix(-45, 0, 0, &l, &r);
    assert_true(l > 0);
    assert_int_equal(l, -r);
    mix(120, 0, -20000, &l, &r);
    assert_true(r > 0);
    assert_int_equal(l, -r);
    mix(30, 20000, 30000, &l, &r); /* a forward part: no brake, an arc */
    assert_true(r > l && l > 0);
}

/* The turn part reaches full wheel speed at turn_full_deg: at 180 (a robot twice as fast
 * as one at 90, on the same track) every heading below 90 deg asks half the turn part it
 * asks at 90, so both turn at the same rate; 0 is taken as 1 (full at any heading). */
static void test_the_turn_is_full_at_turn_full_deg(void **state)
{
    int h;
    qnav_q1_15_t l90, r90, l180, r180;
    (void)state;
    for (h = -180; h <= 180; ++h) {
        qnav_drive_mix((qnav_deg_t)h, 0, 0, 90, &l90, &r90);
        qnav_drive_mix((qnav_deg_t)h, 0, 0, 180, &l180, &r180);
        assert_int_equal(r180, (h < 0 ? -1 : 1) * (32767 * abs(h) / 180));
        if (abs(h) < 90) {
            assert_true(abs(r180 - r90 / 2) <= 1);
        }
        assert_int_equal(l180, -r180);
    }
    qnav_drive_mix(180, 0, 0, 180, &l180, &r180);
    assert_int_equal(r180, 32767);
    qnav_drive_mix(1, 0, 0, 0, &l90, &r90);
    assert_int_equal(r90, 32767);
    qnav_drive_mix(-30, 0, 0, 360, &l90, &r90);
    assert_int_equal(l90, 32767 * 30 / 360);
}

/* qnav_drive_servo_brakes_first(): a turn back (90 deg and beyond either way) while the
 * robot rolls faster than QNAV_DRIVE_STOPPED, and nothing else, whatever the speed asked. */
static void test_a_servo_brakes_first_only_to_turn_back(void **state)
{
    static const int rolls[] = {-32767, 0, QNAV_DRIVE_STOPPED, QNAV_DRIVE_STOPPED + 1, 32767};
    int h, k, braked = 0;
    (void)state;
    for (h = -180; h <= 180; ++h) {
        for (k = 0; k < (int)(sizeof rolls / sizeof rolls[0]); ++k) {
            const int b = qnav_drive_servo_brakes_first((qnav_deg_t)h, (qnav_q1_15_t)rolls[k]);
            assert_int_equal(b, (h >= 90 || h <= -90) && rolls[k] > QNAV_DRIVE_STOPPED);
            braked += b;
        }
    }
    assert_int_equal(braked, 2 * 182); /* 91 headings each side, two rolling speeds */
}

/* qnav_drive_brakes_first() is the mixer's own brake: for every heading, several speeds
 * and rolling speeds either side of a stop, it says 1 exactly when the mixer stops both
 * wheels of a robot that rolls, and never for one that does not. */
static void test_brakes_first_is_when_the_mixer_brakes(void **state)
{
    static const int speeds[] = {0, 1, 2, 100, 12000, 32767};
    static const int rolls[] = {-32767, 0, 1, QNAV_DRIVE_STOPPED, 32767};
    int h, s, k, braked = 0;
    qnav_q1_15_t l, r;
    (void)state;
    for (h = -180; h <= 180; ++h) {
        for (s = 0; s < (int)(sizeof speeds / sizeof speeds[0]); ++s) {
            for (k = 0; k < (int)(sizeof rolls / sizeof rolls[0]); ++k) {
                const int b = qnav_drive_brakes_first((qnav_deg_t)h, (qnav_q1_15_t)speeds[s],
                                                      (qnav_q1_15_t)rolls[k]);
                mix(h, speeds[s], rolls[k], &l, &r);
                if (rolls[k] > 0) {
                    assert_int_equal(b, l == 0 && r == 0);
                } else {
                    assert_int_equal(b, 0);
                }
                braked += b;
            }
        }
    }
    /* at the three rolling speeds forward: the 182 headings at 90 deg and beyond at
     * every speed; the 179 others at speed 0; at speed 1 those but straight ahead (1 x cos
     * rounds to nothing); at speed 2 the 58 beyond 60 deg (cos below one half) */
    assert_int_equal(braked, 3 * (182 * 6 + 179 + 178 + 58));
}

static void test_rolling_is_the_travel_as_a_fraction_of_full_speed(void **state)
{
    (void)state;
    /* 0.5 m/s, 100 ms: 50 000 um a tick is full speed */
    assert_int_equal(qnav_drive_rolling(50000, 100, 500), 32767);
    assert_int_equal(qnav_drive_rolling(25000, 100, 500), 16383);
    assert_int_equal(qnav_drive_rolling(-25000, 100, 500), -16383);
    assert_int_equal(qnav_drive_rolling(6250, 100, 500), 4095);
    assert_int_equal(qnav_drive_rolling(0, 100, 500), 0);
    assert_int_equal(qnav_drive_rolling(900000, 100, 500), 32767); /* saturated */
    assert_int_equal(qnav_drive_rolling(INT32_MIN, 100, 500), -32767);
    assert_int_equal(qnav_drive_rolling(1000, 0, 500), 0);
    assert_int_equal(qnav_drive_rolling(1000, 100, 0), 0);
    /* a full tick's travel above 65 535 um (1.5 m/s): within one part in 2^15 */
    assert_true(abs(qnav_drive_rolling(75000, 100, 1500) - 16383) <= 1);
    assert_true(abs(qnav_drive_rolling(-149999, 1000, 1500) + 3276) <= 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_counter_clockwise_heading_runs_the_right_wheel_faster),
        cmocka_unit_test(test_forward_falls_with_the_cosine_and_the_turn_with_the_heading),
        cmocka_unit_test(test_at_a_wheels_limit_the_arc_is_kept),
        cmocka_unit_test(test_a_turn_in_place_brakes_first_while_the_robot_rolls),
        cmocka_unit_test(test_brakes_first_is_when_the_mixer_brakes),
        cmocka_unit_test(test_a_servo_brakes_first_only_to_turn_back),
        cmocka_unit_test(test_the_turn_is_full_at_turn_full_deg),
        cmocka_unit_test(test_rolling_is_the_travel_as_a_fraction_of_full_speed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
