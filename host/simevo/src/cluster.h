/*
 * An experiment on many processes or machines: the options of a run recorded in run.txt
 * (so `simevo summarize` rebuilds the same spec), shares of the task plan (`--tasks I/N`,
 * `--stage 1|2`: stage 1 is every task that needs no other task's result, stage 2 the
 * transfers seeded from a stage-1 source), the list of unfinished tasks, and the Slurm
 * scripts of `simevo slurm` (a stage-1 array, a stage-2 array after it, a summarize job).
 */
#ifndef QNAV_SIMEVO_CLUSTER_H
#define QNAV_SIMEVO_CLUSTER_H

#include <cstdint>
#include <string>
#include <vector>

#include "spec.h"
#include "task.h"

namespace qnav {

/* The command-line settings of `simevo run` that change results (0 / -1 / "" = the
 * file's value). */
struct RunArgs {
    std::string preset = "full";
    int64_t runs = 0, episodes = 0, source_episodes = 0, eval_episodes = 0, seed = -1, per_candidate = 0;
    std::string fitness, controller;
    std::string vary; /* "" or "KEY=VALUE": the target situation varied, the experiment
                         renamed NAME.KEY-VALUE (a sweep member; sweep.h) */
    bool network_mode = false;
};

/* The experiment file at path with args' preset and overrides. Throws UserError. */
ExperimentSpec load_run_spec(const std::string &path, const RunArgs &args);
/* The overrides as flags (" --runs 3 --fitness paper"); --network-mode is not one
 * (bit-identical to table mode by design). */
std::string override_flags(const RunArgs &args);
/* run.txt: the experiment file (absolute) and args but network_mode (bit-identical to
 * table mode, so not part of the results' identity), one "key = value" per line; the
 * "vary" line only when there is a variation (so older folders' run.txt still match). */
std::string run_record_text(const std::string &experiment_file, const RunArgs &args);
/* Parses run.txt text (path names it in errors); sets *experiment_file. Throws UserError. */
RunArgs parse_run_record(const std::string &text, const std::string &path, std::string *experiment_file);

/* One share of a plan: index 1..count of the tasks of stage (0 = both), in plan order with
 * stage 1 first, cut into count contiguous chunks (so shares run in order 1..count never
 * wait for a later share). */
struct Share {
    uint32_t index = 1, count = 1;
    int stage = 0;
};
/* "I/N" with 1 <= I <= N. Throws UserError naming --tasks. */
Share parse_share(const std::string &text, int stage);
int task_stage(const TaskDef &t);
std::vector<std::size_t> stage_tasks(const std::vector<TaskDef> &tasks, int stage);
std::vector<char> select_share(const std::vector<TaskDef> &tasks, const Share &share);

/* One line per task without its done file: "run-002/direct: not started" or
 * "...: started, not finished (failed, killed or still running; N journal lines)". */
std::vector<std::string> unfinished_tasks(const std::vector<TaskDef> &tasks, const std::string &exp_dir);

/* s in single quotes for sh. */
std::string sh_quote(const std::string &s);

struct SlurmOptions {
    std::string simevo;          /* absolute path of the simevo program */
    std::string experiment_file; /* absolute */
    std::string out_dir;         /* absolute; results in out_dir/<name> */
    std::string tools_dir;       /* absolute, for the summarize job's plots */
    bool plots = true;
    std::string partition, time; /* "" = the cluster's default */
    uint32_t array_limit = 0;    /* at most this many array tasks at once; 0 = no limit */
    uint32_t tasks_per_job = 1;  /* simevo tasks per array task */
    uint32_t jobs = 1;           /* threads (and --cpus-per-task) per array task */
};
/* Throws UserError (one line naming the option) when --partition or --time is not a
 * Slurm partition name or time limit, or out_dir holds a character an #SBATCH line
 * cannot carry (a control character, '"' or '\\'). */
void check_slurm_options(const SlurmOptions &o, const std::string &out_dir);
/* Writes sweep_dir/slurm/submit.sh, which runs every member's submit.sh in turn. Returns
 * its path. */
std::string write_sweep_submit(const std::string &sweep_dir, const std::vector<std::string> &member_scripts);
/* Writes exp_dir/slurm/{tasks.sbatch,summarize.sbatch,submit.sh}; a file there that
 * simevo did not write with this content is refused. Returns the submit.sh path. */
std::string write_slurm_scripts(const std::vector<TaskDef> &tasks, const std::string &exp_dir, const RunArgs &args,
                                const SlurmOptions &o);

} // namespace qnav

#endif
