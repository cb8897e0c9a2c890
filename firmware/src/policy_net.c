/*
 * The evolved network (paper §3.3): 2 inputs (dtheta, distance level) -> H sigmoid hidden
 * units -> 1 sigmoid output, Q8.8 weights; optionally a third input, the angular distance
 * dprev between the path and the previous tick's heading (paper §5). Its key is the
 * output's pre-activation, companded into 16 bits (docs/qformats.md), or the quality under
 * QNAV_RANK_QUALITY. Two inputs: init learns the shape of every row of keys (a level,
 * dtheta 0..180), which settles most runs of paths with one evaluation or none; the rest
 * are searched by halving with exact bounds paid from a credit, so that no step evaluates
 * more than QNAV_NET_STEP_EVALS_MAX units. Three inputs: every path is evaluated (dprev
 * breaks the runs' shape, and a table would need a third dimension, docs/architecture.md).
 */
#include "policy_eval.h"
#include "sigmoid_lut.h"

#if !QNAV_WITH_NETWORK
#error "policy_net.c is left out of the build when QNAV_WITH_NETWORK is 0 (qnav/qnav_config.h)"
#endif

/* QNAV_BENCH_COUNT: n hidden-unit evaluations, into the caller's counter if it gave one. */
#if QNAV_BENCH_COUNT
#define QNAV_COUNT_EVALS(ctrl, n)                                                          \
    do {                                                                                   \
        if ((ctrl)->bench_evals != 0) {                                                    \
            *(ctrl)->bench_evals += (uint32_t)(n);                                         \
        }                                                                                  \
    } while (0)
#else
#define QNAV_COUNT_EVALS(ctrl, n) ((void)0)
#endif


/* Divide by a positive divisor, rounding halves away from zero. */
static int32_t div_round(int32_t num, int32_t den)
{
    return (num >= 0) ? (num + den / 2) / den : -((-num + den / 2) / den);
}

/* A pre-activation below this gives the sigmoid's 0, at or above UNIT_TOP_FROM its top. */
#define UNIT_ZERO_BELOW ((int32_t)QNAV_SIGMOID_LAST_ZERO * 256 + 128)
#define UNIT_TOP_FROM ((int32_t)QNAV_SIGMOID_FIRST_TOP * 256 - 128)

/*
 * One hidden unit's share of the output pre-activation, in units of 2^-15.
 * z is the unit's pre-activation in units of 2^-19 (|z| < 2^29).
 * @par Scaling and overflow: (z + 2^7) >> 8 is Q5.11 (a byte move on AVR), saturated to
 * [-16, 16); out (Q8.8) times h (Q1.15) is below 2^30; >> 8 leaves units of 2^-15, below
 * 2^22 per unit, so 32 units sum below 2^27.
 */
static inline int32_t unit_share(int32_t z, int16_t out)
{
    int16_t h;
    /* the sigmoid's flat ends, without the table or the multiply: h = 0 gives 0, and
     * h = 32767 gives (out * 2^15 - out + 128) >> 8 = out * 128 + ((128 - out) >> 8) */
    if (z < UNIT_ZERO_BELOW) {
        return 0;
    }
    if (z >= UNIT_TOP_FROM) {
        return (int32_t)out * 128 + (((int32_t)128 - out) >> 8);
    }
    /* strictly between the flat ends now, so the table is read without checking them */
    h = qnav_sigmoid_q5_11_between(qnav_sat16((z + 128) >> 8));
    return ((int32_t)out * h + 128) >> 8;
}

/* Output unit: acc in units of 2^-15, rounded to Q5.11 and saturated. */
static inline qnav_q1_15_t net_output(int32_t acc)
{
    return qnav_sigmoid_q5_11(qnav_sat16((acc + 8) >> 4));
}

/* The network's key for an output accumulator, under the controller's rank. */
static inline qnav_qkey_t net_key_of(const qnav_ctrl_t *ctrl, int32_t acc)
{
    return ctrl->rank == (uint8_t)QNAV_RANK_PREACT ? qnav_preact_key(acc) : net_output(acc);
}

/* net_key_of for the step's searches and single paths (key_of_path, search_run's bounds,
 * 3 inputs). Out of line on AVR: inlined at each of its dozen uses there, its 32-bit
 * companding cost qnav_net_eval_paths 13 bytes of spills, on the step's deepest call path,
 * and no cycles were saved (the step is 0.2-0.7 % faster with the call). eval_run, one
 * key per path after H units, keeps it inline. */
QNAV_AVR_NOINLINE static qnav_qkey_t step_key_of(const qnav_ctrl_t *ctrl, int32_t acc)
{
    return net_key_of(ctrl, acc);
}

/* a * b for a small unsigned b (the low 32 bits, which is the product: |a * b| < 2^31
 * wherever it is used). avr-gcc would call its 32 x 32 bit __mulsi3 (about 70 cycles):
 * four 8 x 8 bit MULs do it in 16; the shared vectors check it on the ATmega128. */
static inline int32_t mul_u8(int32_t a, uint8_t b)
{
#if defined(__AVR__) && defined(__AVR_HAVE_MUL__)
    int32_t r;
    __asm__("mul %A1, %2\n\t"
            "movw %A0, r0\n\t"
            "mul %C1, %2\n\t"
            "movw %C0, r0\n\t"
            "mul %B1, %2\n\t"
            "add %B0, r0\n\t"
            "adc %C0, r1\n\t"
            "clr r1\n\t"
            "adc %D0, r1\n\t"
            "mul %D1, %2\n\t"
            "add %D0, r0\n\t"
            "clr r1"
            : "=&r"(r)
            : "r"(a), "r"(b));
    return r;
#else
    return a * (int32_t)b;
#endif
}

static inline int32_t unit_base(const qnav_ctrl_unit_t *u, uint8_t level)
{
    return u->bias_z + mul_u8(u->per_level, level);
}

/* The output accumulator of one path of a 3-input network (inline: the step calls it once
 * per path, and a call there costs a 3-input step about 2 % on the ATmega128). */
static inline int32_t path_acc_prev(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta,
                             uint8_t dprev)
{
    int32_t acc = ctrl->p.net.out_bias_z;
    uint8_t j;
    QNAV_COUNT_EVALS(ctrl, ctrl->hidden);
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.net.unit[j];
        acc += unit_share(unit_base(u, level) + mul_u8(u->per_deg, dtheta) +
                              mul_u8(ctrl->p.net.in.per_prev[j], dprev),
                          u->out);
    }
    return acc;
}

/* The key of one 2-input path (inline: the step calls it without a frame of its own). */
static inline qnav_qkey_t key_of_path(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    int32_t acc = ctrl->p.net.out_bias_z;
    uint8_t j;
    QNAV_COUNT_EVALS(ctrl, ctrl->hidden);
    /* dprev = 0: the third input's term is 0 */
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.net.unit[j];
        acc += unit_share(unit_base(u, level) + mul_u8(u->per_deg, dtheta), u->out);
    }
    return step_key_of(ctrl, acc);
}

qnav_qkey_t qnav_net_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    return key_of_path(ctrl, level, dtheta);
}

qnav_qkey_t qnav_net_eval_path_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta,
                                   uint8_t dprev)
{
    if (ctrl->inputs == QNAV_NET_INPUTS_PREV) {
        return step_key_of(ctrl, path_acc_prev(ctrl, level, dtheta, dprev));
    }
    return qnav_net_eval_key(ctrl, level, dtheta);
}

/* Paths evaluated together by eval_run: one unit at a time over all of them, so that its
 * pre-activation stays in registers (on the ATmega128 about half the cycles of one path
 * at a time). */
#define QNAV_EVAL_CHUNK 16u

/* Every path of a run; each unit's pre-activation walks by one degree's weight per path
 * (the same integers as the per-path products). */
static void eval_run(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best,
                     qnav_qkey_t *keys)
{
    int32_t acc[QNAV_EVAL_CHUNK];
    uint8_t done = 0;
    uint8_t dtheta = r->dtheta0;
    while (done < r->count) {
        uint8_t n = (uint8_t)(r->count - done);
        if (n > QNAV_EVAL_CHUNK) {
            n = QNAV_EVAL_CHUNK;
        }
        uint8_t k;
        uint8_t j;
        QNAV_COUNT_EVALS(ctrl, (uint16_t)n * ctrl->hidden);
        for (k = 0; k < n; ++k) {
            acc[k] = ctrl->p.net.out_bias_z;
        }
        for (j = 0; j < ctrl->hidden; ++j) {
            const qnav_ctrl_unit_t *u = &ctrl->p.net.unit[j];
            int32_t step = r->dir > 0 ? u->per_deg : -u->per_deg;
            int32_t z = unit_base(u, r->level) + mul_u8(u->per_deg, dtheta);
            int16_t out = u->out;
#if !defined(__AVR__)
            /* On hosts a unit on one flat end of the sigmoid over the whole piece is taken at
             * once: z steps evenly, so it lies between its first and last values. The AVR's
             * step keeps its loop (not measured with the tests). */
            const int32_t z_last = z + step * (int32_t)(n - 1u);
            if (z < UNIT_ZERO_BELOW && z_last < UNIT_ZERO_BELOW) {
                continue; /* every share 0 */
            }
            if (z >= UNIT_TOP_FROM && z_last >= UNIT_TOP_FROM) {
                const int32_t top = unit_share(z, out);
                for (k = 0; k < n; ++k) {
                    acc[k] += top;
                }
                continue;
            }
#endif
            for (k = 0; k < n; ++k) {
                acc[k] += unit_share(z, out);
                z += step;
            }
        }
        for (k = 0; k < n; ++k, ++done, dtheta = (uint8_t)(dtheta + r->dir)) {
            qnav_qkey_t q = net_key_of(ctrl, acc[k]);
            if (keys != 0) {
                keys[r->first + done] = q;
            }
            qnav_best_consider(best, q, (uint16_t)(r->first + done), dtheta);
        }
    }
}

/* On hosts a table's row takes each unit's flat ends as ranges of paths (add_unit_row);
 * the ATmega128 and the Cortex-M4 keep eval_run's row, whose cycles their benches measure. */
#if !defined(__AVR__) && !(defined(__ARM_ARCH_PROFILE) && __ARM_ARCH_PROFILE == 'M')
/* The first k in 0..n - 1 at which z0 + k * s (s >= 0) reaches bound, or n. */
static int32_t first_reaching(int32_t z0, int32_t s, int32_t bound, int32_t n)
{
    int32_t k;
    if (z0 >= bound) {
        return 0;
    }
    if (s == 0) {
        return n;
    }
    k = (bound - z0 + s - 1) / s;
    return k < n ? k : n;
}

/* Unit u's shares of paths dtheta 0..n - 1 (pre-activation z0 + dtheta * per_deg, the
 * same integers as eval_run's) added to acc: z moves one way, so the paths on the flat
 * ends are two ranges, found by a division each, and only those between read the table
 * (unit_share's values: there the rounded z needs no saturation). */
static void add_unit_row(const qnav_ctrl_unit_t *u, uint8_t level, int32_t *acc, int32_t n)
{
    const int32_t z0 = unit_base(u, level), s = u->per_deg;
    const int32_t top = unit_share(UNIT_TOP_FROM, u->out);
    int32_t a, b, k, z, top_from, top_to; /* paths a .. b - 1 lie between the flat ends */
    if (s >= 0) { /* 0 below a, the top from b */
        a = first_reaching(z0, s, UNIT_ZERO_BELOW, n);
        b = first_reaching(z0, s, UNIT_TOP_FROM, n);
        top_from = b;
        top_to = n;
    } else { /* -z rises: the top below a, 0 from b */
        a = first_reaching(-z0, -s, 1 - UNIT_TOP_FROM, n);
        b = first_reaching(-z0, -s, 1 - UNIT_ZERO_BELOW, n);
        top_from = 0;
        top_to = a;
    }
    for (k = top_from; k < top_to; ++k) {
        acc[k] += top;
    }
    for (k = a, z = z0 + a * s; k < b; ++k, z += s) {
        const int16_t h = qnav_sigmoid_q5_11_between((int16_t)((z + 128) >> 8));
        acc[k] += ((int32_t)u->out * h + 128) >> 8;
    }
}

void qnav_net_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row)
{
    int32_t acc[QNAV_DTHETA_MAX + 1];
    int32_t k;
    uint8_t j;
    QNAV_COUNT_EVALS(ctrl, (uint16_t)(QNAV_DTHETA_MAX + 1u) * ctrl->hidden);
    for (k = 0; k <= QNAV_DTHETA_MAX; ++k) {
        acc[k] = ctrl->p.net.out_bias_z;
    }
    for (j = 0; j < ctrl->hidden; ++j) {
        add_unit_row(&ctrl->p.net.unit[j], level, acc, QNAV_DTHETA_MAX + 1);
    }
    for (k = 0; k <= QNAV_DTHETA_MAX; ++k) {
        row[k] = net_key_of(ctrl, acc[k]);
    }
}
#else
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
#endif

/* The shape of every row (init time): each row evaluated in pieces by eval_run, the same
 * integers as the step. @par Cost: 181 * QNAV_DIST_LEVELS paths of H units (ATmega128:
 * docs/performance.md). */
void qnav_net_eval_shapes(qnav_ctrl_t *ctrl)
{
    qnav_qkey_t keys[QNAV_EVAL_CHUNK];
    qnav_best_t ignore;
    qnav_run_t r;
    uint16_t level;
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        qnav_row_scan_t sc;
        uint8_t d = 0;
        r.first = 0;
        r.level = (uint8_t)level;
        r.dir = 1;
        while (d <= QNAV_DTHETA_MAX) {
            uint8_t k;
            r.dtheta0 = d;
            r.count = (uint8_t)(QNAV_DTHETA_MAX + 1 - d);
            if (r.count > QNAV_EVAL_CHUNK) {
                r.count = QNAV_EVAL_CHUNK;
            }
            ignore.key = QNAV_KEY_NONE;
            eval_run(ctrl, &r, &ignore, keys);
            for (k = 0; k < r.count; ++k, ++d) {
                if (d == 0) {
                    qnav_row_shape_start(&sc, &ctrl->p.net.in.row[level], keys[0]);
                } else {
                    qnav_row_shape_next(&sc, d, keys[k]);
                }
            }
        }
    }
}

/* @par Scaling and overflow: a Q8.8 weight times 2048 is in units of 2^-19 (|.| <= 2^26);
 * per degree and per level divide that by 180 and by QNAV_DIST_LEVELS - 1, so each
 * input's term over its whole range stays within 2^26 and a 3-input pre-activation within
 * 2^28. The output bias times 128 is in units of 2^-15. */
void qnav_net_eval_init(qnav_ctrl_t *ctrl, const qnav_net_t *net)
{
    uint8_t j;
#if QNAV_BENCH_COUNT
    ctrl->bench_evals = 0;
#endif
    ctrl->hidden = net->hidden;
    ctrl->inputs = net->inputs;
    for (j = 0; j < net->hidden; ++j) {
        qnav_ctrl_unit_t *u = &ctrl->p.net.unit[j];
        u->bias_z = (int32_t)net->b_hidden[j] * 2048;
        u->per_deg = div_round((int32_t)net->w_theta[j] * 2048, QNAV_DTHETA_MAX);
        u->per_level = div_round((int32_t)net->w_dist[j] * 2048, QNAV_DIST_LEVELS - 1);
        u->out = net->w_out[j];
        if (net->inputs == QNAV_NET_INPUTS_PREV) {
            ctrl->p.net.in.per_prev[j] =
                div_round((int32_t)net->w_prev[j] * 2048, QNAV_DTHETA_MAX);
        }
    }
    ctrl->p.net.out_bias_z = (int32_t)net->b_out * 128;
}

/* The dtheta of run r's path at offset i. */
static inline uint8_t dtheta_at(const qnav_run_t *r, uint8_t i)
{
    return (uint8_t)(r->dir > 0 ? r->dtheta0 + i : r->dtheta0 - i);
}

/* The dtheta of the path of offsets lo..hi nearest the goal. */
static inline uint8_t dtheta_near(const qnav_run_t *r, uint8_t lo, uint8_t hi)
{
    return dtheta_at(r, r->dir > 0 ? lo : hi);
}

/* Do unit u's shares rise along run r (dtheta moving by r->dir per path)? A unit whose
 * pre-activation does not move is constant: either answer holds. */
static inline uint8_t rises_along(const qnav_ctrl_unit_t *u, const qnav_run_t *r)
{
    uint8_t z_up = (uint8_t)(r->dir > 0 ? u->per_deg > 0 : u->per_deg < 0);
    return (uint8_t)((u->out >= 0) == z_up);
}

/*
 * Each unit's share at one of two paths of run r (offsets i_lo, i_hi): at i_hi for the
 * units whose shares rise along the run (summed into *s_hi), at i_lo for the others
 * (*s_lo). Along a run every unit's pre-activation is linear in the path, and rounding,
 * saturation, the interpolated sigmoid and the output weight all keep order, so each share
 * is monotone: over offsets lo..hi the largest output accumulator any path can have is the
 * output bias plus the rising units' shares at hi plus the others' at lo, and for a single
 * path (lo = hi) that is its exact accumulator. One sigmoid per unit.
 */
static inline void two_sums(const qnav_ctrl_t *ctrl, const qnav_run_t *r, uint8_t i_lo,
                            uint8_t i_hi, int32_t *s_lo, int32_t *s_hi)
{
    uint8_t d_lo = dtheta_at(r, i_lo);
    uint8_t d_hi = dtheta_at(r, i_hi);
    int32_t lo = 0;
    int32_t hi = 0;
    uint8_t j;
    QNAV_COUNT_EVALS(ctrl, ctrl->hidden);
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.net.unit[j];
        int32_t base = unit_base(u, r->level);
        if (rises_along(u, r)) {
            hi += unit_share(base + mul_u8(u->per_deg, d_hi), u->out);
        } else {
            lo += unit_share(base + mul_u8(u->per_deg, d_lo), u->out);
        }
    }
    *s_lo = lo;
    *s_hi = hi;
}

/* Paths lo..hi (offsets) of a run and the two halves of their bound (see two_sums). */
typedef struct {
    uint8_t lo;
    uint8_t hi;
    int32_t s_lo;
    int32_t s_hi;
} span_t;

/* A span left for later: its paths and its bound (its sums are made again if it is taken
 * up, which keeps the stack at 4 bytes a span on the ATmega128's 4 KB). */
typedef struct {
    uint8_t lo;
    uint8_t hi;
    qnav_qkey_t bound;
} later_t;

/* Spans of at most this many paths are evaluated path by path: bounding them costs as
 * much as it can save. */
#define QNAV_SPAN_DIRECT 4u

/* Halving a span of at most 181 paths down to QNAV_SPAN_DIRECT leaves at most 6 halves
 * waiting (181, 91, 46, 23, 12, 6 are halved; 3 is not). */
#define QNAV_SPAN_DEPTH 6

/* Can a span whose bound is `bound` and whose path nearest the goal has dtheta d_near
 * still beat best? */
static inline uint8_t may_win(const qnav_best_t *best, qnav_qkey_t bound, uint8_t d_near)
{
    return (uint8_t)(bound > best->key || (bound == best->key && d_near <= best->dtheta));
}

/* The number of paths lo..hi. */
static inline uint8_t span_size(uint8_t lo, uint8_t hi)
{
    return (uint8_t)((uint8_t)(hi - lo) + 1u);
}

/* Offsets lo..hi of run r, each path evaluated (one path at a time: evaluating a few
 * together, as eval_run does, took the step's deepest frame 47 bytes past the ATmega128's
 * 1 KB budget for controller and stack). */
static inline void span_direct(const qnav_ctrl_t *ctrl, const qnav_run_t *r, uint8_t lo,
                               uint8_t hi, qnav_best_t *best)
{
    uint8_t i;
    for (i = lo; i <= hi; ++i) {
        uint8_t d = dtheta_at(r, i);
        qnav_best_consider(best, key_of_path(ctrl, r->level, d), (uint16_t)(r->first + i), d);
    }
}

/* The step's credit: how many evaluations (H sigmoids each) it may still spend beyond one
 * per path not yet settled (docs/architecture.md, "The run search"). It starts at
 * QNAV_PATHS / QNAV_NET_SEARCH_SLACK; paths settled without an evaluation add one each, a
 * bound of the run search takes one. */
typedef uint16_t qnav_credit_t;

/* Span n halved, lo..mid and mid + 1..hi (the left keeps n's s_lo, the right its s_hi): the
 * more promising half stays in n (on equal bounds, the one nearer the goal), the other
 * waits in *w with its bound. One sigmoid per unit. */
static void halve(const qnav_ctrl_t *ctrl, const qnav_run_t *r, span_t *n, later_t *w)
{
    uint8_t mid = (uint8_t)(n->lo + (uint8_t)(n->hi - n->lo) / 2u);
    int32_t left_hi;
    int32_t right_lo;
    qnav_qkey_t k_left;
    qnav_qkey_t k_right;
    two_sums(ctrl, r, (uint8_t)(mid + 1u), mid, &right_lo, &left_hi);
    k_left = step_key_of(ctrl, ctrl->p.net.out_bias_z + n->s_lo + left_hi);
    k_right = step_key_of(ctrl, ctrl->p.net.out_bias_z + right_lo + n->s_hi);
    if (k_left > k_right || (k_left == k_right && r->dir > 0)) {
        w->lo = (uint8_t)(mid + 1u);
        w->hi = n->hi;
        w->bound = k_right;
        n->hi = mid;
        n->s_hi = left_hi;
    } else {
        w->lo = n->lo;
        w->hi = mid;
        w->bound = k_left;
        n->lo = (uint8_t)(mid + 1u);
        n->s_lo = right_lo;
    }
}

/* What a search leaves when its credit is spent: span n (which may still win), then every
 * waiting span that may, path by path (a span ruled out adds its paths to the credit).
 * Inline: as a call its frame alone took the step's stack past the 1 KB budget. */
static inline void search_rest(const qnav_ctrl_t *ctrl, const qnav_run_t *r,
                               const span_t *n, const later_t *stack, uint8_t depth,
                               qnav_best_t *best, qnav_credit_t *credit)
{
    span_direct(ctrl, r, n->lo, n->hi, best);
    while (depth != 0u) {
        const later_t *w = &stack[--depth];
        uint8_t d_near = dtheta_near(r, w->lo, w->hi);
        if (may_win(best, w->bound, d_near)) {
            span_direct(ctrl, r, w->lo, w->hi, best);
        } else {
            *credit = (qnav_credit_t)(*credit + span_size(w->lo, w->hi));
        }
    }
}

/*
 * The best path of run r by branch and bound: a span whose bound cannot beat the best is
 * dropped; a short one is evaluated path by path; otherwise it is halved, and each half's
 * bound needs one new sigmoid per unit (the rising units' shares at the left half's end,
 * the others' at the right half's start; the outer ends are the parent's). The half left
 * for later keeps its bound and costs one sigmoid per unit again only if it is taken up.
 * Each bound is paid from the step's credit, and each span dropped adds its paths to it;
 * with none left, every path not yet ruled out is evaluated. So the step evaluates at most
 * QNAV_PATHS + QNAV_PATHS / QNAV_NET_SEARCH_SLACK paths whatever the policy
 * (QNAV_NET_STEP_EVALS_MAX), and in the usual case far fewer.
 */
static void search_run(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best,
                       qnav_credit_t *credit)
{
    later_t stack[QNAV_SPAN_DEPTH];
    uint8_t depth = 0;
    uint8_t d_near;
    span_t n;
    n.lo = 0;
    n.hi = (uint8_t)(r->count - 1u);
    if (r->count <= QNAV_SPAN_DIRECT || *credit == 0u) {
        span_direct(ctrl, r, n.lo, n.hi, best);
        return;
    }
    two_sums(ctrl, r, n.lo, n.hi, &n.s_lo, &n.s_hi);
    --*credit;
    for (;;) {
        qnav_qkey_t bound = step_key_of(ctrl, ctrl->p.net.out_bias_z + n.s_lo + n.s_hi);
        d_near = dtheta_near(r, n.lo, n.hi);
        if (may_win(best, bound, d_near)) {
            if (*credit == 0u) {
                search_rest(ctrl, r, &n, stack, depth, best, credit);
                return;
            }
            halve(ctrl, r, &n, &stack[depth++]);
            --*credit;
            if ((uint8_t)(n.hi - n.lo) >= QNAV_SPAN_DIRECT) {
                continue;
            }
            span_direct(ctrl, r, n.lo, n.hi, best);
        } else {
            *credit = (qnav_credit_t)(*credit + span_size(n.lo, n.hi));
        }
        /* the next waiting span that may still win */
        for (;;) {
            if (depth == 0u) {
                return;
            }
            --depth;
            n.lo = stack[depth].lo;
            n.hi = stack[depth].hi;
            d_near = dtheta_near(r, n.lo, n.hi);
            if (!may_win(best, stack[depth].bound, d_near)) {
                *credit = (qnav_credit_t)(*credit + span_size(n.lo, n.hi));
                continue;
            }
            if ((uint8_t)(n.hi - n.lo) < QNAV_SPAN_DIRECT) {
                span_direct(ctrl, r, n.lo, n.hi, best);
                continue;
            }
            if (*credit == 0u) {
                search_rest(ctrl, r, &n, stack, depth, best, credit);
                return;
            }
            two_sums(ctrl, r, n.lo, n.hi, &n.s_lo, &n.s_hi);
            --*credit;
            break;
        }
    }
}

/* The path of run r at dtheta d, its key offered to best. */
static inline void offer_at(const qnav_ctrl_t *ctrl, const qnav_run_t *r, uint8_t d,
                            qnav_best_t *best)
{
    qnav_best_consider(best, key_of_path(ctrl, r->level, d), qnav_run_path_at(r, d), d);
}

/* The best of run r's paths at dtheta lo..hi, on which the row is valley-shaped (keys
 * first never rise, then never fall): the path at lo unless the key at hi is larger, then
 * the first path with the key at hi. The keys below it before the valley are at most the
 * key at lo, so "key >= the key at hi" is false, then true, over lo..hi: a halving search
 * finds where, when the last step is flat. */
static inline void offer_valley(const qnav_ctrl_t *ctrl, const qnav_run_t *r, uint8_t lo,
                                uint8_t hi, qnav_best_t *best)
{
    qnav_qkey_t k_lo = key_of_path(ctrl, r->level, lo);
    qnav_qkey_t k_hi = lo == hi ? k_lo : key_of_path(ctrl, r->level, hi);
    /* the path at lo wins, or no path with the key at hi can beat the best wherever its
     * plateau starts (then the path at lo cannot either: its key is lower) */
    if (k_hi <= k_lo || k_hi < best->key ||
        (k_hi == best->key && (uint8_t)(lo + 1u) > best->dtheta)) {
        qnav_best_consider(best, k_lo, qnav_run_path_at(r, lo), lo);
        return;
    }
    /* (two paths: the key at lo, below k_hi, is the one before hi; no need to read it) */
    if ((uint8_t)(hi - 1u) != lo && key_of_path(ctrl, r->level, (uint8_t)(hi - 1u)) >= k_hi) {
        uint8_t x = (uint8_t)(lo + 1u); /* the key at lo is below k_hi */
        hi = (uint8_t)(hi - 1u);
        while (x < hi) {
            uint8_t mid = (uint8_t)(x + (uint8_t)(hi - x) / 2u);
            if (key_of_path(ctrl, r->level, mid) >= k_hi) {
                hi = mid;
            } else {
                x = (uint8_t)(mid + 1u);
            }
        }
    }
    qnav_best_consider(best, k_hi, qnav_run_path_at(r, hi), hi);
}

/*
 * Two inputs, no keys wanted: every run, outward from the goal, settled by its row's shape
 * (qnav_run_reduce); what that leaves is a few paths to evaluate, or a search.
 */
static void two_inputs_best(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best)
{
    qnav_run_t r;
    qnav_credit_t credit = QNAV_PATHS / QNAV_NET_SEARCH_SLACK;
    while (qnav_run_next(it, &r)) {
        uint8_t paths = r.count;
        uint8_t a;
        uint8_t e;
        uint8_t how = qnav_run_reduce(ctrl->p.net.in.row, &r, best, it);
        /* the paths ruled out credit the search; the rest cost at most one evaluation each
         * (a valley or a peak fewer, not counted) */
        credit = (qnav_credit_t)(credit +
                                 (how == QNAV_RUN_DONE ? paths : (uint8_t)(paths - r.count)));
        switch (how) {
        case QNAV_RUN_DONE:
            break;
        case QNAV_RUN_ALL:
            if (r.count == 1u) {
                qnav_best_consider(best, key_of_path(ctrl, r.level, r.dtheta0), r.first,
                                   r.dtheta0);
            } else {
                search_run(ctrl, &r, best, &credit);
            }
            break;
        case QNAV_RUN_VALLEY:
            a = qnav_run_dmin(&r);
            offer_valley(ctrl, &r, a, (uint8_t)(a + (uint8_t)(r.count - 1u)), best);
            break;
        default: { /* QNAV_RUN_PEAK */
            const qnav_row_shape_t *s = &ctrl->p.net.in.row[r.level];
            a = qnav_run_dmin(&r);
            e = (uint8_t)(a + (uint8_t)(r.count - 1u));
            offer_at(ctrl, &r, a, best);
            offer_at(ctrl, &r, s->peak_lo, best);
            offer_valley(ctrl, &r, (uint8_t)(s->peak_hi + 1u), e, best);
            break;
        }
        }
    }
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
        qnav_qkey_t q = step_key_of(ctrl, path_acc_prev(ctrl, it->lvl[p], dtheta,
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
        two_inputs_best(ctrl, it, best);
    } else {
        while (qnav_run_next(it, &r)) {
            eval_run(ctrl, &r, best, keys);
        }
    }
}
