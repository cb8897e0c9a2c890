/*
 * Held-out worlds of an experiment (docs/simevo.md, "Held-out worlds"): every evolved
 * condition's best policy of every run, and the references (the probabilistic policy,
 * VFH+), driven in the test worlds of every generator family and in every named
 * environment of data/envs/, on the same episode seeds in every experiment; the figures
 * per condition and world (arrival, recovery ticks, R with 95% CIs: the summary's
 * cross-environment matrix); and, for a distribution target, the policy recommended across
 * runs by its arrival in the validation worlds (never by training scores).
 */
#ifndef QNAV_SIMEVO_HELDOUT_H
#define QNAV_SIMEVO_HELDOUT_H

#include <cstdint>
#include <string>
#include <vector>

#include "experiment.h"
#include "worlds.h"

namespace qnav {

/* One policy (or reference) in one held-out world: n episodes summed. */
struct WorldRow {
    std::string condition; /* condition label */
    uint32_t run = 0;      /* 1-based run of an evolved condition; 0 for a reference */
    std::string world;     /* HeldOutWorld label */
    uint32_t n = 0;        /* episodes */
    double R = 0;          /* mean R */
    double R_sd = 0;       /* sample standard deviation of R over the n episodes */
    uint32_t arrived = 0;  /* episodes that reached the destination */
    uint64_t tau_c = 0;    /* recovery ticks, summed */
    double tau_c_sd = 0;   /* sample standard deviation of the ticks per episode */
};

/* Episode i of every held-out world runs with mix_seed(kHeldOutWorldsSeed, i): the same
 * set in every experiment, so their matrices compare. */
extern const uint64_t kHeldOutWorldsSeed;

/* Drive every evolved condition's per-run best policy and both references in every world
 * for spec.worlds_episodes episodes, on `jobs` threads (0 = all cores); make creates the
 * runner of a concrete scenario. Rows in a fixed order whatever the threads. Throws
 * UserError. */
std::vector<WorldRow> evaluate_held_out_worlds(const ExperimentSpec &spec, const ExperimentSummary &S,
                                               const std::string &exp_dir, const std::vector<HeldOutWorld> &worlds,
                                               const WorldRunnerFactory &make, unsigned jobs);

/* worlds.csv: condition,run,world,n,R,R_sd,arrived,tau_c,tau_c_sd. */
std::string world_rows_csv(const std::vector<WorldRow> &rows);
std::vector<WorldRow> read_world_rows(const std::string &csv_path);

/* One condition in one world: evolved conditions, 95% CIs over runs (Student t); a
 * reference, over episodes (arrival: Wilson). */
struct WorldCell {
    std::string world;
    bool family = false;
    Interval R, arrival, tau_c;
    uint32_t runs = 0;     /* policies behind it (1 for a reference) */
    uint32_t episodes = 0; /* per policy */
};
struct ConditionWorlds {
    std::string label;
    bool evolved = false;
    std::vector<WorldCell> cells; /* in the worlds' order */
};
std::vector<ConditionWorlds> summarize_worlds(const ExperimentSummary &S, const std::vector<HeldOutWorld> &worlds,
                                              const std::vector<WorldRow> &rows);

/* The policy recommended across runs: of every evolved target condition's per-run best,
 * the one that arrived without touching anything in the most validation episodes (its
 * eval.csv), ties by arrival, then by mean R, then by condition order and run; but the
 * robot's probabilistic policy (the reference on the same validation episodes) when no
 * evolved policy is ahead of it by the same order (docs/simevo.md, "The recommended
 * policy"). Its test figures per world (CIs over its episodes). */
struct Recommendation {
    bool valid = false;
    std::string condition;           /* an evolved condition, or the reference's label */
    uint32_t run = 0;                /* 1-based; 0: the probabilistic policy */
    double validation_clean = 0;     /* fraction that arrived without touching anything */
    double validation_arrival = 0;   /* fraction */
    double validation_R = 0;
    double validation_tau_c = 0;     /* recovery ticks an episode */
    uint32_t validation_episodes = 0;
    std::vector<WorldCell> test;     /* per held-out world */
    /* The candidate not recommended, on the same validation episodes: the probabilistic
     * policy, or the best evolved run when the probabilistic policy is recommended. */
    bool has_other = false;
    std::string other_condition;
    uint32_t other_run = 0;
    double other_clean = 0;
    double other_arrival = 0;
    double other_R = 0;
    double other_tau_c = 0;
    bool reference() const { return run == 0; }
};
Recommendation recommend(const ExperimentSummary &S, const std::vector<HeldOutWorld> &worlds,
                         const std::vector<WorldRow> &rows, uint32_t validation_episodes);

/* What a summary reports of the held-out worlds. */
struct HeldOut {
    uint32_t episodes = 0;                  /* per policy and world */
    std::vector<HeldOutWorld> worlds;       /* the columns */
    std::vector<std::string> skipped;       /* "NAME: why": named environments the robot
                                               cannot start in (e.g. a larger body) */
    std::vector<ConditionWorlds> conditions;
    Recommendation recommended;             /* valid for a distribution target */
};

/* Where the recommended policy is written: OUT/<experiment>/recommended.policy. */
std::string recommended_policy_path(const std::string &exp_dir);

/* One line per held-out world: "NAME: recommended POLICY ... test WORLD: arrival ...". */
std::vector<std::string> recommendation_lines(const std::string &name, const Recommendation &r,
                                              const std::string &exp_dir);

} // namespace qnav

#endif
