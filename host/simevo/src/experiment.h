/*
 * Running a whole experiment: expand a spec into resumable tasks (per run: source
 * evolutions, transfers seeded from them, direct evolution from a random population; once:
 * the probabilistic policy on the held-out set), run them on a pool of threads (each with
 * its own simulator context and controllers), show progress on a terminal, then compute
 * the summary (final performance, episodes to 90%, improvement, significance), write
 * curves.csv / quality.csv / summary.json, draw the plots and write summary.md last.
 */
#ifndef QNAV_SIMEVO_EXPERIMENT_H
#define QNAV_SIMEVO_EXPERIMENT_H

#include <string>
#include <utility>
#include <vector>

#include "qnav/ctrl.h"

#include "spec.h"
#include "stats.h"
#include "task.h"

namespace qnav {

struct RunOptions {
    std::string out_dir = "runs";   /* experiment folder = out_dir/<name> */
    unsigned jobs = 0;              /* worker threads; 0 = all cores */
    int progress = -1;              /* 1 on, 0 off, -1 when stderr is a terminal */
    bool plots = true;              /* run tools/plot_*.py at the end */
    std::string tools_dir;          /* where plot_*.py live */
    std::string python = "/usr/bin/python3";
    bool use_table = true;          /* table-mode controller (bit-identical, faster) */
    std::string preset = "full";    /* recorded in the summary's command line */
    std::string overrides;          /* the command line's overrides (" --runs 3 ..."), also
                                       recorded there, so the line regenerates these results */
    std::string run_record;         /* run.txt: what `simevo summarize` rebuilds the spec
                                       from (written once, compared later); "" = none */
    std::string experiment_file;    /* the file run (run.txt's file), named by the summary's
                                       Regenerate line; "" = the experiment's name */
};

/* Target episodes after which a target run's best member is evaluated held out: the
 * spec's checkpoints within the budget and every checkpoint_every episodes, increasing. */
std::vector<uint64_t> checkpoint_grid(const ExperimentSpec &spec);

/* Tasks of an experiment, in an order where every source precedes its transfers. */
std::vector<TaskDef> plan_tasks(const ExperimentSpec &spec, const std::string &exp_dir);

/* Where a `fit` source's network is written in the experiment's folder. */
std::string fitted_source_path(const std::string &exp_dir, const SourceSpec &s);

/* Run tasks on `jobs` threads; a task with source_task waits for it. Each task is locked
 * (flock on its folder's .lock) while it runs. selected (empty = all) names the tasks to
 * run; the others belong to other processes, and a selected transfer whose source is not
 * selected needs that source's done file, else UserError. Throws UserError on the first
 * failure (others are stopped). */
void run_tasks(const std::vector<TaskDef> &tasks, const RunnerFactory &make, unsigned jobs,
               bool progress, const std::string &title, std::vector<char> selected = {});

/* Summary statistics of a finished experiment, from its task folders only. */

/* A mean with its 95% confidence interval (lo, hi). */
struct Interval {
    double mean = 0, lo = 0, hi = 0;
};
/* Mean of x with its Student-t 95% CI, clipped to [lo_bound, hi_bound]. */
Interval t_interval(const std::vector<double> &x, double lo_bound, double hi_bound);
/* successes / n with its Wilson score 95% CI. */
Interval wilson_interval(double successes, double n);

/* A run's folder: exp_dir/run-NNN (run 0-based, NNN 1-based). */
std::string run_dir(const std::string &exp_dir, uint32_t run);

/* Held-out performance of a condition's best members at one checkpoint, per run. */
struct CheckpointSummary {
    uint64_t checkpoint = 0;          /* target episodes */
    bool listed = false;              /* one of the spec's checkpoints (else only a point of
                                         the checkpoint_every grid, for the threshold) */
    std::vector<double> R, arrival, tau_c; /* per run: mean R, arrival fraction, recovery
                                             ticks per episode */
    Interval R_ci, arrival_ci, tau_c_ci;
    TestResult R_vs_direct;           /* Welch t on R, transfer vs direct */
    TestResult arrival_vs_direct;     /* Mann-Whitney on the arrival fractions */
};

/* The conditions an experiment compares, declared once (docs/simevo.md): what each is
 * and its label. Code asks a condition its kind, never compares label strings. */
enum class ConditionKind {
    Transfer,      /* evolved in the target from a source's best ("transfer-SOURCE") */
    Direct,        /* evolved in the target from a random population */
    Probabilistic, /* the hand-tuned probabilistic policy: a reference, not evolved */
    Vfh            /* VFH+ (libqnav's "vfh" controller): a second reference, no policy */
};
struct ConditionDecl {
    ConditionKind kind;
    const char *label;   /* the label, or its prefix for Transfer */
    bool evolved;        /* has runs, learning curves and checkpoints */
    const ReferenceDecl *reference; /* a reference's row of kReferences (task.h), or null */
};
/* Every condition: the two evolved ones, then one row per reference of kReferences in its
 * order (a reference without its row here stops the build: experiment_plan.cpp). */
constexpr std::size_t kConditionCount = 2 + kReferenceCount;
extern const ConditionDecl kConditions[kConditionCount];
const ConditionDecl &condition_decl(ConditionKind kind);
/* "transfer-" + source, "direct", "probabilistic". */
std::string condition_label(ConditionKind kind, const std::string &source = std::string());

struct ConditionSummary {
    ConditionKind kind = ConditionKind::Direct;
    std::string label;               /* condition_label(kind, source) */
    std::vector<double> final_per_run; /* held-out mean R per run (probabilistic: per episode) */
    double final_mean = 0, final_ci = 0, final_sd = 0;
    std::vector<double> curve_mean, curve_ci; /* candidates' R: per bin, mean over runs */
    std::vector<double> best_mean, best_ci;   /* population best's fitness at each bin's
                                                 end: mean over runs (the learned policy) */
    double start = 0;                /* first bin of the candidates' curve */
    double end = 0;                  /* last bin of the candidates' curve */
    double best_end = 0;             /* last point of the best-fitness curve */
    double episodes_to_90 = -1;      /* first bin end where the candidates' curve reaches
                                        start + 0.9 (end - start); -1 n/a */
    std::vector<double> online_per_run; /* mean episode R of all candidates of a run: the
                                           area under its learning curve */
    double online_mean = 0;
    int best_run = -1;               /* run whose best policy scored highest held out */
    double reached_rate = 0;         /* fraction of held-out episodes that reached the goal */
    /* What the robots do, held out: arrival fraction and recovery ticks per episode, per
     * run (probabilistic: per episode), with 95% CIs (runs: Student t over runs, clamped
     * to [0, 1]; probabilistic arrival: Wilson score interval). */
    std::vector<double> arrival_per_run, tau_c_per_run;
    std::vector<double> clean_per_run; /* arrived without a recovery (touching nothing), as
                                          arrival_per_run */
    Interval arrival, tau_c;
    std::vector<double> arrival_curve_mean, arrival_curve_ci; /* candidates' episodes that
                                                 arrived: per bin, mean over runs */
    std::vector<CheckpointSummary> checkpoints; /* target conditions only */
    /* Target episodes until the best member's held-out arrival first reached the
     * threshold, per run; NaN = not reached within the budget. */
    std::vector<double> to_threshold;
    uint32_t threshold_not_reached = 0;
    TestResult threshold_vs_direct;  /* Mann-Whitney, a run not reaching it ranked after
                                        every run that did */
};

struct Comparison {
    std::string a, b;
    ConditionKind b_kind = ConditionKind::Direct; /* what b is */
    double difference = 0;       /* mean_a - mean_b, R units */
    double improvement_pct = 0;  /* (mean_a - mean_b) / |mean_b| * 100; NaN when
                                    |mean_b| < 1 (a percentage of almost nothing) */
    double speedup_pct = 0;      /* (T90_b - T90_a) / T90_b * 100; NaN if n/a */
    std::string test;            /* "welch" (runs vs runs) or "one-sample" (runs vs the
                                    probabilistic policy's held-out mean) */
    TestResult t;                /* the t test named above */
    TestResult mann_whitney;     /* runs vs runs only */
    double online_difference = 0; /* online_mean_a - online_mean_b (runs vs runs only) */
    TestResult online;            /* Welch t on the runs' online means */
};

struct ExperimentSummary {
    std::vector<ConditionSummary> conditions; /* transfers, direct, probabilistic */
    std::vector<Comparison> comparisons;      /* each transfer vs direct, vs probabilistic */
    uint32_t curve_bin = 0;
    uint64_t episodes = 0;
    std::vector<uint64_t> bin_end;  /* target episodes at the end of each curve bin */
    uint32_t k = 1;                 /* episodes per candidate */
    double arrival_threshold = 0.8;
    uint32_t checkpoint_episodes = 0;
};

ExperimentSummary summarize(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks);

/* The situation an experiment's pictures (episodes.csv, quality.csv) are made in: the
 * target, or for a distribution target its first fixed environment, else the first named
 * environment of data/envs/. Throws UserError. */
Scenario picture_scenario(const Scenario &target);

/* Path quality over (distance level, dtheta) of each named policy, as libqnav computes it
 * (qnav_ctrl_quality): the quality.csv that tools/plot_policy.py draws. Throws UserError. */
std::string quality_table_csv(const std::vector<std::pair<std::string, qnav_policy_t>> &policies,
                              const qnav_ctrl_config_t &ccfg);
/* Run tools/<script> DIR with opt.python. Throws UserError when it fails. */
void run_plot(const RunOptions &opt, const std::string &script, const std::string &dir);

/* Where an experiment's best policy of one condition is copied (best-<condition>.policy
 * beside summary.md; written with the summary). */
std::string best_policy_copy(const std::string &exp_dir, const std::string &condition);

/* The three steps of a run. prepare: create OUT/<name>, refuse a folder with other
 * settings (settings.txt, run.txt), check every input; returns the plan. run: the selected
 * tasks (empty = all) on opt.jobs threads. finish: summary, curves, policies, plots. */
std::vector<TaskDef> prepare_experiment(const ExperimentSpec &spec, const RunOptions &opt);
void run_experiment_tasks(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, const RunOptions &opt,
                          const std::vector<char> &selected);
void finish_experiment(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, const RunOptions &opt);

/* Run a spec end to end (resuming what is there). Returns the experiment folder. Throws
 * UserError. */
std::string run_experiment(const ExperimentSpec &spec, const RunOptions &opt);

} // namespace qnav

#endif
