/*
 * Probabilistic navigation (paper §3.2), the hand-tuned baseline: X = P_goal(dtheta) *
 * P_safe(level), both exponentials tabulated at init so that a path costs one product.
 * Its key is the quality itself (a product of probabilities does not saturate).
 */
#include "policy_eval.h"

#if !QNAV_WITH_PROB
#error "policy_prob.c is left out of the build when QNAV_WITH_PROB is 0 (qnav/qnav_config.h)"
#endif

/*
 * e^-u for u in Q16.16 (u >= 0), result in units of 2^-15 in [0, 32768] (1.0 included).
 * Range reduction by ln 2, then 9 terms of the series in Q0.16; error at most 2 LSB.
 * @par Scaling and overflow: all products are r * t with r < 45426 and t <= 65536, which
 * fit uint32.
 */
static uint16_t exp_neg_q15(uint32_t u_q16)
{
    const uint32_t ln2_q16 = 45426u;
    uint32_t n = u_q16 / ln2_q16;
    uint32_t r = u_q16 - n * ln2_q16;
    uint32_t t = 65536u;
    uint32_t k;
    uint32_t v;
    if (n > 16u) {
        return 0;
    }
    for (k = 8u; k >= 1u; --k) {
        t = 65536u - ((r * t) / k >> 16);
    }
    v = (t + ((uint32_t)1 << n)) >> (n + 1u);
    return (uint16_t)v;
}

/* @par Scaling and overflow: k (Q8.8, <= 2^14) * i (<= 180) * 256 < 2^30: u is Q16.16. */
void qnav_prob_eval_init(qnav_ctrl_t *ctrl, const qnav_prob_params_t *p)
{
    uint16_t i;
    for (i = 0; i <= QNAV_DTHETA_MAX; ++i) {
        uint32_t u = ((uint32_t)p->k_goal * i * 256u + QNAV_DTHETA_MAX / 2u) / QNAV_DTHETA_MAX;
        uint16_t g = exp_neg_q15(u);
        ctrl->p.prob.goal[i] = (qnav_q1_15_t)(g > 32767u ? 32767u : g);
    }
    for (i = 0; i < QNAV_DIST_LEVELS; ++i) {
        uint32_t u = ((uint32_t)p->k_safe * i * 256u + (QNAV_DIST_LEVELS - 1u) / 2u) /
                     (QNAV_DIST_LEVELS - 1u);
        ctrl->p.prob.safe[i] = (qnav_q1_15_t)(32768u - exp_neg_q15(u) > 32767u
                                                  ? 32767u : 32768u - exp_neg_q15(u));
    }
}

/* @par Scaling and overflow: two Q1.15 values below 2^15 multiply below 2^30; rounded
 * back to Q1.15. */
qnav_qkey_t qnav_prob_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    uint32_t q = (uint32_t)ctrl->p.prob.goal[dtheta] * (uint32_t)ctrl->p.prob.safe[level];
    return (qnav_q1_15_t)((q + 16384u) >> 15);
}

void qnav_prob_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row)
{
    uint16_t d;
    for (d = 0; d <= QNAV_DTHETA_MAX; ++d) {
        row[d] = qnav_prob_eval_key(ctrl, level, (uint8_t)d);
    }
}

static void eval_run_all(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best,
                         qnav_qkey_t *keys)
{
    uint8_t k;
    uint8_t dtheta = r->dtheta0;
    for (k = 0; k < r->count; ++k, dtheta = (uint8_t)(dtheta + r->dir)) {
        qnav_q1_15_t q = qnav_prob_eval_key(ctrl, r->level, dtheta);
        keys[r->first + k] = q;
        qnav_best_consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
}

/* Quality falls with dtheta at a fixed level, so a run's best path is its end nearest the
 * goal, which the tie order also prefers. */
static void eval_run_best(const qnav_ctrl_t *ctrl, const qnav_run_t *r, qnav_best_t *best)
{
    uint8_t k = (uint8_t)(r->dir > 0 ? 0u : r->count - 1u);
    uint8_t dtheta = (uint8_t)(r->dir > 0 ? r->dtheta0 : r->dtheta0 - k);
    qnav_best_consider(best, qnav_prob_eval_key(ctrl, r->level, dtheta),
                       (uint16_t)(r->first + k), dtheta);
}

void qnav_prob_eval_paths(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                          qnav_qkey_t *keys)
{
    qnav_run_t r;
    while (qnav_run_next(it, &r)) {
        if (keys != 0) {
            eval_run_all(ctrl, &r, best, keys);
        } else {
            eval_run_best(ctrl, &r, best);
        }
    }
}
