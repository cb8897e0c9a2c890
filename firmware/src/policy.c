/*
 * Policy helpers: the hand-tuned probabilistic defaults, an all-zero network, and the flat
 * weight order that policy files and evolution use to address a network's weights.
 */
#include "qnav/policy.h"

void qnav_policy_prob_default(qnav_policy_t *policy)
{
    if (policy == 0) {
        return;
    }
    policy->kind = (uint8_t)QNAV_POLICY_PROB;
    policy->u.prob.k_goal = QNAV_Q8_8(1.0);
    policy->u.prob.k_safe = QNAV_Q8_8(4.0);
}

void qnav_policy_net_zero(qnav_policy_t *policy, uint8_t hidden)
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
    for (j = 0; j < QNAV_MAX_HIDDEN; ++j) {
        policy->u.net.w_theta[j] = 0;
        policy->u.net.w_dist[j] = 0;
        policy->u.net.b_hidden[j] = 0;
        policy->u.net.w_out[j] = 0;
    }
    policy->u.net.b_out = 0;
}

qnav_q8_8_t *qnav_net_weight(qnav_net_t *net, uint16_t k)
{
    uint16_t j;
    if (net == 0 || net->hidden < 1u || net->hidden > QNAV_MAX_HIDDEN) {
        return 0;
    }
    j = (uint16_t)(k / 4u);
    if (j == net->hidden) {
        return (k % 4u == 0u) ? &net->b_out : 0;
    }
    if (j > net->hidden) {
        return 0;
    }
    switch (k % 4u) {
    case 0u:
        return &net->w_theta[j];
    case 1u:
        return &net->w_dist[j];
    case 2u:
        return &net->b_hidden[j];
    default:
        return &net->w_out[j];
    }
}
