/*
 * Policies: what maps one path's two inputs (angular distance to the destination, distance
 * level of its sector) to a path quality. Two kinds share that shape (paper §3.2, §3.3):
 * the hand-tuned probabilistic policy and the evolved 2-input sigmoid network. A policy is
 * plain data that the caller owns; qnav_ctrl_init() checks it and derives what a step needs.
 */
#ifndef QNAV_POLICY_H
#define QNAV_POLICY_H

#include "qnav/fixed.h"
#include "qnav/qnav_config.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    QNAV_POLICY_PROB = 1, /* probabilistic navigation: X = P_goal(dtheta) * P_safe(d) */
    QNAV_POLICY_NET = 2   /* network: 2 inputs -> H sigmoid hidden -> 1 sigmoid output */
} qnav_policy_kind_t;

/*
 * Probabilistic navigation (paper §3.2), with x_theta = dtheta / 180 deg and
 * x_d = level / (QNAV_DIST_LEVELS - 1):
 *   P_goal = exp(-k_goal * x_theta)       P_safe = 1 - exp(-k_safe * x_d)
 * Both parameters Q8.8, valid in (0, 64]. Hand-tuned defaults in qnav_policy_prob_default().
 */
typedef struct {
    qnav_q8_8_t k_goal; /* goal sharpness, per half turn, Q8.8, (0, 64] */
    qnav_q8_8_t k_safe; /* safety steepness, per maximum range, Q8.8, (0, 64] */
} qnav_prob_params_t;

/*
 * Network policy (paper §3.3). Inputs x_theta = dtheta / 180 deg in [0, 1] and
 * x_d = level / (QNAV_DIST_LEVELS - 1) in [0, 1]. Hidden unit j:
 *   h_j = sigmoid(w_theta[j] * x_theta + w_dist[j] * x_d + b_hidden[j])
 * output: X = sigmoid(sum_j w_out[j] * h_j + b_out). All weights Q8.8 in [-128, 128).
 */
typedef struct {
    uint8_t hidden;                            /* H, 1..QNAV_MAX_HIDDEN */
    qnav_q8_8_t w_theta[QNAV_MAX_HIDDEN];      /* input weight of x_theta, Q8.8 */
    qnav_q8_8_t w_dist[QNAV_MAX_HIDDEN];       /* input weight of x_d, Q8.8 */
    qnav_q8_8_t b_hidden[QNAV_MAX_HIDDEN];     /* hidden bias, Q8.8 */
    qnav_q8_8_t w_out[QNAV_MAX_HIDDEN];        /* output weight of h_j, Q8.8 */
    qnav_q8_8_t b_out;                         /* output bias, Q8.8 */
} qnav_net_t;

typedef struct {
    uint8_t kind; /* a qnav_policy_kind_t */
    union {
        qnav_prob_params_t prob;
        qnav_net_t net;
    } u;
} qnav_policy_t;

/* Number of Q8.8 weights of a network with H hidden units: 4H + 1. */
#define QNAV_NET_WEIGHTS(h) (4u * (h) + 1u)

/* The hand-tuned probabilistic policy: k_goal = 1.0, k_safe = 4.0 (docs/architecture.md). */
void qnav_policy_prob_default(qnav_policy_t *policy);

/* A network of H hidden units with every weight zero (its quality is 0.5 everywhere).
 * H outside 1..QNAV_MAX_HIDDEN is clamped into it. */
void qnav_policy_net_zero(qnav_policy_t *policy, uint8_t hidden);

/* Weight k of a network in the flat order used by policy files and evolution:
 * for j in 0..H-1: w_theta[j], w_dist[j], b_hidden[j], w_out[j]; then b_out.
 * Returns a pointer to it, or 0 (null) when k >= 4H + 1. */
qnav_q8_8_t *qnav_net_weight(qnav_net_t *net, uint16_t k);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_POLICY_H */
