/*
 * Round trip of every qnav LCM type through an in-process LCM bus (memq://): publish a
 * message with distinctive values in every field, receive it through the generated
 * subscribe function, and compare field by field. Nothing leaves the process.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>
#include <lcm/lcm.h>

#include "qnav_command_t.h"
#include "qnav_goal_t.h"
#include "qnav_link_status_t.h"
#include "qnav_nav_input_t.h"
#include "qnav_path_qualities_t.h"
#include "qnav_pose_t.h"
#include "qnav_scan_t.h"

static lcm_t *bus(void)
{
    lcm_t *lcm = lcm_create("memq://");
    assert_non_null(lcm);
    return lcm;
}

/* Deliver one queued message; fail if none arrives within a second. */
static void deliver(lcm_t *lcm)
{
    assert_int_equal(lcm_handle_timeout(lcm, 1000), 1);
}

/* For type T: got_T and n_T hold what the subscriber received, and round_trip_T(m, ch)
 * publishes m on ch of a fresh memq:// bus and delivers it to that subscriber once. */
#define DEFINE_CATCHER(T)                                                                   \
    static T got_##T;                                                                       \
    static int n_##T;                                                                       \
    static void on_##T(const lcm_recv_buf_t *rbuf, const char *ch, const T *msg, void *u)   \
    {                                                                                       \
        (void)rbuf;                                                                         \
        (void)ch;                                                                           \
        (void)u;                                                                            \
        got_##T = *msg;                                                                     \
        n_##T++;                                                                            \
    }                                                                                       \
    static void round_trip_##T(const T *m, const char *ch)                                  \
    {                                                                                       \
        lcm_t *lcm = bus();                                                                 \
        T##_subscription_t *sub = T##_subscribe(lcm, ch, on_##T, NULL);                     \
        assert_int_equal(T##_publish(lcm, ch, m), 0);                                       \
        deliver(lcm);                                                                       \
        assert_int_equal(n_##T, 1);                                                         \
        T##_unsubscribe(lcm, sub);                                                          \
        lcm_destroy(lcm);                                                                   \
    }

DEFINE_CATCHER(qnav_scan_t)
DEFINE_CATCHER(qnav_goal_t)
DEFINE_CATCHER(qnav_command_t)
DEFINE_CATCHER(qnav_path_qualities_t)
DEFINE_CATCHER(qnav_pose_t)
DEFINE_CATCHER(qnav_link_status_t)
DEFINE_CATCHER(qnav_nav_input_t)

static void test_scan_round_trips_over_memq(void **state)
{
    qnav_scan_t m;
    int k;
    (void)state;
    memset(&m, 0, sizeof m);
    m.utime = 1700000000123456LL;
    m.seq = 65535;
    m.board_ms = 4294967295LL;
    m.n_sectors = 360;
    m.max_range_mm = 5000;
    m.goal_bearing_cdeg = -17999;
    m.goal_id = 7;
    for (k = 0; k < 360; ++k) {
        m.ranges_mm[k] = 65535 - k;
    }
    round_trip_qnav_scan_t(&m, "QNAV_SCAN");
    assert_memory_equal(&got_qnav_scan_t, &m, sizeof m);
}

static void test_goal_round_trips_over_memq(void **state)
{
    qnav_goal_t m = {123, 65535, 9000, 2000000};
    (void)state;
    round_trip_qnav_goal_t(&m, "QNAV_GOAL");
    assert_int_equal(got_qnav_goal_t.goal_id, 65535);
    assert_int_equal(got_qnav_goal_t.bearing_cdeg, 9000);
    assert_int_equal(got_qnav_goal_t.distance_mm, 2000000);
}

static void test_command_round_trips_over_memq(void **state)
{
    qnav_command_t m;
    (void)state;
    memset(&m, 0, sizeof m);
    m.utime = 5;
    m.scan_seq = 1234;
    m.heading_deg = -179;
    m.speed_q15 = 32767;
    m.quality_q15 = 16384;
    m.speed = 32767.0 / 32768.0;
    m.quality = 0.5;
    m.flags = 8;
    m.stop_reason = 1;
    m.source = 2;
    m.policy_crc = 0xBEEF;
    round_trip_qnav_command_t(&m, "QNAV_COMMAND");
    assert_int_equal(got_qnav_command_t.heading_deg, -179);
    assert_int_equal(got_qnav_command_t.speed_q15, 32767);
    assert_int_equal(got_qnav_command_t.quality_q15, 16384);
    assert_true(got_qnav_command_t.quality == 0.5);
    assert_int_equal(got_qnav_command_t.flags, 8);
    assert_int_equal(got_qnav_command_t.stop_reason, 1);
    assert_int_equal(got_qnav_command_t.source, 2);
    assert_int_equal(got_qnav_command_t.policy_crc, 0xBEEF);
}

static void test_path_qualities_round_trip_all_360_over_memq(void **state)
{
    static qnav_path_qualities_t m;
    int k;
    (void)state;
    m.utime = 9;
    m.scan_seq = 77;
    m.best_deg = 45;
    for (k = 0; k < 360; ++k) {
        m.quality_q15[k] = (int16_t)(k * 91);
        m.quality[k] = (float)k / 360.0f;
    }
    round_trip_qnav_path_qualities_t(&m, "QNAV_QUALITIES");
    assert_memory_equal(&got_qnav_path_qualities_t, &m, sizeof m);
}

static void test_pose_round_trips_over_memq(void **state)
{
    qnav_pose_t m;
    (void)state;
    memset(&m, 0, sizeof m);
    m.utime = 11;
    m.tick = 300;
    m.x_m = 1.25;
    m.y_m = -3.5;
    m.heading_deg = 179.5;
    m.speed_mps = 0.75;
    m.goal_distance_m = 2.0;
    m.recovering = 1;
    m.collisions = 3;
    m.reached = 0;
    round_trip_qnav_pose_t(&m, "QNAV_POSE");
    assert_memory_equal(&got_qnav_pose_t, &m, sizeof m);
}

static void test_link_status_round_trips_over_memq(void **state)
{
    qnav_link_status_t m;
    (void)state;
    memset(&m, 0, sizeof m);
    m.utime = 13;
    m.mode = 2;
    m.rx_frames = 1LL << 40;
    m.tx_frames = 99;
    m.rx_bytes = 12345;
    m.drop_cobs = 1;
    m.drop_short = 2;
    m.drop_overflow = 3;
    m.drop_crc = 4;
    m.drop_unknown = 5;
    m.drop_length = 6;
    m.drop_seq = 7;
    m.seq_gaps = 8;
    m.last_heartbeat_age_ms = 120;
    m.last_scan_age_ms = -1;
    m.watchdog_stop = 1;
    m.board_rx_ok = 65535;
    m.board_rx_dropped = 9;
    m.board_state = 5;
    m.board_policy_crc = 0x1234;
    m.last_upload_status = -2;
    round_trip_qnav_link_status_t(&m, "QNAV_LINK_STATUS");
    assert_memory_equal(&got_qnav_link_status_t, &m, sizeof m);
}

static void test_decoder_refuses_truncated_buffer(void **state)
{
    qnav_command_t m, out;
    uint8_t buf[256];
    int n;
    (void)state;
    memset(&m, 0, sizeof m);
    n = qnav_command_t_encode(buf, 0, (int)sizeof buf, &m);
    assert_int_equal(n, qnav_command_t_encoded_size(&m));
    assert_true(qnav_command_t_decode(buf, 0, n - 1, &out) < 0);
    assert_int_equal(qnav_command_t_decode(buf, 0, n, &out), n);
}

static void test_nav_input_round_trips_over_memq(void **state)
{
    qnav_nav_input_t m;
    (void)state;
    memset(&m, 0, sizeof m);
    m.utime = 1700000000123456LL;
    m.scan_seq = 65535;
    m.goal_id = 65535;
    m.goal_range_mm = 65535;
    m.prev_heading_cdeg = -17999;
    m.escape_clear = 1;
    m.escape_grow_mm = 65535;
    m.config_crc = -1;
    round_trip_qnav_nav_input_t(&m, "QNAV_NAV_INPUT");
    assert_int_equal(got_qnav_nav_input_t.utime, m.utime);
    assert_int_equal(got_qnav_nav_input_t.scan_seq, 65535);
    assert_int_equal(got_qnav_nav_input_t.goal_id, 65535);
    assert_int_equal(got_qnav_nav_input_t.goal_range_mm, 65535);
    assert_int_equal(got_qnav_nav_input_t.prev_heading_cdeg, -17999);
    assert_int_equal(got_qnav_nav_input_t.escape_clear, 1);
    assert_int_equal(got_qnav_nav_input_t.escape_grow_mm, 65535);
    assert_int_equal(got_qnav_nav_input_t.config_crc, -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scan_round_trips_over_memq),
        cmocka_unit_test(test_goal_round_trips_over_memq),
        cmocka_unit_test(test_command_round_trips_over_memq),
        cmocka_unit_test(test_path_qualities_round_trip_all_360_over_memq),
        cmocka_unit_test(test_pose_round_trips_over_memq),
        cmocka_unit_test(test_link_status_round_trips_over_memq),
        cmocka_unit_test(test_nav_input_round_trips_over_memq),
        cmocka_unit_test(test_decoder_refuses_truncated_buffer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
