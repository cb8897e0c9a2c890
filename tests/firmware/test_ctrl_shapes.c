/*
 * Carried row shapes (firmware/src/ctrl_shapes.c): a controller initialised with the row
 * shapes its policy carries is the controller that computes them, bit for bit, and decides
 * alike; shapes that are not the policy's (corrupted, another policy's, another rank's,
 * out of range) are ignored and computed; a well-formed summary that lies (forged check)
 * never makes the step fail or read out of bounds. Over random networks and the
 * benchmark's fixture policies (bench/fixtures/policies).
 */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "qnav/ctrl.h"
#include "qnav/policy_io.h"
#include "runs.h"
#include "test_rng.h"

#define SCANS 40
#define SECTORS 32

static void random_net(qnav_policy_t *p, uint8_t hidden)
{
    uint16_t k;
    qnav_policy_net_zero(p, hidden);
    for (k = 0; k < qnav_net_weight_count(&p->u.net); ++k) {
        /* wide weights give steep, saturating units: plateaus and several peaks */
        *qnav_net_weight(&p->u.net, k) = (qnav_q8_8_t)rng_range(-32768, 32767);
    }
}

static void config(qnav_ctrl_config_t *cfg)
{
    qnav_ctrl_config_default(cfg);
    cfg->n_sectors = SECTORS;
}

/* The shapes record of policy under cfg, written from a controller that computed them. */
static void save_shapes(const qnav_ctrl_config_t *cfg, const qnav_policy_t *p, uint8_t *rec)
{
    qnav_ctrl_t c;
    assert_int_equal(qnav_ctrl_init(&c, cfg, p), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(&c), 0);
    assert_int_equal(qnav_ctrl_shapes_save(&c, p, rec), QNAV_OK);
}

static void random_scan(qnav_mm_t *r, qnav_ctrl_input_t *in)
{
    unsigned i;
    memset(in, 0, sizeof *in);
    for (i = 0; i < SECTORS; ++i) {
        r[i] = (qnav_mm_t)(rng_u32() % 4u == 0u ? 5000 : rng_range(100, 5000));
    }
    in->ranges_mm = r;
    in->goal_bearing_cdeg = (qnav_cdeg_t)rng_range(-18000, 17999);
}

/* Every field of two outputs (not memcmp: the structs have padding). */
static void assert_same_output(const qnav_ctrl_output_t *a, const qnav_ctrl_output_t *b)
{
    assert_int_equal(a->heading_deg, b->heading_deg);
    assert_int_equal(a->speed, b->speed);
    assert_int_equal(a->quality, b->quality);
    assert_int_equal(a->flags, b->flags);
    assert_int_equal(a->escape.best_mm, b->escape.best_mm);
    assert_int_equal(a->escape.hit_mm, b->escape.hit_mm);
    assert_int_equal(a->escape.ticks, b->escape.ticks);
    assert_int_equal(a->escape.side, b->escape.side);
    assert_int_equal(a->escape.last_side, b->escape.last_side);
    assert_int_equal(a->escape.tries, b->escape.tries);
    assert_int_equal(a->escape.stall_mm, b->escape.stall_mm);
    assert_int_equal(a->escape.near_mm, b->escape.near_mm);
    assert_int_equal(a->escape.loop_mm, b->escape.loop_mm);
    assert_int_equal(a->escape.loop_deg2, b->escape.loop_deg2);
    assert_int_equal(a->escape.loop, b->escape.loop);
    assert_int_equal(a->escape.from_mm, b->escape.from_mm);
    assert_int_equal(a->escape.over_mm, b->escape.over_mm);
    assert_int_equal(a->escape.prev_mm, b->escape.prev_mm);
}

/* a and b decide alike on SCANS scans: every output field and every path's quality. */
static void assert_same_decisions(const qnav_ctrl_t *a, const qnav_ctrl_t *b)
{
    qnav_mm_t r[SECTORS];
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t oa, ob;
    qnav_q1_15_t qa[QNAV_PATHS], qb[QNAV_PATHS];
    unsigned s;
    for (s = 0; s < SCANS; ++s) {
        random_scan(r, &in);
        qnav_ctrl_step(a, &in, &oa, NULL);
        qnav_ctrl_step(b, &in, &ob, NULL);
        assert_same_output(&oa, &ob);
        qnav_ctrl_step(a, &in, &oa, qa);
        qnav_ctrl_step(b, &in, &ob, qb);
        assert_memory_equal(qa, qb, sizeof qa);
    }
}

/* Carried and computed: same rows, same decisions; the carried init took them. */
static void assert_carried_is_computed(const qnav_policy_t *p)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_t computed, carried;
    uint8_t rec[QNAV_SHAPES_BYTES];
    config(&cfg);
    save_shapes(&cfg, p, rec);
    assert_int_equal(qnav_ctrl_init(&computed, &cfg, p), QNAV_OK);
    assert_int_equal(qnav_ctrl_init_carried(&carried, &cfg, p, rec, sizeof rec), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(&carried), 1);
    assert_memory_equal(carried.p.net.in.row, computed.p.net.in.row,
                        sizeof computed.p.net.in.row);
    assert_same_decisions(&carried, &computed);
}

static void test_carried_shapes_decide_as_computed_ones_on_random_networks(void **state)
{
    qnav_policy_t p;
    unsigned i;
    (void)state;
    for (i = 0; i < 60u; ++i) {
        random_net(&p, (uint8_t)(1u + i % QNAV_MAX_HIDDEN));
        assert_carried_is_computed(&p);
    }
}

static void test_carried_shapes_decide_as_computed_ones_on_the_fixture_policies(void **state)
{
    DIR *dir = opendir(QNAV_FIXTURE_POLICIES);
    struct dirent *e;
    unsigned nets = 0;
    (void)state;
    assert_non_null(dir);
    while ((e = readdir(dir)) != NULL) {
        char path[1024], err[QNAV_POLICY_IO_ERRLEN];
        qnav_policy_t p;
        size_t n = strlen(e->d_name);
        if (n < 8 || strcmp(e->d_name + n - 7, ".policy") != 0) {
            continue;
        }
        snprintf(path, sizeof path, "%s/%s", QNAV_FIXTURE_POLICIES, e->d_name);
        assert_int_equal(qnav_policy_read(path, &p, err, sizeof err), 0);
        if (p.kind == QNAV_POLICY_NET && p.u.net.inputs == QNAV_NET_INPUTS_PAPER &&
            p.u.net.hidden <= QNAV_MAX_HIDDEN) {
            assert_carried_is_computed(&p);
            ++nets;
        }
    }
    closedir(dir);
    assert_true(nets >= 17u);
}

/* init_carried with rec (len bytes) ignores it: computed rows, status OK. */
static void assert_ignored(const qnav_ctrl_config_t *cfg, const qnav_policy_t *p,
                           const uint8_t *rec, uint16_t len)
{
    qnav_ctrl_t c, computed;
    assert_int_equal(qnav_ctrl_init_carried(&c, cfg, p, rec, len), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(&c), 0);
    assert_int_equal(qnav_ctrl_init(&computed, cfg, p), QNAV_OK);
    assert_memory_equal(c.p.net.in.row, computed.p.net.in.row, sizeof c.p.net.in.row);
}

static void test_every_flipped_bit_of_carried_shapes_is_refused(void **state)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    uint8_t rec[QNAV_SHAPES_BYTES];
    unsigned k, b;
    (void)state;
    config(&cfg);
    random_net(&p, 6u);
    save_shapes(&cfg, &p, rec);
    for (k = 0; k < sizeof rec; ++k) {
        for (b = 0; b < 8u; ++b) {
            rec[k] ^= (uint8_t)(1u << b);
            assert_ignored(&cfg, &p, rec, sizeof rec);
            rec[k] ^= (uint8_t)(1u << b);
        }
    }
}

static void test_shapes_of_another_policy_rank_or_length_are_refused(void **state)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t p, q;
    uint8_t rec[QNAV_SHAPES_BYTES];
    (void)state;
    config(&cfg);
    random_net(&p, 8u);
    q = p;
    q.u.net.w_out[3] = (qnav_q8_8_t)(q.u.net.w_out[3] ^ 1); /* one weight differs by 1/256 */
    save_shapes(&cfg, &q, rec);
    assert_ignored(&cfg, &p, rec, sizeof rec);
    save_shapes(&cfg, &p, rec);
    assert_ignored(&cfg, &p, rec, (uint16_t)(sizeof rec - 1u));
    assert_ignored(&cfg, &p, NULL, sizeof rec);
    cfg.rank = QNAV_RANK_QUALITY; /* written for pre-activation keys */
    assert_ignored(&cfg, &p, rec, sizeof rec);
}

/* A record for p whose check is right but whose row `level` says what edit() makes of it
 * (qnav_ctrl_shapes_save writes whatever rows the controller holds). */
static void forged(const qnav_ctrl_config_t *cfg, const qnav_policy_t *p, uint8_t level,
                   void (*edit)(qnav_row_shape_t *), uint8_t *rec)
{
    qnav_ctrl_t c;
    assert_int_equal(qnav_ctrl_init(&c, cfg, p), QNAV_OK);
    edit(&c.p.net.in.row[level]);
    assert_int_equal(qnav_ctrl_shapes_save(&c, p, rec), QNAV_OK);
}

static void top_d_past_180(qnav_row_shape_t *s) { s->top_d = 181u; s->fall_d = 181u; }
static void fall_before_top(qnav_row_shape_t *s) { s->top_d = 9u; s->fall_d = 3u; }
static void peak_past_179(qnav_row_shape_t *s) { s->peak_lo = 100u; s->peak_hi = 180u; }
static void peak_upside_down(qnav_row_shape_t *s) { s->peak_lo = 50u; s->peak_hi = 40u; }
static void peak_at_0(qnav_row_shape_t *s) { s->peak_lo = 0u; s->peak_hi = 3u; }
static void top_off_by_one(qnav_row_shape_t *s) { s->top = (qnav_qkey_t)(s->top + 1); }

static void test_well_checked_shapes_out_of_range_or_off_the_network_are_refused(void **state)
{
    void (*edits[])(qnav_row_shape_t *) = {top_d_past_180, fall_before_top, peak_past_179,
                                           peak_upside_down, peak_at_0, top_off_by_one};
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    uint8_t rec[QNAV_SHAPES_BYTES];
    unsigned i;
    (void)state;
    config(&cfg);
    random_net(&p, 5u);
    for (i = 0; i < sizeof edits / sizeof edits[0]; ++i) {
        forged(&cfg, &p, (uint8_t)(i * 5u % QNAV_DIST_LEVELS), edits[i], rec);
        assert_ignored(&cfg, &p, rec, sizeof rec);
    }
}

/* A lie the load cannot see: fields in range, the top where the network has it, the
 * rest random. */
static void lie(qnav_row_shape_t *s)
{
    s->fall_d = (uint8_t)rng_range(s->top_d, QNAV_DTHETA_MAX);
    switch (rng_u32() % 3u) {
    case 0:
        s->peak_lo = QNAV_PEAK_NONE;
        s->peak_hi = 0u;
        break;
    case 1:
        s->peak_lo = QNAV_PEAK_MANY;
        break;
    default:
        s->peak_lo = (uint8_t)rng_range(1, QNAV_DTHETA_MAX - 1);
        s->peak_hi = (uint8_t)rng_range(s->peak_lo, QNAV_DTHETA_MAX - 1);
        break;
    }
}

static void test_a_forged_summary_only_makes_the_choice_inexact(void **state)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t p;
    uint8_t rec[QNAV_SHAPES_BYTES];
    unsigned i, s, l;
    (void)state;
    config(&cfg);
    for (i = 0; i < 20u; ++i) {
        qnav_ctrl_t c;
        random_net(&p, (uint8_t)(2u + i % (QNAV_MAX_HIDDEN - 1u)));
        assert_int_equal(qnav_ctrl_init(&c, &cfg, &p), QNAV_OK);
        for (l = 0; l < QNAV_DIST_LEVELS; ++l) {
            lie(&c.p.net.in.row[l]);
        }
        assert_int_equal(qnav_ctrl_shapes_save(&c, &p, rec), QNAV_OK);
        assert_int_equal(qnav_ctrl_init_carried(&c, &cfg, &p, rec, sizeof rec), QNAV_OK);
        assert_int_equal(qnav_ctrl_shapes_carried(&c), 1);
        for (s = 0; s < SCANS; ++s) {
            qnav_mm_t r[SECTORS];
            qnav_ctrl_input_t in;
            qnav_ctrl_output_t out;
            random_scan(r, &in);
            qnav_ctrl_step(&c, &in, &out, NULL);
            assert_true(out.heading_deg >= -179 && out.heading_deg <= 180);
            assert_true(out.speed >= 0 && out.quality >= 0);
            assert_int_equal(out.flags & QNAV_FLAG_NOT_READY, 0);
        }
    }
}

static void test_shapes_are_neither_written_nor_taken_for_other_policies(void **state)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t two, three, prob;
    qnav_ctrl_t c;
    uint8_t rec[QNAV_SHAPES_BYTES];
    (void)state;
    config(&cfg);
    random_net(&two, 4u);
    save_shapes(&cfg, &two, rec);
    three = two;
    three.u.net.inputs = QNAV_NET_INPUTS_PREV;
    qnav_policy_prob_default(&prob);
    assert_int_equal(qnav_ctrl_init_carried(&c, &cfg, &three, rec, sizeof rec), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(&c), 0);
    assert_int_equal(qnav_ctrl_shapes_save(&c, &three, rec), QNAV_E_NO_TABLE);
    assert_int_equal(qnav_ctrl_init_carried(&c, &cfg, &prob, rec, sizeof rec), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_carried(&c), 0);
    assert_int_equal(qnav_ctrl_shapes_save(&c, &prob, rec), QNAV_E_NO_TABLE);
    assert_int_equal(qnav_ctrl_init(&c, &cfg, &two), QNAV_OK);
    assert_int_equal(qnav_ctrl_shapes_save(&c, &three, rec), QNAV_E_NO_TABLE);
    assert_int_equal(qnav_ctrl_shapes_save(&c, &two, NULL), QNAV_E_NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_carried_shapes_decide_as_computed_ones_on_random_networks),
        cmocka_unit_test(test_carried_shapes_decide_as_computed_ones_on_the_fixture_policies),
        cmocka_unit_test(test_every_flipped_bit_of_carried_shapes_is_refused),
        cmocka_unit_test(test_shapes_of_another_policy_rank_or_length_are_refused),
        cmocka_unit_test(test_well_checked_shapes_out_of_range_or_off_the_network_are_refused),
        cmocka_unit_test(test_a_forged_summary_only_makes_the_choice_inexact),
        cmocka_unit_test(test_shapes_are_neither_written_nor_taken_for_other_policies),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
