/*
 * Unit tests of the run machinery (firmware/src/runs.[ch]): what qnav_run_reduce claims of
 * the runs it narrows, checked against the keys themselves on synthetic rows of every
 * shape.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "qnav/ctrl.h"
#include "runs.h"
#include "test_rng.h"

/* A row of keys with the features that break shortcuts: plateaus, single-path spikes and
 * dips, valleys, several peaks, long flat stretches. kind 0: stretches of random slope;
 * 1: a valley (falls, then rises); 2: a peak (rises, then falls); 3: a peak, a valley and
 * a higher end; all with flat steps. */
static void synthetic_row(qnav_qkey_t *row, unsigned kind)
{
    int32_t v = rng_range(-200, 200);
    int32_t slope = rng_range(-3, 3);
    unsigned turn = (unsigned)rng_range(0, QNAV_DTHETA_MAX);
    for (unsigned d = 0; d <= QNAV_DTHETA_MAX; ++d) {
        uint32_t pick = rng_u32() % 100u;
        if (kind == 0u) {
            if (pick < 6u) {
                slope = rng_range(-3, 3); /* a new stretch: rising, falling or flat */
            }
            if (pick == 50u) {
                row[d] = (qnav_qkey_t)(v + rng_range(-5, 5)); /* a spike or a dip */
                continue;
            }
        } else if (kind < 3u) {
            int32_t sign = (d < turn) == (kind == 1u) ? -1 : 1;
            slope = pick < 30u ? 0 : sign * rng_range(0, 2); /* flat steps on the way */
        } else { /* rises to a peak, falls, rises again higher: the top at the far end */
            int32_t sign = d < turn / 2u ? 1 : (d < turn ? -1 : 1);
            slope = pick < 30u ? 0 : sign * rng_range(0, d < turn ? 2 : 4);
        }
        v += slope;
        row[d] = (qnav_qkey_t)v;
    }
}

/* Keys on lo..hi first never rise, then never fall (no rise is followed by a fall). */
static int valley_shaped(const qnav_qkey_t *row, uint8_t lo, uint8_t hi)
{
    int rose = 0;
    for (unsigned d = lo; d < hi; ++d) {
        if (row[d + 1] > row[d]) {
            rose = 1;
        } else if (row[d + 1] < row[d] && rose) {
            return 0;
        }
    }
    return 1;
}

/* One trial's quality table: a synthetic row of a shape chosen by trial and level. */
static void synthetic_table(qnav_qkey_t *table, unsigned trial)
{
    for (unsigned level = 0; level < QNAV_DIST_LEVELS; ++level) {
        synthetic_row(&table[level * (QNAV_DTHETA_MAX + 1)], (trial + level) % 4u);
    }
}

/* Every path's level: runs of random levels and lengths. */
static void random_runs(uint8_t *lvl)
{
    for (unsigned p = 0; p < QNAV_PATHS;) {
        uint8_t level = (uint8_t)rng_range(0, QNAV_DIST_LEVELS - 1);
        unsigned len = (unsigned)rng_range(1, 40);
        for (; len > 0 && p < QNAV_PATHS; --len, ++p) {
            lvl[p] = level;
        }
    }
}

/* A run that qnav_run_reduce answered QNAV_RUN_DONE for: nothing of it beats what best
 * now holds. */
static void assert_nothing_beats_best(const qnav_qkey_t *row, const qnav_run_t *r,
                                      const qnav_best_t *best)
{
    uint8_t a0 = qnav_run_dmin(r);
    uint8_t b0 = (uint8_t)(a0 + r->count - 1u);
    qnav_best_t check = *best;
    for (uint8_t d = a0; d <= b0; ++d) {
        qnav_best_consider(&check, row[d], qnav_run_path_at(r, d), d);
    }
    assert_int_equal(check.key, best->key);
    assert_int_equal(check.dtheta, best->dtheta);
    assert_int_equal(check.heading, best->heading);
}

/* A peak kept by qnav_run_reduce on a..e: valleys on both sides of a flat top that both
 * neighbours fall from. */
static void assert_peak_shaped(const qnav_qkey_t *row, const qnav_row_shape_t *sh, uint8_t a,
                               uint8_t e)
{
    assert_true(sh->peak_lo != QNAV_PEAK_NONE && sh->peak_lo != QNAV_PEAK_MANY);
    assert_true(a < sh->peak_lo && sh->peak_hi < e);
    assert_true(valley_shaped(row, a, sh->peak_hi));
    assert_true(valley_shaped(row, (uint8_t)(sh->peak_hi + 1u), e));
    assert_true(row[sh->peak_lo - 1u] < row[sh->peak_lo]);
    for (uint8_t d = sh->peak_lo; d < sh->peak_hi; ++d) {
        assert_true(row[d] == row[d + 1]);
    }
    assert_true(row[sh->peak_hi + 1u] < row[sh->peak_hi]);
}

/* Reduce run r and check what the answer claims; returns the answer. */
static uint8_t reduce_and_check(const qnav_ctrl_t *c, const qnav_qkey_t *table,
                                const qnav_run_t *r, qnav_best_t *best, qnav_run_iter_t *it)
{
    const qnav_qkey_t *row = &table[r->level * (QNAV_DTHETA_MAX + 1)];
    const qnav_row_shape_t *sh = &c->p.net.in.row[r->level];
    uint8_t a0 = qnav_run_dmin(r);
    uint8_t b0 = (uint8_t)(a0 + r->count - 1u);
    /* the run's own best by the step's order, before reduce (dtheta, then turn) */
    qnav_best_t own = *best;
    for (uint8_t d = a0; d <= b0; ++d) {
        qnav_best_consider(&own, row[d], qnav_run_path_at(r, d), d);
    }
    qnav_run_t kept = *r;
    uint8_t code = qnav_run_reduce(c->p.net.in.row, &kept, best, it);
    assert_true(code <= QNAV_RUN_PEAK);
    if (code == QNAV_RUN_DONE) {
        assert_nothing_beats_best(row, r, best);
        return code;
    }
    uint8_t a = qnav_run_dmin(&kept);
    uint8_t e = (uint8_t)(a + kept.count - 1u);
    assert_true(a == a0 && e <= b0);
    if (code == QNAV_RUN_VALLEY) {
        assert_true(valley_shaped(row, a, e));
    } else if (code == QNAV_RUN_PEAK) {
        assert_peak_shaped(row, sh, a, e);
    }
    /* the kept paths hold the run's best: offering them reaches the same record */
    for (uint8_t d = a; d <= e; ++d) {
        qnav_best_consider(best, row[d], qnav_run_path_at(&kept, d), d);
    }
    assert_int_equal(best->key, own.key);
    assert_int_equal(best->dtheta, own.dtheta);
    assert_int_equal(best->heading, own.heading);
    return code;
}

/* What qnav_run_reduce claims of a narrowed run must hold of the keys, and the run's best
 * path (the brute-force best of the run as handed out) must stay reachable: checked on
 * synthetic rows of every shape in table mode, where reduce reads the table's shapes. */
static void test_run_reduce_keeps_its_promises_on_any_row(void **state)
{
    (void)state;
    static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
    uint8_t lvl[QNAV_PATHS];
    unsigned codes[4] = {0, 0, 0, 0};
    for (unsigned trial = 0; trial < 1500; ++trial) {
        qnav_ctrl_config_t cfg;
        qnav_ctrl_t c;
        qnav_run_iter_t it;
        qnav_run_t r;
        qnav_best_t best = {QNAV_KEY_NONE, 0, 0};
        qnav_ctrl_config_default(&cfg);
        synthetic_table(table, trial);
        assert_int_equal(qnav_ctrl_init_table(&c, &cfg, table, QNAV_RANK_PREACT), QNAV_OK);
        random_runs(lvl);
        qnav_run_start(&it, lvl, (uint16_t)rng_range(0, 359), 0);
        while (qnav_run_next(&it, &r)) {
            ++codes[reduce_and_check(&c, table, &r, &best, &it)];
        }
    }
    print_message("reduce: %u done, %u all, %u valley, %u peak\n", codes[0], codes[1],
                  codes[2], codes[3]);
    for (unsigned k = 0; k < 4; ++k) {
        assert_true(codes[k] > 100u); /* every rule met often enough to mean something */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_run_reduce_keeps_its_promises_on_any_row),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
