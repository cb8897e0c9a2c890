/*
 * Policies: what maps one path's two inputs (angular distance to the destination, distance
 * level of its sector) to a path quality. Two kinds share that shape (paper §3.2, §3.3):
 * the hand-tuned probabilistic policy and the evolved 2-input sigmoid network. A policy is
 * plain data that the caller owns; qnav_ctrl_init() checks it and derives what a step needs.
 */
#ifndef QNAV_POLICY_H
#define QNAV_POLICY_H

#include "qnav/check.h"
#include "qnav/fixed.h"
#include "qnav/qnav_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Policy kinds. Every place where the kind matters is a switch over this enum without a
 * default, so that -Wswitch names each place a new kind must be handled; the rules of a
 * valid policy live in qnav_policy_validate() only (docs/architecture.md, "Adding a
 * policy kind").
 */
typedef enum {
    QNAV_POLICY_PROB = 1, /* probabilistic navigation: X = P_goal(dtheta) * P_safe(d) */
    QNAV_POLICY_NET = 2   /* network: 2 or 3 inputs -> H sigmoid hidden -> 1 sigmoid output */
} qnav_policy_kind_t;

/* Results of qnav_policy_validate(). 0 is success, negatives are errors. */
typedef enum {
    QNAV_POLICY_OK = 0,
    QNAV_POLICY_E_NULL = -1,       /* no policy */
    QNAV_POLICY_E_KIND = -2,       /* kind is not a qnav_policy_kind_t */
    QNAV_POLICY_E_HIDDEN = -3,     /* network: hidden outside 1..QNAV_MAX_HIDDEN */
    QNAV_POLICY_E_INPUTS = -4,     /* network: inputs not 2 or 3 */
    QNAV_POLICY_E_PROB_PARAM = -5, /* probabilistic: k_goal or k_safe outside (0, 64] */
    QNAV_POLICY_E_KIND_DISABLED = -6 /* kind left out of this build (QNAV_WITH_NETWORK or
                                        QNAV_WITH_PROB 0, qnav/qnav_config.h) */
} qnav_policy_status_t;

/* Largest probabilistic parameter, 64.0 in Q8.8. */
#define QNAV_PROB_PARAM_MAX_RAW 16384

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

/* Inputs of a network: the paper's two, or those and the previous decision (§5). */
#define QNAV_NET_INPUTS_PAPER 2u
#define QNAV_NET_INPUTS_PREV 3u

/*
 * Network policy (paper §3.3). Inputs x_theta = dtheta / 180 deg in [0, 1] and
 * x_d = level / (QNAV_DIST_LEVELS - 1) in [0, 1]; with inputs = 3 also
 * x_prev = dprev / 180 deg in [0, 1], dprev the angular distance between the path and the
 * heading chosen at the previous tick (qnav_ctrl_input_t.prev_heading_cdeg; paper §5's
 * "information concerning earlier navigation decisions"). Hidden unit j:
 *   h_j = sigmoid(w_theta[j] * x_theta + w_dist[j] * x_d [+ w_prev[j] * x_prev] + b_hidden[j])
 * output: X = sigmoid(sum_j w_out[j] * h_j + b_out). All weights Q8.8 in [-128, 128).
 */
typedef struct {
    uint8_t hidden;                            /* H, 1..QNAV_MAX_HIDDEN */
    uint8_t inputs;                            /* 2 (paper) or 3 (previous decision) */
    qnav_q8_8_t w_theta[QNAV_MAX_HIDDEN];      /* input weight of x_theta, Q8.8 */
    qnav_q8_8_t w_dist[QNAV_MAX_HIDDEN];       /* input weight of x_d, Q8.8 */
    qnav_q8_8_t w_prev[QNAV_MAX_HIDDEN];       /* input weight of x_prev, Q8.8 (3 inputs) */
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

/* Number of Q8.8 weights of a 2-input network with H hidden units: 4H + 1. */
#define QNAV_NET_WEIGHTS(h) (4u * (h) + 1u)
/* Number of Q8.8 weights of a network with H hidden units and I inputs: (I + 2)H + 1. */
#define QNAV_NET_WEIGHTS_IN(h, i) (((i) + 2u) * (h) + 1u)

/* The hand-tuned probabilistic policy: k_goal = 1.0, k_safe = 4.0 (docs/architecture.md). */
void qnav_policy_prob_default(qnav_policy_t *policy);

/* A 2-input network of H hidden units with every weight zero (its quality is 0.5
 * everywhere). H outside 1..QNAV_MAX_HIDDEN is clamped into it. */
void qnav_policy_net_zero(qnav_policy_t *policy, uint8_t hidden);

/* The same with the previous-decision input: inputs 2 or 3 (anything else gives 2). */
void qnav_policy_net_zero_inputs(qnav_policy_t *policy, uint8_t hidden, uint8_t inputs);

/* Weight k of a network in the flat order used by policy files, links and evolution:
 * for j in 0..H-1: w_theta[j], w_dist[j], (w_prev[j] with 3 inputs,) b_hidden[j],
 * w_out[j]; then b_out. Returns a pointer to it, or 0 (null) when k is past the last
 * weight (QNAV_NET_WEIGHTS_IN(H, inputs)) or the shape is invalid. */
qnav_q8_8_t *qnav_net_weight(qnav_net_t *net, uint16_t k);

/* Number of weights of net (0 when its shape is invalid). */
uint16_t qnav_net_weight_count(const qnav_net_t *net);

/*
 * The one check of a policy: kind, shape and parameter ranges (what qnav_ctrl_init, the
 * policy reader, the link and the tools accept). Returns QNAV_POLICY_OK or a
 * qnav_policy_status_t error; QNAV_POLICY_E_KIND_DISABLED for a kind this build left out.
 */
QNAV_CHECK_RESULT qnav_policy_status_t qnav_policy_validate(const qnav_policy_t *policy);

/* One line of text for a status ("ok", "hidden units outside 1..QNAV_MAX_HIDDEN", ...);
 * never null. */
const char *qnav_policy_status_str(qnav_policy_status_t status);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_POLICY_H */
