/*
 * Unit tests of the policy module and the 3-input network: the one validation, status
 * text, the flat weight order with and without the previous-decision input, the 3-input
 * step (which keeps no hidden state: the previous heading comes in the input) and the
 * literal macros' rounding.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "qnav/ctrl.h"
#include "qnav/fixed_host.h"
#include "qnav/policy.h"
#include "test_rng.h"

static void test_validate_accepts_defaults_and_names_each_broken_rule(void **state)
{
    qnav_policy_t p;
    (void)state;
    qnav_policy_prob_default(&p);
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_OK);
    p.u.prob.k_safe = QNAV_PROB_PARAM_MAX_RAW + 1;
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_E_PROB_PARAM);
    qnav_policy_net_zero_inputs(&p, 5, QNAV_NET_INPUTS_PREV);
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_OK);
    p.u.net.inputs = 1;
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_E_INPUTS);
    p.u.net.inputs = 2;
    p.u.net.hidden = 0;
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_E_HIDDEN);
    p.kind = 0;
    assert_int_equal(qnav_policy_validate(&p), QNAV_POLICY_E_KIND);
    assert_int_equal(qnav_policy_validate(NULL), QNAV_POLICY_E_NULL);
}

static void test_status_text_names_each_status(void **state)
{
    (void)state;
    assert_string_equal(qnav_policy_status_str(QNAV_POLICY_E_INPUTS),
                        "network inputs neither 2 nor 3");
    assert_string_equal(qnav_policy_status_str((qnav_policy_status_t)-77),
                        "unknown policy status");
    assert_string_equal(qnav_status_str(QNAV_OK), "ok");
    assert_string_equal(qnav_status_str(QNAV_E_NO_TABLE),
                        "a 3-input network has no 2-D quality table");
    assert_string_equal(qnav_status_str((qnav_status_t)-99), "unknown status");
}

static void test_three_input_weight_order_puts_w_prev_before_the_bias(void **state)
{
    qnav_policy_t p;
    (void)state;
    qnav_policy_net_zero_inputs(&p, 2, QNAV_NET_INPUTS_PREV);
    assert_int_equal(qnav_net_weight_count(&p.u.net), 11);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 2), &p.u.net.w_prev[0]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 3), &p.u.net.b_hidden[0]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 8), &p.u.net.b_hidden[1]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 9), &p.u.net.w_out[1]);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 10), &p.u.net.b_out);
    assert_null(qnav_net_weight(&p.u.net, 11));
    qnav_policy_net_zero(&p, 2);
    assert_int_equal(qnav_net_weight_count(&p.u.net), 9);
    assert_ptr_equal(qnav_net_weight(&p.u.net, 2), &p.u.net.b_hidden[0]);
}

/* A 3-input network that likes paths near the previous heading and ignores the goal. */
static void init_prev_follower(qnav_ctrl_t *c)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_config_default(&cfg);
    qnav_policy_net_zero_inputs(&p, 1, QNAV_NET_INPUTS_PREV);
    p.u.net.w_prev[0] = QNAV_Q8_8(-8.0);
    p.u.net.w_out[0] = QNAV_Q8_8(8.0);
    assert_int_equal(qnav_ctrl_init(c, &cfg, &p), QNAV_OK);
}

/* 16 clear sectors, goal straight ahead, previous heading prev_cdeg. */
static void clear_scan(qnav_mm_t *ranges, qnav_ctrl_input_t *in, qnav_cdeg_t prev_cdeg)
{
    uint16_t s;
    for (s = 0; s < 16; ++s) {
        ranges[s] = 5000;
    }
    in->ranges_mm = ranges;
    in->goal_bearing_cdeg = 0;
    in->prev_heading_cdeg = prev_cdeg;
}

static void test_three_input_network_turns_towards_the_previous_heading(void **state)
{
    qnav_ctrl_t c;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t out;
    qnav_ctrl_input_t in = {0};
    (void)state;
    init_prev_follower(&c);
    clear_scan(ranges, &in, 4000);
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.heading_deg, 40);
    /* same input, same answer: the step remembers nothing */
    in.prev_heading_cdeg = -9000;
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.heading_deg, -90);
    in.prev_heading_cdeg = 4000;
    qnav_ctrl_step(&c, &in, &out, NULL);
    assert_int_equal(out.heading_deg, 40);
}

static void test_two_input_network_ignores_the_previous_heading(void **state)
{
    qnav_ctrl_t c;
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t a;
    qnav_ctrl_output_t b;
    qnav_ctrl_input_t in = {0};
    uint16_t s;
    (void)state;
    for (s = 0; s < 16; ++s) {
        ranges[s] = (qnav_mm_t)(300u * s + 200u);
    }
    qnav_ctrl_config_default(&cfg);
    qnav_policy_net_zero(&p, 2);
    p.u.net.w_theta[0] = QNAV_Q8_8(-6.0);
    p.u.net.w_dist[1] = QNAV_Q8_8(5.0);
    p.u.net.w_out[0] = QNAV_Q8_8(3.0);
    p.u.net.w_out[1] = QNAV_Q8_8(4.0);
    p.u.net.w_prev[0] = QNAV_Q8_8(50.0); /* not an input of a 2-input network */
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
    in.ranges_mm = ranges;
    in.goal_bearing_cdeg = 3000;
    in.prev_heading_cdeg = 0;
    qnav_ctrl_step(&c, &in, &a, NULL);
    in.prev_heading_cdeg = 17000;
    qnav_ctrl_step(&c, &in, &b, NULL);
    assert_int_equal(a.heading_deg, b.heading_deg);
    assert_int_equal(a.speed, b.speed);
}

static void test_three_input_network_has_no_table_but_network_mode_with_qualities_agrees(void **state)
{
    qnav_ctrl_t c;
    qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_q1_15_t q[QNAV_PATHS];
    qnav_mm_t ranges[16];
    qnav_ctrl_output_t a;
    qnav_ctrl_output_t b;
    qnav_ctrl_input_t in = {0};
    (void)state;
    init_prev_follower(&c);
    assert_int_equal(qnav_ctrl_build_table(&c, table), QNAV_E_NO_TABLE);
    clear_scan(ranges, &in, 4500);
    ranges[2] = 400; /* the previous heading lies in sector 2's blocked wedge */
    qnav_ctrl_step(&c, &in, &a, NULL);
    qnav_ctrl_step(&c, &in, &b, q);
    assert_int_equal(a.heading_deg, b.heading_deg);
    assert_true(q[10] > q[180]); /* nearer the previous heading is better */
}

static void test_q1_15_literal_rounds_negative_values_away_from_zero(void **state)
{
    (void)state;
    assert_int_equal(QNAV_Q1_15(-0.5), -16384);
    assert_int_equal(QNAV_Q1_15(0.5), 16384);
    assert_int_equal(QNAV_Q1_15(-1.0), -32768);
    assert_int_equal(QNAV_Q1_15(1.0), 32767);
    assert_int_equal(QNAV_Q1_15(-0.9), -29491);
    assert_true(QNAV_Q1_15_TO_REAL(16384) == 0.5);
}

/* A table's rows are built a row at a time (on hosts by each unit's flat ranges, elsewhere
 * by eval_run); each key must be the one the step evaluates for that single path. Random
 * networks of every width and of weights from small to the Q8.8 limits, so that units lie
 * on either flat end, between them, or cross them along a row either way. */
static void test_every_table_key_is_the_single_paths_key(void **state)
{
    static const int32_t scales[] = {64, 512, 4096, 32767};
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    qnav_ctrl_t c;
    (void)state;
    qnav_ctrl_config_default(&cfg);
    for (unsigned k = 0; k < 40u; ++k) {
        const uint8_t hidden = (uint8_t)(1u + k % QNAV_MAX_HIDDEN);
        qnav_policy_net_zero_inputs(&p, hidden, QNAV_NET_INPUTS_PAPER);
        for (uint16_t w = 0; w < qnav_net_weight_count(&p.u.net); ++w) {
            const int32_t s = scales[k % 4u];
            *qnav_net_weight(&p.u.net, w) = (qnav_q8_8_t)rng_range(-s, s);
        }
        assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
        assert_int_equal(qnav_ctrl_build_table(&c, table), QNAV_OK);
        for (uint16_t level = 0; level < QNAV_DIST_LEVELS; ++level) {
            for (uint16_t d = 0; d <= QNAV_DTHETA_MAX; ++d) {
                assert_int_equal(table[level * (QNAV_DTHETA_MAX + 1u) + d],
                                 qnav_ctrl_key(&c, (uint8_t)level, (uint8_t)d));
            }
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_validate_accepts_defaults_and_names_each_broken_rule),
        cmocka_unit_test(test_status_text_names_each_status),
        cmocka_unit_test(test_three_input_weight_order_puts_w_prev_before_the_bias),
        cmocka_unit_test(test_three_input_network_turns_towards_the_previous_heading),
        cmocka_unit_test(test_two_input_network_ignores_the_previous_heading),
        cmocka_unit_test(test_three_input_network_has_no_table_but_network_mode_with_qualities_agrees),
        cmocka_unit_test(test_q1_15_literal_rounds_negative_values_away_from_zero),
        cmocka_unit_test(test_every_table_key_is_the_single_paths_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
