/*
 * The evolved network (paper §3.3): 2 inputs (dtheta, distance level) -> H sigmoid hidden
 * units -> 1 sigmoid output, Q8.8 weights; optionally a third input, the angular distance
 * dprev between the path and the previous tick's heading (paper §5). Its key is the
 * output's pre-activation, companded into 16 bits (docs/qformats.md), or the quality under
 * QNAV_RANK_QUALITY. Two inputs: the step bounds whole runs of paths and searches them
 * best first; three inputs: every path is evaluated (dprev breaks the runs' shape, and a
 * table would need a third dimension, docs/architecture.md).
 */
#include "ctrl_internal.h"
#include "sigmoid_lut.h"

/* Knee of the companded key: |z| below 8 keeps Q5.11 resolution. */
#define QNAV_KEY_KNEE 16384

/* Divide by a positive divisor, rounding halves away from zero. */
static int32_t div_round(int32_t num, int32_t den)
{
    return (num >= 0) ? (num + den / 2) / den : -((-num + den / 2) / den);
}

/* @par Scaling and overflow: a Q8.8 weight times 2048 is in units of 2^-19 (|.| <= 2^26);
 * per degree and per level divide that by 180 and by QNAV_DIST_LEVELS - 1, so each
 * input's term over its whole range stays within 2^26 and a 3-input pre-activation within
 * 2^28. The output bias times 128 is in units of 2^-15. */
void qnav_net_eval_init(qnav_ctrl_t *ctrl, const qnav_net_t *net)
{
    uint8_t j;
    ctrl->hidden = net->hidden;
    ctrl->inputs = net->inputs;
    for (j = 0; j < net->hidden; ++j) {
        qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        u->bias_z = (int32_t)net->b_hidden[j] * 2048;
        u->per_deg = div_round((int32_t)net->w_theta[j] * 2048, QNAV_DTHETA_MAX);
        u->per_level = div_round((int32_t)net->w_dist[j] * 2048, QNAV_DIST_LEVELS - 1);
        u->per_prev = net->inputs == QNAV_NET_INPUTS_PREV
                          ? div_round((int32_t)net->w_prev[j] * 2048, QNAV_DTHETA_MAX)
                          : 0;
        u->out = net->w_out[j];
    }
    ctrl->out_bias_z = (int32_t)net->b_out * 128;
}

/*
 * One hidden unit's share of the output pre-activation, in units of 2^-15.
 * z is the unit's pre-activation in units of 2^-19 (|z| < 2^29).
 * @par Scaling and overflow: (z + 2^7) >> 8 is Q5.11 (a byte move on AVR), saturated to
 * [-16, 16); out (Q8.8) times h (Q1.15) is below 2^30; >> 8 leaves units of 2^-15, below
 * 2^22 per unit, so 32 units sum below 2^27.
 */
static inline int32_t unit_share(int32_t z, int16_t out)
{
    int16_t h = qnav_sigmoid_q5_11(qnav_sat16((z + 128) >> 8));
    return ((int32_t)out * h + 128) >> 8;
}

/* Output unit: acc in units of 2^-15, rounded to Q5.11 and saturated. */
static inline qnav_q1_15_t net_output(int32_t acc)
{
    return qnav_sigmoid_q5_11(qnav_sat16((acc + 8) >> 4));
}

/*
 * The companded pre-activation key of acc (units of 2^-15).
 * @par Scaling and overflow: a = round(acc / 16) is Q5.11; |a| < 16384 (|z| < 8) is kept,
 * beyond the knee every 16 Q5.11 steps are one key step (1/128 in z), saturated to
 * +-32767, so the key is monotone in acc and -32768 stays free. |acc| < 2^27.
 */
static inline qnav_qkey_t preact_key(int32_t acc)
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

/* The network's key for an output accumulator, under the controller's rank. */
static inline qnav_qkey_t net_key_of(const qnav_ctrl_t *ctrl, int32_t acc)
{
    return ctrl->rank == (uint8_t)QNAV_RANK_PREACT ? preact_key(acc) : net_output(acc);
}

/* A key back to the quality: expand to Q5.11 (saturating at +-16) and take the sigmoid. */
qnav_q1_15_t qnav_net_eval_key_quality(qnav_qkey_t key)
{
    int32_t z = key;
    if (z >= QNAV_KEY_KNEE) {
        z = QNAV_KEY_KNEE + (z - QNAV_KEY_KNEE) * 16;
    } else if (z < -QNAV_KEY_KNEE) {
        z = -QNAV_KEY_KNEE + (z + QNAV_KEY_KNEE) * 16;
    }
    return qnav_sigmoid_q5_11(qnav_sat16(z));
}

/* a * b for a small unsigned b. */
static inline int32_t mul_u8(int32_t a, uint8_t b)
{
    return a * (int32_t)b;
}

static inline int32_t unit_base(const qnav_ctrl_unit_t *u, uint8_t level)
{
    return u->bias_z + mul_u8(u->per_level, level);
}

/* The output accumulator of one path (dprev 0 for a 2-input network: per_prev is 0). */
static int32_t path_acc(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta, uint8_t dprev)
{
    int32_t acc = ctrl->out_bias_z;
    uint8_t j;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        acc += unit_share(unit_base(u, level) + mul_u8(u->per_deg, dtheta) +
                              mul_u8(u->per_prev, dprev),
                          u->out);
    }
    return acc;
}

qnav_qkey_t qnav_net_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    return net_key_of(ctrl, path_acc(ctrl, level, dtheta, 0u));
}

/* Every path of a run; pre-activations walk by one degree's weight per path. */
static void eval_run(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best,
                     qnav_qkey_t *keys)
{
    int32_t z[QNAV_MAX_HIDDEN];
    uint8_t k;
    uint8_t j;
    uint8_t dtheta = r->dtheta0;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        z[j] = unit_base(u, r->level) + mul_u8(u->per_deg, r->dtheta0);
    }
    for (k = 0; k < r->count; ++k, dtheta = (uint8_t)(dtheta + r->dir)) {
        int32_t acc = ctrl->out_bias_z;
        qnav_qkey_t q;
        for (j = 0; j < ctrl->hidden; ++j) {
            const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
            acc += unit_share(z[j], u->out);
            z[j] = (r->dir > 0) ? z[j] + u->per_deg : z[j] - u->per_deg;
        }
        q = net_key_of(ctrl, acc);
        if (keys != 0) {
            keys[r->first + k] = q;
        }
        qnav_best_consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
}

void qnav_net_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row)
{
    /* a row is a run of dtheta 0..180: the same integers, by addition */
    qnav_run_t r;
    qnav_best_t ignore;
    r.first = 0;
    r.count = QNAV_DTHETA_MAX + 1;
    r.level = level;
    r.dtheta0 = 0;
    r.dir = 1;
    ignore.key = QNAV_KEY_NONE;
    ignore.dtheta = 0;
    ignore.heading = 0;
    eval_run(ctrl, &r, &ignore, row);
}

/* A run kept for the network's best-first search, with its bound. */
typedef struct {
    uint16_t first;
    uint8_t count;
    uint8_t level;
    qnav_qkey_t bound;   /* no path of the run exceeds it; QNAV_KEY_NONE once evaluated */
} pending_t;

/* How the dtheta term moves in the current run (see bound_runs). */
typedef struct {
    uint8_t level;
    uint8_t span;     /* paths in the run - 1 */
    uint8_t up;       /* dtheta rises along the run */
    uint8_t step_up;  /* the run's first dtheta is above the previous run's last */
    uint8_t first;    /* first run of the step: c starts from dtheta0 */
    uint8_t dtheta0;
} run_walk_t;

/* One unit's largest share over a run; advances its dtheta term c (per_deg * dtheta at
 * the end of the previous run) to the run's end. */
static inline int32_t bound_unit(const qnav_ctrl_unit_t *u, int32_t *c_io, const run_walk_t *rw)
{
    int32_t base = unit_base(u, rw->level);
    int32_t c = rw->first ? mul_u8(u->per_deg, rw->dtheta0)
                          : (rw->step_up ? *c_io + u->per_deg : *c_io - u->per_deg);
    int32_t dz = mul_u8(u->per_deg, rw->span);
    int32_t z0 = base + c;
    int32_t z1;
    c = rw->up ? c + dz : c - dz;
    *c_io = c;
    z1 = base + c;
    return unit_share(((u->out >= 0) == (z1 > z0)) ? z1 : z0, u->out);
}

/*
 * First pass: bound every run. Along a run each hidden unit's pre-activation is linear in
 * dtheta, and rounding, saturation, the interpolated sigmoid and the output weight all
 * keep order, so a unit's share is largest at one end, the end where out * z is larger:
 * one sigmoid per unit bounds the whole run, and the key is monotone in the output's
 * accumulator. The dtheta term is carried from run to run (neighbouring paths differ by
 * one degree). Runs whose bound is below the best so far are dropped; runs beyond cap are
 * evaluated at once (same answer). Returns the runs kept in runs[].
 */
static uint16_t bound_runs(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, pending_t *runs,
                           uint16_t cap, qnav_best_t *best)
{
    int32_t c[QNAV_MAX_HIDDEN];
    run_walk_t rw;
    uint8_t prev_end = 0;
    uint16_t n = 0;
    uint8_t j;
    qnav_run_t r;
    rw.first = 1;
    while (qnav_run_next(it, &r)) {
        int32_t acc = ctrl->out_bias_z;
        qnav_qkey_t bound;
        rw.level = r.level;
        rw.span = (uint8_t)(r.count - 1u);
        rw.up = (uint8_t)(r.dir > 0);
        rw.step_up = (uint8_t)(r.dtheta0 > prev_end);
        rw.dtheta0 = r.dtheta0;
        for (j = 0; j < ctrl->hidden; ++j) {
            acc += bound_unit(&ctrl->p.unit[j], &c[j], &rw);
        }
        rw.first = 0;
        prev_end = (uint8_t)(rw.up ? r.dtheta0 + rw.span : r.dtheta0 - rw.span);
        bound = net_key_of(ctrl, acc);
        if (r.count == 1u) {
            qnav_best_consider(best, bound, r.first, r.dtheta0); /* the bound is exact */
        } else if (bound < best->key) {
            /* cannot win: the best only rises */
        } else if (n < cap) {
            runs[n].first = r.first;
            runs[n].count = r.count;
            runs[n].level = r.level;
            runs[n].bound = bound;
            ++n;
        } else {
            eval_run(ctrl, &r, best, 0);
        }
    }
    return n;
}

/* Best-first over the runs' bounds: stop when no run left can reach the best. */
static void search_runs(const qnav_ctrl_t *ctrl, pending_t *runs, uint16_t n, uint16_t goal,
                        qnav_best_t *best)
{
    uint16_t i;
    for (;;) {
        pending_t *top = 0;
        qnav_run_t r;
        for (i = 0; i < n; ++i) {
            if (runs[i].bound != QNAV_KEY_NONE && (top == 0 || runs[i].bound > top->bound)) {
                top = &runs[i];
            }
        }
        if (top == 0 || top->bound < best->key) {
            return;
        }
        r.first = top->first;
        r.count = top->count;
        r.level = top->level;
        qnav_run_shape(&r, goal);
        eval_run(ctrl, &r, best, 0);
        top->bound = QNAV_KEY_NONE;
    }
}

/* Two inputs, no keys wanted: bound every run, then search the runs best first. */
static void best_first(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best)
{
    pending_t runs[QNAV_MAX_RUNS];
    uint16_t n;
    /* the path straight at the goal first: a good best prunes runs before they are kept */
    qnav_best_consider(best, qnav_net_eval_key(ctrl, it->lvl[it->goal], 0), it->goal, 0);
    n = bound_runs(ctrl, it, runs, QNAV_MAX_RUNS, best);
    search_runs(ctrl, runs, n, it->goal, best);
}

/*
 * Three inputs: every path, each from its own three inputs.
 * @par Cost: 360 * H sigmoids and 2 * 360 * H multiplies of 32 x 8 bits (measured on the
 * ATmega128 in docs/performance.md).
 */
static void eval_paths_prev(const qnav_ctrl_t *ctrl, const qnav_run_iter_t *it,
                            qnav_best_t *best, qnav_qkey_t *keys)
{
    uint16_t p;
    for (p = 0; p < QNAV_PATHS; ++p) {
        uint8_t dtheta = qnav_angle_dist_deg(p, it->goal);
        qnav_qkey_t q = net_key_of(ctrl, path_acc(ctrl, it->lvl[p], dtheta,
                                                  qnav_angle_dist_deg(p, it->prev)));
        if (keys != 0) {
            keys[p] = q;
        }
        qnav_best_consider(best, q, p, dtheta);
    }
}

void qnav_net_eval_paths(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                         qnav_qkey_t *keys)
{
    qnav_run_t r;
    if (ctrl->inputs == QNAV_NET_INPUTS_PREV) {
        eval_paths_prev(ctrl, it, best, keys);
    } else if (keys == 0) {
        best_first(ctrl, it, best);
    } else {
        while (qnav_run_next(it, &r)) {
            eval_run(ctrl, &r, best, keys);
        }
    }
}
