/*
 * Distributions of worlds: which concrete situation (world, sector count, noise level,
 * start point) an episode seed stands for when a scenario names a training distribution,
 * the runner that drives such a scenario (one simulator context per world, cached), and
 * the held-out worlds every summary reports: new test seeds of each generator family and
 * every named environment in data/envs/. Training, validation and test worlds come from
 * disjoint seed ranges (spec.h, WorldSet); docs/simevo.md, "Distributions of worlds".
 */
#ifndef QNAV_SIMEVO_WORLDS_H
#define QNAV_SIMEVO_WORLDS_H

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "evolution.h"
#include "spec.h"

namespace qnav {

/* The concrete situation one episode of a distribution runs in. */
struct WorldDraw {
    Scenario scenario;       /* no distribution: environment, sectors and noise set */
    uint64_t start_seed = 0; /* the episode seed of that situation (start point, noise) */
    std::size_t family = 0;  /* index into the distribution's families */
    uint64_t world_seed = 0; /* the generator's seed (0 for a fixed environment) */
};

/* The environment spec of a generated world: "gen:FAMILY:SEED:DIFFICULTY:ROBOT" (the
 * simulator's grammar, docs/sim.md), difficulty with two decimals. */
std::string family_env_spec(const std::string &family, uint64_t seed, double difficulty, const std::string &robot);

/* What episode_seed stands for in s (which must have a distribution): a component drawn by
 * weight, a world seed from s.worlds' range, a difficulty, sectors and noise when the
 * distribution draws them. A pure function of (s, episode_seed): a candidate and the
 * parent it is compared with, given the same episode seeds, meet the same worlds and
 * start points. */
WorldDraw draw_world(const Scenario &s, uint64_t episode_seed);

/* Creates the runner of one concrete scenario. */
using WorldRunnerFactory = std::function<std::unique_ptr<EpisodeRunner>(const Scenario &, uint64_t)>;

/* Drives a distribution scenario: each episode's world drawn by draw_world, its runner
 * made by make (the simulator, or a fake in tests) and kept in a small LRU cache, so the
 * parent re-run on a step's worlds reuses the candidate's contexts. */
class DistributionRunner : public EpisodeRunner {
public:
    DistributionRunner(const Scenario &scenario, uint64_t context_seed, WorldRunnerFactory make,
                       std::size_t cache_size = 16);
    EpisodeOutcome run(const qnav_policy_t &policy, uint64_t episode_seed) override;
    EpisodeOutcome run_controller(const char *controller, uint64_t episode_seed) override;
    qnav_policy_t probabilistic_policy() const override;

private:
    EpisodeRunner &runner_for(const Scenario &concrete);

    Scenario scenario_;
    uint64_t context_seed_;
    WorldRunnerFactory make_;
    std::size_t cache_size_;
    std::list<std::pair<std::string, std::unique_ptr<EpisodeRunner>>> cache_; /* most recent first */
    qnav_policy_t prob_{};
};

/* The named environments of data/envs/ (sorted names without .toml). Throws UserError. */
std::vector<std::string> named_environments();
/* The world generator's families (sorted as the simulator lists them). */
std::vector<std::string> world_families();

/* One column of the held-out worlds: a family's test worlds or a named environment. */
struct HeldOutWorld {
    std::string label;   /* "clutter" or "dense" */
    bool family = false; /* a generator family (else a named environment) */
    Scenario scenario;   /* family: a one-family distribution over test worlds, difficulty
                            [0, 1]; environment: that environment. Robot, sectors, noise,
                            fitness and controller are the target's. */
};
/* Label suffix of a family's test worlds judged at twice each world's time limit. */
inline constexpr const char *kTwiceLimitSuffix = "@2x";
/* Every family's test worlds, then (a distribution target) every family's test worlds at
 * twice each world's time limit ("clutter@2x"), then every named environment, for
 * target's held-out robot ([evaluation] robot, else its robot). */
std::vector<HeldOutWorld> held_out_worlds(const Scenario &target);

/* A scenario's held-out version: a distribution's validation worlds (the scenario itself
 * when it has no distribution: its held-out episodes are new start points), with its
 * held-out robot when it has one. */
Scenario validation_scenario(const Scenario &s);

} // namespace qnav

#endif
