/*
 * What a finished experiment writes besides the summary's text: its best policies in the
 * held-out worlds, the quality map, the episode traces, the best policies' copies and
 * the plots. Private to the experiment runner.
 */
#ifndef QNAV_SIMEVO_EXPERIMENT_OUTPUTS_H
#define QNAV_SIMEVO_EXPERIMENT_OUTPUTS_H

#include <string>
#include <vector>

#include "experiment.h"
#include "heldout.h"
#include "sim_runner.h"

namespace qnav {

/* The held-out worlds of a finished experiment: every best policy and reference driven in
 * them (worlds.csv), their figures, and for a distribution target the recommended policy
 * (written to recommended.policy). */
HeldOut evaluate_held_out(const ExperimentSpec &spec, const ExperimentSummary &S, const std::string &exp_dir,
                          SimWorlds &worlds, const RunOptions &opt);

/* Everything after the runs but summary.md: curves, quality map, summary.json, episode
 * traces and the plots (STATUS says when plots are missing). Throws UserError. */
void write_outputs(const ExperimentSpec &spec, const ExperimentSummary &S, const std::vector<TaskDef> &tasks,
                   const std::string &exp_dir, SimWorlds &worlds, SimRunner &target_runner, const RunOptions &opt,
                   const HeldOut &H);

} // namespace qnav

#endif
