/*
 * Tests of headers made by `qnav-policy header` (generated at build time from the files in
 * tests/policyio/good/ and compiled here with warnings as errors): the policy in a header
 * is the policy in its file, a table header equals the table the library builds, and a
 * controller running the table gives the same decisions and all 360 qualities as one
 * running the policy itself, scan after scan.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "qnav/ctrl.h"
#include "qnav/policy_io.h"

#include "net12_policy.h"
#include "net12_table.h"
#include "prob_policy.h"
#include "prob_table.h"

static uint32_t rng = 2463534242u;

static uint32_t xorshift32(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return rng;
}

static void assert_header_policy_matches_file(const qnav_policy_t *from_header,
                                              const char *file)
{
    qnav_policy_t from_file;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    if (qnav_policy_read(file, &from_file, err, sizeof err) != 0) {
        fail_msg("%s", err);
    }
    assert_true(qnav_policy_equal(from_header, &from_file));
}

static void assert_table_matches_library(const qnav_policy_t *policy, const qnav_qkey_t *table)
{
    static qnav_qkey_t built[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_t ctrl;
    qnav_ctrl_config_t cfg;
    qnav_ctrl_config_default(&cfg);
    assert_int_equal(qnav_ctrl_init(&ctrl, &cfg, policy), QNAV_OK);
    assert_int_equal(qnav_ctrl_build_table(&ctrl, built), QNAV_OK);
    assert_memory_equal(built, table, sizeof built);
}

/* Steps a policy controller and a table controller on the same random scans; every
 * output field and every path quality must agree. Returns how many distinct headings the
 * scans produced, so the caller can check the scans were not all alike. */
static int assert_table_mode_equals_policy_mode(const qnav_policy_t *policy,
                                                const qnav_qkey_t *table)
{
    static const uint16_t sector_counts[] = {8, 16, 32, 180};
    int headings_seen[360] = {0};
    int distinct = 0;
    size_t s;
    for (s = 0; s < sizeof sector_counts / sizeof sector_counts[0]; ++s) {
        qnav_ctrl_config_t cfg;
        qnav_ctrl_t by_policy;
        qnav_ctrl_t by_table;
        int scan;
        qnav_ctrl_config_default(&cfg);
        cfg.n_sectors = sector_counts[s];
        cfg.max_range_mm = 4000;
        assert_int_equal(qnav_ctrl_init(&by_policy, &cfg, policy), QNAV_OK);
        assert_int_equal(qnav_ctrl_init_table(&by_table, &cfg, table, qnav_ctrl_rank(&by_policy)), QNAV_OK);
        for (scan = 0; scan < 25; ++scan) {
            qnav_mm_t ranges[QNAV_MAX_SECTORS];
            qnav_q1_15_t qa[QNAV_PATHS];
            qnav_q1_15_t qb[QNAV_PATHS];
            qnav_ctrl_input_t in = {0};
            qnav_ctrl_output_t a;
            qnav_ctrl_output_t b;
            uint16_t i;
            for (i = 0; i < cfg.n_sectors; ++i) {
                /* some sectors beyond max range, to exercise clipping too */
                ranges[i] = (qnav_mm_t)(xorshift32() % 4600u);
            }
            in.ranges_mm = ranges;
            in.goal_bearing_cdeg = (qnav_cdeg_t)((int32_t)(xorshift32() % 36000u) - 18000);
            qnav_ctrl_step(&by_policy, &in, &a, qa);
            qnav_ctrl_step(&by_table, &in, &b, qb);
            assert_int_equal(a.heading_deg, b.heading_deg);
            assert_int_equal(a.speed, b.speed);
            assert_int_equal(a.quality, b.quality);
            assert_int_equal(a.flags, b.flags);
            assert_memory_equal(qa, qb, sizeof qa);
            assert_true(a.heading_deg >= -179 && a.heading_deg <= 180);
            if (!headings_seen[a.heading_deg + 179]) {
                headings_seen[a.heading_deg + 179] = 1;
                distinct++;
            }
        }
    }
    return distinct;
}

static void test_network_header_holds_the_policy_of_its_file(void **state)
{
    (void)state;
    assert_int_equal(net12_policy.kind, QNAV_POLICY_NET);
    assert_int_equal(net12_policy.u.net.hidden, 12);
    assert_int_equal(net12_policy.u.net.w_out[0], 2048);
    assert_header_policy_matches_file(&net12_policy, QNAV_POLICYIO_GOOD_DIR "/net12.policy");
}

static void test_probabilistic_header_holds_the_policy_of_its_file(void **state)
{
    (void)state;
    assert_int_equal(prob_policy.kind, QNAV_POLICY_PROB);
    assert_header_policy_matches_file(&prob_policy, QNAV_POLICYIO_GOOD_DIR "/prob.policy");
}

static void test_table_headers_equal_the_tables_the_library_builds(void **state)
{
    (void)state;
    assert_int_equal(sizeof net12_table / sizeof net12_table[0], QNAV_QTABLE_ENTRIES);
    assert_table_matches_library(&net12_policy, net12_table);
    assert_table_matches_library(&prob_policy, prob_table);
}

static void test_network_table_header_steps_like_network_mode(void **state)
{
    (void)state;
    assert_true(assert_table_mode_equals_policy_mode(&net12_policy, net12_table) > 5);
}

static void test_probabilistic_table_header_steps_like_probabilistic_mode(void **state)
{
    (void)state;
    assert_true(assert_table_mode_equals_policy_mode(&prob_policy, prob_table) > 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_network_header_holds_the_policy_of_its_file),
        cmocka_unit_test(test_probabilistic_header_holds_the_policy_of_its_file),
        cmocka_unit_test(test_table_headers_equal_the_tables_the_library_builds),
        cmocka_unit_test(test_network_table_header_steps_like_network_mode),
        cmocka_unit_test(test_probabilistic_table_header_steps_like_probabilistic_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
