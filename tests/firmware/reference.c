/*
 * Double-precision reference of the probabilistic and network policies (tests only).
 */
#include "reference.h"

#include <math.h>

static double sigmoid(double z) { return 1.0 / (1.0 + exp(-z)); }

double ref_preact(const qnav_policy_t *policy, unsigned level, unsigned dtheta)
{
    double xt = dtheta / 180.0;
    double xd = level / (double)(QNAV_DIST_LEVELS - 1);
    const qnav_net_t *n = &policy->u.net;
    double y = n->b_out / 256.0;
    for (unsigned j = 0; j < n->hidden; ++j) {
        double z = n->w_theta[j] / 256.0 * xt + n->w_dist[j] / 256.0 * xd + n->b_hidden[j] / 256.0;
        y += n->w_out[j] / 256.0 * sigmoid(z);
    }
    return y;
}

double ref_preact_bound(const qnav_policy_t *policy)
{
    const qnav_net_t *n = &policy->u.net;
    double sum_out = 0.0;
    for (unsigned j = 0; j < n->hidden; ++j) {
        sum_out += fabs(n->w_out[j] / 256.0);
    }
    /* as ref_quality_bound, before the output sigmoid; keys beyond |y| = 8 step by 1/128 */
    const double e_z = 1.0 / 4096 + 211.0 / 1048576.0;
    const double e_hidden = 0.25 * e_z + 1.0 / 32768 + 1e-6;
    return sum_out * e_hidden + n->hidden / 65536.0 + 1.0 / 4096;
}

double ref_quality(const qnav_policy_t *policy, unsigned level, unsigned dtheta)
{
    double xt = dtheta / 180.0;
    double xd = level / (double)(QNAV_DIST_LEVELS - 1);
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB: {
        double kg = policy->u.prob.k_goal / 256.0;
        double ks = policy->u.prob.k_safe / 256.0;
        return exp(-kg * xt) * (1.0 - exp(-ks * xd));
    }
    case QNAV_POLICY_NET:
        return sigmoid(ref_preact(policy, level, dtheta));
    }
    return 0.0;
}

/* The network's quality bound (see ref_quality_bound). */
static double net_quality_bound(const qnav_net_t *n)
{
    double sum_out = 0.0;
    for (unsigned j = 0; j < n->hidden; ++j) {
        sum_out += fabs(n->w_out[j] / 256.0);
    }
    /* docs/qformats.md: pre-activation rounding 2^-12 + weight rounding 211 * 2^-20,
     * times the largest slope 1/4, plus the table's rounding and interpolation 2^-15 */
    const double e_z = 1.0 / 4096 + 211.0 / 1048576.0;
    const double e_sig = 1.0 / 32768 + 1e-6;
    const double e_hidden = 0.25 * e_z + e_sig;
    const double e_share = 1.0 / 65536;    /* rounding of each unit's share */
    const double e_y = 1.0 / 4096;         /* rounding of the output to Q5.11 */
    return 0.25 * (sum_out * e_hidden + n->hidden * e_share + e_y) + e_sig;
}

double ref_quality_bound(const qnav_policy_t *policy)
{
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
        return 2.5e-4;
    case QNAV_POLICY_NET:
        return net_quality_bound(&policy->u.net);
    }
    return 0.0;
}

int ref_is_network(const qnav_policy_t *policy)
{
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
        return 0;
    case QNAV_POLICY_NET:
        return 1;
    }
    return 0;
}

int ref_ranks_by_preact(const qnav_ctrl_t *ctrl, const qnav_policy_t *policy)
{
    /* the probabilistic policy always ranks by its quality */
    return ref_is_network(policy) && qnav_ctrl_rank(ctrl) == QNAV_RANK_PREACT;
}

unsigned ref_goal_deg(qnav_cdeg_t bearing_cdeg)
{
    long d = lround(bearing_cdeg / 100.0);
    d %= 360;
    return (unsigned)(d < 0 ? d + 360 : d);
}

unsigned ref_dtheta(unsigned path, unsigned goal)
{
    unsigned d = (path + 360u - goal) % 360u;
    return d <= 180u ? d : 360u - d;
}

void ref_seen_ranges(const qnav_clearance_t *c, const qnav_ctrl_input_t *in,
                     qnav_mm_t seen[QNAV_MAX_SECTORS])
{
    unsigned k;
    /* the sector whose wedge holds the destination's whole-degree path */
    unsigned sector = qnav_ctrl_sector_of_path(c->n_sectors,
                                               (uint16_t)ref_goal_deg(in->goal_bearing_cdeg));
    for (k = 0; k < c->n_sectors; ++k) {
        seen[k] = in->ranges_mm[k];
    }
    if (in->goal_range_mm != 0u && seen[sector] < c->max_range_mm &&
        (double)seen[sector] + c->sensor_offset_mm >= (double)in->goal_range_mm + c->margin_mm) {
        seen[sector] = c->max_range_mm;
    }
}

void ref_path_qualities(const qnav_ctrl_t *ctrl, const qnav_policy_t *policy,
                        const qnav_ctrl_input_t *in, double out[QNAV_PATHS])
{
    unsigned goal = ref_goal_deg(in->goal_bearing_cdeg);
    uint8_t lvl[QNAV_PATHS];
    qnav_mm_t seen[QNAV_MAX_SECTORS];
    ref_seen_ranges(&ctrl->clr, in, seen);
    (void)qnav_ctrl_path_levels(ctrl, seen, lvl);
    for (unsigned i = 0; i < QNAV_PATHS; ++i) {
        out[i] = ref_ranks_by_preact(ctrl, policy)
                     ? ref_preact(policy, lvl[i], ref_dtheta(i, goal))
                     : ref_quality(policy, lvl[i], ref_dtheta(i, goal));
    }
}
