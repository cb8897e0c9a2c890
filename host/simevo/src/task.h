/*
 * One unit of work of an experiment, resumable: an evolution in one situation (source,
 * transfer or direct; with or without a held-out evaluation of its best policy), or the
 * held-out evaluation of the probabilistic policy. A task lives in its own folder:
 *   task.txt      the resolved settings (a resumed task must match them exactly)
 *   episodes.csv  the journal: one line per evolution step (a candidate scored on k
 *                 episodes), appended with one write(); a kill leaves at most a partial
 *                 last line, which resume drops
 *   checkpoints.csv  held-out evaluations of the best member after given numbers of
 *                 target episodes (journaled the same way; target tasks only)
 *   best.policy   the best member at the end (policy file, atomic)
 *   eval.csv      held-out episodes of the best (or probabilistic) policy (atomic)
 *   eval-vfh.csv  the reference task only: VFH+ on the same held-out episodes (atomic)
 *   done          written last (atomic): the task is complete
 * Resuming replays the journal through the search (evolution.h: same draws, recorded R
 * values) without simulating, so the finished files equal those of an uninterrupted run
 * byte for byte.
 */
#ifndef QNAV_SIMEVO_TASK_H
#define QNAV_SIMEVO_TASK_H

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "evolution.h"
#include "spec.h"

namespace qnav {

enum class TaskKind { Evolve, EvalProbabilistic };
/* The kind as task.txt spells it ("evolve", "eval-probabilistic+vfh"). */
const char *task_kind_name(TaskKind k);

/* The second reference the EvalProbabilistic task runs: libqnav's controller of this name
 * (VFH+), journaled as <task dir>/kVfhEvalStem.csv. One home for both names. */
constexpr const char *kVfhController = "vfh";
constexpr const char *kVfhEvalStem = "eval-vfh";

/* The references every experiment compares against, one row each: what a reference is,
 * how it is evaluated and how it is plotted. The reference task (EvalProbabilistic) runs
 * every row on the held-out episodes in this order; summaries, pictures, held-out worlds
 * and tools/plot_learning.py (through summary.json "references") read the same rows. A new
 * reference is a row here and its ConditionKind (experiment.h), whose switch the compiler
 * checks (docs/simevo.md, "References"). */
struct ReferenceDecl {
    const char *label;      /* condition label in every output, e.g. "vfh" */
    const char *controller; /* libqnav controller (qnav/nav.h) it runs without a policy, or
                               nullptr: the robot's probabilistic policy through the
                               path-quality controller */
    const char *eval_stem;  /* its held-out episodes: <reference task dir>/STEM.csv */
    const char *plot_name;  /* legend text */
    const char *plot_style; /* matplotlib line style of its held-out band */
    const char *plot_color; /* matplotlib colour */
};
constexpr ReferenceDecl kReferences[] = {
    {"probabilistic", nullptr, "eval", "probabilistic (held out)", "--", "tab:gray"},
    {kVfhController, kVfhController, kVfhEvalStem, "VFH+ (held out)", ":", "tab:brown"},
};
constexpr std::size_t kReferenceCount = sizeof kReferences / sizeof kReferences[0];

/* One episode of reference r on runner: its controller, or the runner's probabilistic
 * policy. */
EpisodeOutcome run_reference(EpisodeRunner &runner, const ReferenceDecl &r, uint64_t episode_seed);

struct TaskDef {
    TaskKind kind = TaskKind::Evolve;
    std::string dir;                 /* output folder */
    std::string label;               /* condition, e.g. "transfer-open", "direct" */
    uint32_t run = 0;                /* run index, 0-based */
    Scenario scenario;
    uint64_t context_seed = 1;       /* qnav_sim_config_t.seed */
    uint64_t episodes = 0;           /* evolution budget in simulated candidate episodes:
                                        task_steps() steps of k episodes each */
    EvolutionParams evolution;
    uint64_t evolution_seed = 0;     /* seeds the search's Rng */
    uint64_t episode_seed_base = 0;  /* episode j of step s runs with mix_seed(base, s*k+j),
                                        for the candidate and the re-evaluated parent */
    int source_task = -1;            /* index of the task whose best.policy seeds this */
    std::string source_policy_file;  /* or a policy file that seeds it */
    uint32_t eval_episodes = 0;      /* held-out evaluation of the best; 0 = none */
    uint64_t eval_seed_base = 0;     /* held-out episode i runs with mix_seed(base, i) */
    std::vector<uint64_t> checkpoints; /* target episodes (increasing, <= episodes) after
                                          which the best member is evaluated held out */
    uint32_t checkpoint_episodes = 0;  /* the first this many held-out episodes */
};

/* Evolution steps of a task: budget / k rounded up (so a step may end up to k - 1
 * episodes past the budget), at least 1. */
uint64_t task_steps(const TaskDef &t);

/* Creates the runner a task uses (the simulator, or a fake in tests). */
using RunnerFactory = std::function<std::unique_ptr<EpisodeRunner>(const Scenario &, uint64_t)>;

/* Progress callbacks (thread-safe implementations required). */
struct TaskObserver {
    std::function<void(uint64_t n, bool replayed)> episodes_done; /* n more episodes */
    std::function<void(const std::string &label, double best_R)> best;
};

/* A policy file (qnav_policy_read). Throws UserError naming the file. */
qnav_policy_t read_policy_file(const std::string &path);
/* A policy file that can seed a transfer (a network with 1..QNAV_MAX_HIDDEN hidden
 * units). Throws UserError naming the file. */
qnav_policy_t load_source_policy(const std::string &path);

/* Run (or resume, or skip if done) a task. source_policy_path is the file that seeds a
 * transfer ("" for none). stop is polled between episodes. Throws UserError. Returns
 * true when complete, false when stopped. */
bool run_task(const TaskDef &t, const std::string &source_policy_path, const RunnerFactory &make,
              const TaskObserver &obs, const std::atomic<bool> &stop);

/* Episodes a task runs in all (evolution plus held-out evaluation), for progress totals. */
uint64_t task_total_episodes(const TaskDef &t);

/* Reading finished task outputs. Throw UserError on malformed files. */
/* An episode journal's columns, one entry per step: the candidate's mean R over its k
 * episodes, how many of them arrived, and the population best's fitness after it. */
struct JournalColumns {
    std::vector<double> R, best_fitness;
    std::vector<uint32_t> arrived;
};
JournalColumns read_journal(const std::string &csv_path);
/* One held-out evaluation of the best member at a checkpoint. */
struct CheckpointRow {
    uint64_t checkpoint = 0; /* nominal target episodes */
    uint64_t episodes = 0;   /* target episodes actually run (the first step's end >= it) */
    uint32_t n = 0;          /* held-out episodes */
    double R = 0;            /* their mean R */
    uint32_t arrived = 0;    /* how many reached the destination */
    uint64_t tau_c = 0;      /* their recovery ticks, summed */
};
std::vector<CheckpointRow> read_checkpoints(const std::string &csv_path);
std::vector<EpisodeOutcome> read_eval(const std::string &csv_path);

/* The canonical settings text written to task.txt. */
std::string task_settings_text(const TaskDef &t, const std::string &source_fingerprint);

} // namespace qnav

#endif
