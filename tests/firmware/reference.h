/*
 * Double-precision reference of both policies, for tests only: the same quantized inputs
 * (distance level, whole-degree dtheta) as the controller, real arithmetic everywhere else.
 */
#ifndef QNAV_TEST_REFERENCE_H
#define QNAV_TEST_REFERENCE_H

#include "qnav/ctrl.h"

/* Quality in [0, 1] the policy gives (level, dtheta) in real arithmetic. */
double ref_quality(const qnav_policy_t *policy, unsigned level, unsigned dtheta);

/* The stated bound on |fixed-point quality - reference| for this policy
 * (docs/qformats.md, "error bound"). */
double ref_quality_bound(const qnav_policy_t *policy);

/* Output pre-activation y (X = sigmoid(y)) of a network policy in real arithmetic, and
 * the bound on |fixed-point y - reference| (docs/qformats.md, "error bound"). */
double ref_preact(const qnav_policy_t *policy, unsigned level, unsigned dtheta);
double ref_preact_bound(const qnav_policy_t *policy);

/* 1 when the policy is a network (its keys are pre-activations when ranked by them). */
int ref_is_network(const qnav_policy_t *policy);
/* 1 when ctrl ranks this policy's paths by the pre-activation: a network ranked so. */
int ref_ranks_by_preact(const qnav_ctrl_t *ctrl, const qnav_policy_t *policy);

/* Reference rank values of all 360 paths for a scan, using the controller's own input
 * quantization (qnav_ctrl_path_levels): the pre-activation for a network ranked by it,
 * else the quality. */
void ref_path_qualities(const qnav_ctrl_t *ctrl, const qnav_policy_t *policy,
                        const qnav_ctrl_input_t *in, double out[QNAV_PATHS]);

/* The ranges the step sees (docs/architecture.md, "The destination in reach"): in's, with
 * the reading under the destination's bearing taken as clear when it lies beyond the
 * destination by the body's margin or more. */
void ref_seen_ranges(const qnav_clearance_t *c, const qnav_ctrl_input_t *in,
                     qnav_mm_t seen[QNAV_MAX_SECTORS]);

/* Whole-degree destination bearing (0..359) as the controller rounds it. */
unsigned ref_goal_deg(qnav_cdeg_t bearing_cdeg);

/* Wrapped angular distance between path i and the goal degree, 0..180. */
unsigned ref_dtheta(unsigned path, unsigned goal);

#endif
