/*
 * The run machinery of the step, private to libqnav: the 360 paths cut into runs (one
 * distance level, dtheta moving one way) handed out outward from the goal, each row's
 * shape (a level's keys over dtheta 0..180), and what a row's shape decides of a run
 * before any evaluation. Used by ctrl.c (table mode) and by the policy kinds
 * (policy_<kind>.c); it calls neither (docs/architecture.md, "Runs" and "Row shapes").
 */
#ifndef QNAV_RUNS_H
#define QNAV_RUNS_H

#include "ctrl_internal.h"

/*
 * A run: consecutive paths of one distance level along which dtheta moves one way. Within
 * a run each hidden unit's pre-activation is monotone, which is what lets the network step
 * bound a whole run from its two ends (docs/architecture.md).
 */
typedef struct {
    uint16_t first;      /* first path, degrees */
    uint8_t count;       /* paths in the run, 1..180 */
    uint8_t level;       /* distance level of every path of the run */
    uint8_t dtheta0;     /* dtheta of the first path */
    int8_t dir;          /* +1 or -1: change of dtheta from one path to the next */
} qnav_run_t;

/* Walks the 360 paths once and hands out their runs outward from the goal
 * (qnav_run_next). */
typedef struct {
    const uint8_t *lvl;   /* distance level of every path */
    uint16_t goal;        /* destination, whole degrees 0..359 */
    uint16_t prev;        /* heading chosen at the previous tick, whole degrees 0..359 */
    uint8_t up;           /* next dtheta counter-clockwise of the goal (0..180; 181: done) */
    uint8_t down;         /* next dtheta clockwise of the goal (1..179; 180: done) */
    /* for qnav_run_reduce: levels one of whose paths at or beyond its row's fall_d has
     * been offered (a bit each), and whether the previous run did that, at which dtheta */
    uint8_t settled[(QNAV_DIST_LEVELS + 7) / 8];
    uint8_t fresh;
    uint8_t fresh_level;
    uint8_t fresh_a;
} qnav_run_iter_t;

/* The path of run r whose dtheta is d (d within the run). */
static inline uint16_t qnav_run_path_at(const qnav_run_t *r, uint8_t d)
{
    uint8_t k = (uint8_t)(r->dir > 0 ? d - r->dtheta0 : r->dtheta0 - d);
    return (uint16_t)(r->first + k);
}

/* The smallest dtheta of run r. */
static inline uint8_t qnav_run_dmin(const qnav_run_t *r)
{
    return (uint8_t)(r->dir > 0 ? r->dtheta0 : r->dtheta0 + 1u - r->count);
}

/* Row shapes (docs/architecture.md, "Row shapes"): start a shape with the key at dtheta 0,
 * then feed the keys at dtheta 1..180 in order. */
typedef struct {
    qnav_row_shape_t *shape;
    qnav_qkey_t prev;     /* the key at the previous dtheta */
    uint8_t last_rise;    /* the dtheta of the last rise so far */
    uint8_t rising;       /* a rise since the last fall */
} qnav_row_scan_t;

/* qnav_row_shape_t.peak_lo when a row has no interior peak, or more than one. */
#define QNAV_PEAK_NONE 255u
#define QNAV_PEAK_MANY 254u
void qnav_row_shape_start(qnav_row_scan_t *sc, qnav_row_shape_t *s, qnav_qkey_t key0);
void qnav_row_shape_next(qnav_row_scan_t *sc, uint8_t d, qnav_qkey_t key);

/* What qnav_run_reduce leaves to do with the run it narrowed. A row is valley-shaped on
 * dtheta a..e when no interior peak lies inside (keys first never rise, then never fall):
 * its best is then the path at a, or, when the key at e is larger, the first path by
 * dtheta with the key at e. */
#define QNAV_RUN_DONE 0u   /* nothing: no path of it can win, or its best was offered */
#define QNAV_RUN_ALL 1u    /* its best is one of its paths (one path: that path's key) */
#define QNAV_RUN_VALLEY 2u /* the row is valley-shaped on it */
#define QNAV_RUN_PEAK 3u   /* it holds the row's single interior peak peak_lo..peak_hi and
                              is valley-shaped on either side: its best is the path at its
                              smallest dtheta, at peak_lo, or that of peak_hi + 1.. as for
                              QNAV_RUN_VALLEY */

/*
 * What the shape of a run's row decides before any evaluation (r must be the run that
 * qnav_run_next just handed out of it). Returns QNAV_RUN_DONE when nothing is left to do;
 * otherwise r is narrowed to the paths that can still hold its best path and the code says
 * what is known of them; the caller must then offer r's best to best. Any code but
 * QNAV_RUN_DONE can also be served by evaluating every path of the narrowed r.
 */
uint8_t qnav_run_reduce(const qnav_row_shape_t *row, qnav_run_t *r, qnav_best_t *best,
                        qnav_run_iter_t *it);

/* Start it over the levels lvl (goal and previous heading in whole degrees 0..359).
 * Inline: once a tick, in the step's own frame. */
static inline void qnav_run_start(qnav_run_iter_t *it, const uint8_t *lvl, uint16_t goal,
                                  uint16_t prev)
{
    uint8_t i;
    it->lvl = lvl;
    it->goal = goal;
    it->prev = prev;
    it->up = 0;
    it->down = 1;
    for (i = 0; i < sizeof it->settled; ++i) {
        it->settled[i] = 0;
    }
    it->fresh = 0;
    it->fresh_level = 0;
    it->fresh_a = 0;
}

/* The next run into *r, outward from the goal: runs arrive by their smallest dtheta. 0
 * when all 360 paths have been handed out. */
uint8_t qnav_run_next(qnav_run_iter_t *it, qnav_run_t *r);

#endif /* QNAV_RUNS_H */
