/*
 * The summary of a finished experiment as text: curves.csv, summary.json and summary.md
 * (docs/simevo.md, "Outputs"). Private to the experiment runner.
 */
#ifndef QNAV_SIMEVO_EXPERIMENT_REPORT_H
#define QNAV_SIMEVO_EXPERIMENT_REPORT_H

#include <string>

#include "experiment.h"
#include "heldout.h"

namespace qnav {

/* curves.csv: every condition's binned learning curves with their 95% CIs. */
std::string curves_csv(const ExperimentSummary &S);
/* summary.json: settings, conditions, comparisons, references and held-out worlds.
 * env_file and robot_radius_m describe the pictures' environment and the target's robot. */
std::string summary_json(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt,
                         const std::string &env_file, double robot_radius_m, const HeldOut &H);
/* summary.md: the same for a reader, with the plots linked when plots is set. */
std::string summary_md(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt, bool plots,
                       const HeldOut &H);

} // namespace qnav

#endif
