/*
 * The plain reference step (qnav_ctrl_step_plain): what qnav_ctrl_step() computes, without
 * its shortcuts. Every one of the 360 paths gets its key from its own inputs, the best is
 * kept under the controller's total order (qnav_best_consider: key, then smaller dtheta,
 * then smaller turn, then counter-clockwise), and the command comes from the same
 * qnav_ctrl_decide() as the fast step's. Start reading the step here; the fast one
 * (ctrl.c, runs.c, policy_<kind>.c) must decide exactly as this one does
 * (tests/firmware/test_ctrl.c, tests/target/shared_vectors.c). Its own translation unit, so
 * that a firmware that does not call it does not link it.
 */
#include "qnav/ctrl.h"
#include "clearance.h"
#include "escape.h"
#include "policy_eval.h"
#include "qnav/flash.h"

/* The key of a path at distance level `level`, dtheta from the goal and dprev from the
 * previous heading: the compiled table's entry, or the policy kind's evaluation. */
static qnav_qkey_t path_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta,
                            uint8_t dprev)
{
    const qnav_qkey_t *table = qnav_table_of(ctrl);
    if (table != 0) {
        return QNAV_FLASH_READ_I16(&table[(uint16_t)level * QNAV_TABLE_STRIDE + dtheta]);
    }
    (void)dprev;
    switch ((qnav_policy_kind_t)ctrl->kind) {
    case QNAV_POLICY_PROB:
#if QNAV_WITH_PROB
        return qnav_prob_eval_key(ctrl, level, dtheta);
#endif
        break;
    case QNAV_POLICY_NET:
#if QNAV_WITH_NETWORK
        return qnav_net_eval_path_key(ctrl, level, dtheta, dprev);
#endif
        break;
    }
    return QNAV_KEY_NONE + 1;
}

void qnav_ctrl_step_plain(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                          qnav_ctrl_output_t *out, qnav_q1_15_t *qualities)
{
    uint8_t lvl[QNAV_PATHS];
    qnav_best_t best = {QNAV_KEY_NONE, 0, 0};
    uint8_t flags;
    uint16_t goal;
    uint16_t prev;
    uint16_t path;

    if (out == 0) {
        return;
    }
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || in == 0 || in->ranges_mm == 0) {
        qnav_ctrl_stop(out, QNAV_FLAG_NOT_READY, qualities);
        return;
    }
    flags = qnav_clearance_input_levels(&ctrl->clr, in, lvl);
    goal = qnav_escape_goal(&ctrl->clr, lvl, in, &out->escape);
    prev = qnav_whole_deg(in->prev_heading_cdeg);
    for (path = 0; path < QNAV_PATHS; ++path) {
        uint8_t dtheta = qnav_angle_dist_deg(path, goal);
        qnav_qkey_t key = path_key(ctrl, lvl[path], dtheta, qnav_angle_dist_deg(path, prev));
        if (qualities != 0) {
            qualities[path] = qnav_ctrl_key_quality(ctrl, key);
        }
        qnav_best_consider(&best, key, path, dtheta);
    }
    qnav_ctrl_decide(ctrl, lvl, goal, prev, flags, &best, out);
}
