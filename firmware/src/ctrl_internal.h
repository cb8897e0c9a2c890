/*
 * What the path-quality controller (ctrl.c) shares with each policy kind's evaluation
 * (policy_<kind>.c), private to libqnav: the runs the step cuts the 360 paths into, the
 * best-path record and its total order, and one prototype block per kind. Adding a
 * kind means one block here, one file, and a case in every switch of ctrl.c that -Wswitch
 * names (docs/architecture.md, "Adding a policy kind").
 */
#ifndef QNAV_CTRL_INTERNAL_H
#define QNAV_CTRL_INTERNAL_H

#include "qnav/ctrl.h"

#define QNAV_CTRL_MAGIC 0x514Eu

#define QNAV_TABLE_STRIDE (QNAV_DTHETA_MAX + 1)
/* No key: below every key a policy gives (keys are -32767..32767). */
#define QNAV_KEY_NONE (-32767 - 1)

/* The network arithmetic shifts signed values right and relies on it being arithmetic
 * (implementation-defined in C99; true on gcc, avr-gcc and arm-none-eabi-gcc). */
typedef char qnav_arith_shift_check[((-8 >> 1) == -4) ? 1 : -1];

static inline int16_t qnav_sat16(int32_t v)
{
    if (v > 32767) {
        return 32767;
    }
    if (v < -32768) {
        return -32768;
    }
    return (int16_t)v;
}

/* Knee of the companded pre-activation key: |z| below 8 keeps Q5.11 resolution. */
#define QNAV_KEY_KNEE 16384

/*
 * The companded pre-activation key of acc (units of 2^-15): what a network ranks by under
 * QNAV_RANK_PREACT, and what such a network's compiled table holds.
 * @par Scaling and overflow: a = round(acc / 16) is Q5.11; |a| < 16384 (|z| < 8) is kept,
 * beyond the knee every 16 Q5.11 steps are one key step (1/128 in z), saturated to
 * +-32767, so the key is monotone in acc and -32768 stays free. |acc| < 2^27.
 */
static inline qnav_qkey_t qnav_preact_key(int32_t acc)
{
    int32_t a = (acc + 8) >> 4;
    if (a >= QNAV_KEY_KNEE) {
        a = QNAV_KEY_KNEE + ((a - QNAV_KEY_KNEE) >> 4);
        return (qnav_qkey_t)(a > 32767 ? 32767 : a);
    }
    if (a < -QNAV_KEY_KNEE) {
        a = -QNAV_KEY_KNEE + ((a + QNAV_KEY_KNEE) >> 4);
        return (qnav_qkey_t)(a < -32767 ? -32767 : a);
    }
    return (qnav_qkey_t)a;
}

/* Whether this build has pre-activation keys: networks make them, tables of networks hold
 * them. Turning one back into a quality reads the sigmoid table, so src/sigmoid_lut.c is
 * built exactly then (firmware/CMakeLists.txt says the same). */
#define QNAV_WITH_PREACT_KEYS (QNAV_WITH_NETWORK || QNAV_WITH_TABLE)

/* A pre-activation key back to the quality (ctrl.c; with QNAV_WITH_PREACT_KEYS only):
 * expand to Q5.11 (saturating at +-16) and take the sigmoid. */
qnav_q1_15_t qnav_preact_key_quality(qnav_qkey_t key);

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

/* The best path so far under the controller's total order (key, then smaller dtheta,
 * then smaller turn, then counter-clockwise). */
typedef struct {
    qnav_qkey_t key;
    uint8_t dtheta;
    qnav_deg_t heading;
} qnav_best_t;

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

/* Offer path (with its key and dtheta) to best under the total order above. Inline: the
 * network calls it once per path. */
static inline void qnav_best_consider(qnav_best_t *best, qnav_qkey_t key, uint16_t path,
                                      uint8_t dtheta)
{
    qnav_deg_t heading;
    int16_t turn;
    int16_t best_turn;
    if (key < best->key) {
        return;
    }
    heading = (qnav_deg_t)(path <= 180u ? (int16_t)path : (int16_t)path - 360);
    if (key == best->key) {
        if (dtheta != best->dtheta) {
            if (dtheta > best->dtheta) {
                return;
            }
        } else {
            turn = (int16_t)(heading < 0 ? -heading : heading);
            best_turn = (int16_t)(best->heading < 0 ? -best->heading : best->heading);
            if (turn > best_turn || (turn == best_turn && heading < best->heading)) {
                return;
            }
        }
    }
    best->key = key;
    best->dtheta = dtheta;
    best->heading = heading;
}

/* Angular distance between two whole-degree directions 0..359, in 0..180. */
static inline uint8_t qnav_angle_dist_deg(uint16_t a, uint16_t b)
{
    uint16_t d = (uint16_t)(a >= b ? a - b : b - a);
    return (uint8_t)(d > QNAV_DTHETA_MAX ? QNAV_PATHS - d : d);
}

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

/* An angle in centidegrees to the nearest whole degree (halves away from zero), 0..359.
 * 16-bit arithmetic: one division, no 32-bit ones (costly on AVR). */
uint16_t qnav_whole_deg(qnav_cdeg_t cdeg);

/* Start it over the levels lvl (goal and previous heading in whole degrees 0..359). */
void qnav_run_start(qnav_run_iter_t *it, const uint8_t *lvl, uint16_t goal, uint16_t prev);

/* The next run into *r, outward from the goal: runs arrive by their smallest dtheta. 0
 * when all 360 paths have been handed out. */
uint8_t qnav_run_next(qnav_run_iter_t *it, qnav_run_t *r);

/* ---- policy_prob.c: probabilistic navigation (paper §3.2) --------------------------- */

/* Tabulate P_goal and P_safe into ctrl->p.prob (parameters already validated). */
void qnav_prob_eval_init(qnav_ctrl_t *ctrl, const qnav_prob_params_t *p);
/* The quality of one (level, dtheta), Q1.15: the kind's key. */
qnav_qkey_t qnav_prob_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta);
/* Every run of it into best; keys (may be null) receives every path's key. */
void qnav_prob_eval_paths(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                          qnav_qkey_t *keys);
/* One table row (dtheta 0..180 at level). */
void qnav_prob_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row);

/* ---- policy_net.c: the evolved network (paper §3.3; 3 inputs: §5) ------------------- */

/* Derive the per-unit integer parameters into ctrl (network already validated). */
void qnav_net_eval_init(qnav_ctrl_t *ctrl, const qnav_net_t *net);
/* The key of one (level, dtheta); a 3-input network with the path on the previous
 * heading (dprev = 0). */
qnav_qkey_t qnav_net_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta);
/* Every path of it into best (best first when keys is null); keys as above. */
void qnav_net_eval_paths(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                         qnav_qkey_t *keys);
/* One table row (dtheta 0..180 at level) by the same additions as the step. */
void qnav_net_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row);

#endif /* QNAV_CTRL_INTERNAL_H */
