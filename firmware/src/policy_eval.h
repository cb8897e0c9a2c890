/*
 * What the step (ctrl.c, ctrl_plain.c) calls in each policy kind's evaluation
 * (policy_<kind>.c), private to libqnav: one prototype block per kind. Adding a kind means
 * one block here, one file, and a case in every switch of ctrl.c and ctrl_plain.c that
 * -Wswitch names (docs/architecture.md, "Adding a policy kind").
 */
#ifndef QNAV_POLICY_EVAL_H
#define QNAV_POLICY_EVAL_H

#include "runs.h"

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

/* Derive the per-unit integer parameters into ctrl (network already validated); a 2-input
 * network's row shapes are left to qnav_shapes_take or qnav_net_eval_shapes. */
void qnav_net_eval_init(qnav_ctrl_t *ctrl, const qnav_net_t *net);
/* Compute the row shape of every level by evaluating every row (2 inputs). */
void qnav_net_eval_shapes(qnav_ctrl_t *ctrl);
/* ctrl_shapes.c: take carried row shapes (qnav_ctrl_init_carried); 1 when taken, 0 when
 * they are not this network's (the rows are then to be computed). */
uint8_t qnav_shapes_take(qnav_ctrl_t *ctrl, const qnav_net_t *net, const uint8_t *shapes,
                         uint16_t len);
/* The key of one (level, dtheta); a 3-input network with the path on the previous
 * heading (dprev = 0). */
qnav_qkey_t qnav_net_eval_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta);
/* The key of one path from its own inputs (dprev: its angular distance from the previous
 * heading, read by a 3-input network only): what the plain step evaluates. */
qnav_qkey_t qnav_net_eval_path_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta,
                                   uint8_t dprev);
/* Every path of it into best (best first when keys is null); keys as above. */
void qnav_net_eval_paths(const qnav_ctrl_t *ctrl, qnav_run_iter_t *it, qnav_best_t *best,
                         qnav_qkey_t *keys);
/* One table row (dtheta 0..180 at level) by the same additions as the step. */
void qnav_net_eval_row(const qnav_ctrl_t *ctrl, uint8_t level, qnav_qkey_t *row);

#endif /* QNAV_POLICY_EVAL_H */
