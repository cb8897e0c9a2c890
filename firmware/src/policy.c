/*
 * Policy helpers: the hand-tuned probabilistic defaults, an all-zero network, the flat
 * weight order that policy files, the link and evolution use to address a network's
 * weights, and the one validation of a policy that every reader and qnav_ctrl_init use
 * (which also refuses a kind that the build's QNAV_WITH_* switches left out).
 */
#include "qnav/policy.h"

void qnav_policy_prob_default(qnav_policy_t *policy)
{
    if (policy == 0) {
        return;
    }
    policy->kind = (uint8_t)QNAV_POLICY_PROB;
    policy->u.prob.k_goal = 256;  /* 1.0 in Q8.8 */
    policy->u.prob.k_safe = 1024; /* 4.0 in Q8.8 */
}

void qnav_policy_net_zero_inputs(qnav_policy_t *policy, uint8_t hidden, uint8_t inputs)
{
    uint8_t j;
    if (policy == 0) {
        return;
    }
    if (hidden < 1u) {
        hidden = 1u;
    }
    if (hidden > QNAV_MAX_HIDDEN) {
        hidden = QNAV_MAX_HIDDEN;
    }
    policy->kind = (uint8_t)QNAV_POLICY_NET;
    policy->u.net.hidden = hidden;
    policy->u.net.inputs = (uint8_t)(inputs == QNAV_NET_INPUTS_PREV ? QNAV_NET_INPUTS_PREV
                                                                    : QNAV_NET_INPUTS_PAPER);
    for (j = 0; j < QNAV_MAX_HIDDEN; ++j) {
        policy->u.net.w_theta[j] = 0;
        policy->u.net.w_dist[j] = 0;
        policy->u.net.w_prev[j] = 0;
        policy->u.net.b_hidden[j] = 0;
        policy->u.net.w_out[j] = 0;
    }
    policy->u.net.b_out = 0;
}

void qnav_policy_net_zero(qnav_policy_t *policy, uint8_t hidden)
{
    qnav_policy_net_zero_inputs(policy, hidden, QNAV_NET_INPUTS_PAPER);
}

static qnav_policy_status_t net_shape(const qnav_net_t *net)
{
    if (net->hidden < 1u || net->hidden > QNAV_MAX_HIDDEN) {
        return QNAV_POLICY_E_HIDDEN;
    }
    if (net->inputs != QNAV_NET_INPUTS_PAPER && net->inputs != QNAV_NET_INPUTS_PREV) {
        return QNAV_POLICY_E_INPUTS;
    }
    return QNAV_POLICY_OK;
}

uint16_t qnav_net_weight_count(const qnav_net_t *net)
{
    if (net == 0 || net_shape(net) != QNAV_POLICY_OK) {
        return 0;
    }
    return (uint16_t)QNAV_NET_WEIGHTS_IN((uint16_t)net->hidden, (uint16_t)net->inputs);
}

qnav_q8_8_t *qnav_net_weight(qnav_net_t *net, uint16_t k)
{
    uint16_t per_unit;
    uint16_t j;
    uint16_t slot;
    if (net == 0 || net_shape(net) != QNAV_POLICY_OK) {
        return 0;
    }
    per_unit = (uint16_t)(net->inputs + 2u);
    j = (uint16_t)(k / per_unit);
    slot = (uint16_t)(k % per_unit);
    if (j == net->hidden) {
        return (slot == 0u) ? &net->b_out : 0;
    }
    if (j > net->hidden) {
        return 0;
    }
    if (net->inputs == QNAV_NET_INPUTS_PAPER && slot >= 2u) {
        ++slot; /* no w_prev: b_hidden and w_out move up one */
    }
    switch (slot) {
    case 0u:
        return &net->w_theta[j];
    case 1u:
        return &net->w_dist[j];
    case 2u:
        return &net->w_prev[j];
    case 3u:
        return &net->b_hidden[j];
    default:
        return &net->w_out[j];
    }
}

static qnav_policy_status_t prob_params(const qnav_prob_params_t *p)
{
    if (p->k_goal <= 0 || p->k_goal > QNAV_PROB_PARAM_MAX_RAW || p->k_safe <= 0 ||
        p->k_safe > QNAV_PROB_PARAM_MAX_RAW) {
        return QNAV_POLICY_E_PROB_PARAM;
    }
    return QNAV_POLICY_OK;
}

qnav_policy_status_t qnav_policy_validate(const qnav_policy_t *policy)
{
    if (policy == 0) {
        return QNAV_POLICY_E_NULL;
    }
    /* a kind this build left out is refused here, so no controller ever holds it */
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
        return QNAV_WITH_PROB ? prob_params(&policy->u.prob) : QNAV_POLICY_E_KIND_DISABLED;
    case QNAV_POLICY_NET:
        return QNAV_WITH_NETWORK ? net_shape(&policy->u.net) : QNAV_POLICY_E_KIND_DISABLED;
    }
    return QNAV_POLICY_E_KIND;
}

const char *qnav_policy_status_str(qnav_policy_status_t status)
{
    switch (status) {
    case QNAV_POLICY_OK:
        return "ok";
    case QNAV_POLICY_E_NULL:
        return "no policy (null pointer)";
    case QNAV_POLICY_E_KIND:
        return "unknown policy kind";
    case QNAV_POLICY_E_HIDDEN:
        return "hidden units outside 1..QNAV_MAX_HIDDEN";
    case QNAV_POLICY_E_INPUTS:
        return "network inputs neither 2 nor 3";
    case QNAV_POLICY_E_PROB_PARAM:
        return "probabilistic k_goal or k_safe outside (0, 64]";
    case QNAV_POLICY_E_KIND_DISABLED:
        return "policy kind left out of this build (QNAV_WITH_NETWORK or QNAV_WITH_PROB is 0)";
    }
    return "unknown policy status";
}
