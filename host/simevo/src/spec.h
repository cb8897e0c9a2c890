/*
 * Experiment specifications: the TOML files in experiments/ that describe one of the
 * paper's transfer experiments (target situation, source situations, evolution settings,
 * runs, held-out evaluation, presets). Parsing checks every key and value and reports the
 * first problem as "FILE:LINE: what is wrong"; unknown keys are errors, so a typo never
 * silently falls back to a default. Format: docs/simevo.md, "Experiment files".
 */
#ifndef QNAV_SIMEVO_SPEC_H
#define QNAV_SIMEVO_SPEC_H

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "evolution.h"
#include "qnav/sim.h"
#include "qnav/one_line.hpp"

namespace qnav {

/* One-line, user-facing error ("FILE:LINE: problem" or "OPTION: problem"). */
class UserError : public std::runtime_error {
public:
    /* one line whatever the message quotes: control characters escaped (one_line()) */
    explicit UserError(const std::string &message) : std::runtime_error(one_line(message)) {}
};

/* How the controller reads the paper (docs/architecture.md): Body = obstacles enlarged by
 * the robot's radius + safety distance, speed guard, networks ranked by pre-activation;
 * Literal = each path sees its own sector, no guard, ranked by quality (the ablation). */
enum class ControllerReading { Body, Literal };

/* Every reading, in the order their names are listed. Each is a row of libqnav's
 * controller table that takes a policy (qnav/nav.h; tests/simevo/test_evolution.cpp checks
 * it), named by controller_reading_name. */
constexpr ControllerReading kControllerReadings[] = {ControllerReading::Body,
                                                     ControllerReading::Literal};
/* "body" / "literal". */
const char *controller_reading_name(ControllerReading c);
/* Every reading's name, ", " between them ("body, literal"), for help and messages. */
std::string controller_reading_names();
/* Parses a name; false when it is not one. */
bool controller_reading_parse(const std::string &name, ControllerReading *out);

/* Which worlds of a distribution an episode is drawn from. Training worlds come from the
 * distribution's seed range (below kValidationSeedBase), validation worlds from
 * [kValidationSeedBase, kTestSeedBase), test worlds from [kTestSeedBase, kTestSeedBase +
 * kHeldOutSeedSpan): disjoint by construction (docs/simevo.md, "Held-out worlds"). */
enum class WorldSet { Training, Validation, Test };
constexpr uint64_t kValidationSeedBase = 1000000;
constexpr uint64_t kTestSeedBase = 2000000;
constexpr uint64_t kHeldOutSeedSpan = 1000000;
/* "training", "validation", "test". */
const char *world_set_name(WorldSet w);

/* One component of a distribution of worlds: a family of the simulator's world generator
 * (environment "gen:FAMILY:SEED:DIFFICULTY:ROBOT", a new world per seed) or one fixed
 * environment (only the start point varies). */
struct FamilySpec {
    std::string family;        /* generator family, or "" for a fixed environment */
    std::string environment;   /* fixed environment (name or file), or "" for a family */
    double weight = 1.0;       /* relative probability, > 0 */
    double difficulty_lo = 0.0, difficulty_hi = 1.0; /* drawn uniformly, in [0, 1] */

    /* "clutter" or "env:dense": the family's label in summaries. */
    std::string label() const;
};

/* A training distribution: each episode draws a component by weight, a world seed from
 * the set's range, a difficulty, and optionally a sector count and a noise level. */
struct Distribution {
    std::string name;                   /* [distribution.NAME] */
    std::vector<FamilySpec> families;   /* at least one */
    uint64_t seed_lo = 0, seed_hi = kValidationSeedBase - 1; /* training world seeds,
                                           inclusive, below kValidationSeedBase */
    std::vector<uint32_t> sectors;      /* one drawn per episode; empty = the scenario's */
    bool noise_drawn = false;           /* p drawn uniformly in [noise_lo, noise_hi] for
                                           sensor and actuation alike, per episode */
    double noise_lo = 0.0, noise_hi = 0.0;

    /* Canonical one-line description (part of task fingerprints). */
    std::string describe() const;
};

/* The situation a policy is evolved or evaluated in. */
struct Scenario {
    std::string environment = "dense"; /* sim environment: name or file */
    std::string robot = "tekbot";       /* sim robot profile: name or file */
    uint32_t sectors = 0;               /* sonar sectors, 1..360; 0 = the robot's default */
    double sensor_noise = 0.0;          /* p_s, fraction (0.05 = 5 %) */
    double actuation_noise = 0.0;       /* p_a, fraction */
    double episode_limit_s = 0.0;       /* s; 0 = the environment's limit */
    double limit_factor = 1.0;          /* the limit above (or each world's) times this:
                                           held-out worlds judged at twice the limit */
    qnav_sim_fitness_rule_t fitness = QNAV_SIM_FITNESS_PROGRESS; /* how R is computed;
                                           set for every scenario from [evolution] fitness */
    ControllerReading controller = ControllerReading::Body; /* set for every scenario from
                                           [evolution] controller */
    /* Set: every episode is drawn from this distribution (environment unused) out of the
     * worlds of `worlds`; the episode seed fixes the world and the start point. */
    std::shared_ptr<const Distribution> distribution;
    WorldSet worlds = WorldSet::Training;
    /* The robot of held-out episodes (validation, test, named environments, checkpoints):
     * [evaluation] robot, e.g. the robot with its map while evolution runs without it;
     * "" = robot. */
    std::string held_out_robot;

    /* Canonical one-line description (also part of task fingerprints). */
    std::string describe() const;
};

/* A source situation whose best policy seeds a transfer population. */
struct SourceSpec {
    std::string label;        /* short name: condition "transfer-<label>" */
    Scenario scenario;        /* fields not given inherit from [target] */
    uint64_t episodes = 1000; /* evolution episodes in the source situation */
    std::string policy_file;  /* non-empty: transfer from this file, no source evolution */
    std::string fit;          /* "probabilistic": transfer from the network fitted to the
                                 target robot's probabilistic policy (fit.h), no evolution */
    /* evolved: no policy file and no fit */
    bool evolved() const { return policy_file.empty() && fit.empty(); }
    /* What the source is, for summaries: its situation, a policy file or the fit. */
    std::string describe() const;
};

struct Preset {
    std::optional<uint32_t> runs;
    std::optional<uint64_t> episodes;        /* target episodes */
    std::optional<uint64_t> source_episodes;
    std::optional<uint32_t> eval_episodes;
    std::optional<uint32_t> curve_bin;
    std::optional<uint32_t> checkpoint_episodes;
    std::optional<uint32_t> worlds_episodes;
};

struct ExperimentSpec {
    std::string file;            /* where it was read from */
    std::string name;            /* identifier, [a-z0-9-] */
    std::string title;           /* one line for plots and summaries */
    std::string figure;          /* paper figure it reproduces, e.g. "Fig. 7" */
    uint32_t runs = 30;          /* independent runs per condition */
    uint64_t seed = 1;           /* master seed: everything random derives from it */
    uint32_t curve_bin = 20;     /* episodes per learning-curve point */
    EvolutionParams evolution;
    Scenario target;
    uint64_t target_episodes = 1000;
    std::vector<SourceSpec> sources;
    uint32_t eval_episodes = 50; /* held-out evaluation episodes per best policy */
    uint64_t eval_seed = 0x5eed;  /* seeds the held-out episode set (same for all runs) */
    /* Transfer at equal budgets ([evaluation], docs/simevo.md "Checkpoints"): the best
     * member of every target run is evaluated on the first checkpoint_episodes held-out
     * episodes after these target episodes (beyond the budget: dropped) and after every
     * checkpoint_every episodes (0 = not), the latter to find when its held-out arrival
     * first reaches arrival_threshold. */
    std::vector<uint64_t> checkpoints = {100, 250, 500, 1000};
    uint64_t checkpoint_every = 50;
    uint32_t checkpoint_episodes = 20;
    double arrival_threshold = 0.8; /* fraction; the file gives percent */
    std::map<std::string, Preset> presets;
    std::map<std::string, std::shared_ptr<const Distribution>> distributions; /* by name */
    /* Held-out worlds ([evaluation] worlds_episodes): episodes per best policy in each
     * family's test worlds and each named environment (summary "Held-out worlds"). */
    uint32_t worlds_episodes = 20;
};

/* An identifier of an experiment, source or sweep: 1-64 characters a-z, 0-9, '-', '_'. */
bool valid_name(const std::string &s);
/* Parse a spec from text; name is used in messages. Throws UserError. */
ExperimentSpec parse_experiment(const std::string &text, const std::string &name);
/* Read and parse a file. Throws UserError (missing file, parse error). */
ExperimentSpec load_experiment(const std::string &path);
/* Apply a preset by name ("full" or "" = the spec's own values). Throws UserError. */
void apply_preset(ExperimentSpec &spec, const std::string &preset);

} // namespace qnav

#endif
