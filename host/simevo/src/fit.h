/*
 * A network fitted to a robot's hand-tuned probabilistic policy: the 2-input sigmoid
 * network whose path quality over every (distance level, dtheta) is the probabilistic
 * policy's, as a start that evolution can improve (docs/simevo.md, "A fitted start";
 * `[[source]] fit = "probabilistic"`, `simevo fit`).
 */
#ifndef QNAV_SIMEVO_FIT_H
#define QNAV_SIMEVO_FIT_H

#include <cstdint>
#include <string>

#include "qnav/ctrl.h"
#include "qnav/policy.h"

namespace qnav {

struct FitSettings {
    int hidden = 12;        /* hidden units, 1..QNAV_MAX_HIDDEN */
    int starts = 8;         /* random starts; the best fit is kept */
    int iterations = 6000;  /* full-batch Adam steps per start */
    uint64_t seed = 1;
};

struct FitResult {
    qnav_policy_t policy{}; /* the fit, rounded to Q8.8 */
    double rms = 0.0;       /* libqnav's quality of the rounded network against the target */
    double max = 0.0;
};

/* The network fitted by least squares (Adam from `starts` normal(0, 2) starts of one
 * seeded generator, the best kept; weights within the Q8.8 range) to the quality libqnav
 * gives `target` under controller configuration cfg, over all QNAV_DIST_LEVELS levels x
 * 181 dtheta. The same settings give the same policy. Throws UserError on a bad policy or
 * configuration. */
FitResult fit_network(const qnav_ctrl_config_t &cfg, const qnav_policy_t &target, const FitSettings &s);

/* Writes fit r as a policy file at path (atomically), its comment naming its units, robot,
 * maker (e.g. "simevo fit") and error. Throws UserError when it cannot. */
void write_fit(const std::string &path, const std::string &robot, const FitResult &r, const char *by);

} // namespace qnav

#endif
