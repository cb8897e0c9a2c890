/*
 * Distributions of worlds: episode seed -> world, the runner over a distribution, and the
 * held-out worlds of every summary.
 */
#include "worlds.h"

#include <algorithm>
#include <cstdio>
#include <dirent.h>

#include "qnav/paths.hpp"
#include "qnav/sim.h"
#include "rng.h"

#ifndef QNAV_SIMEVO_DATA_DIR
#error "QNAV_SIMEVO_DATA_DIR (the source tree's data/ folder) is set by the qnav_simevo_core target"
#endif

namespace qnav {

std::string family_env_spec(const std::string &family, uint64_t seed, double difficulty, const std::string &robot)
{
    char d[32];
    std::snprintf(d, sizeof d, "%.2f", difficulty);
    return "gen:" + family + ":" + std::to_string(seed) + ":" + d + ":" + robot;
}

namespace {

uint64_t label_seed(uint64_t seed, const char *label) { return mix_seed(seed, fnv1a64(label, std::char_traits<char>::length(label))); }

/* A uniform draw in [lo, hi] (lo when they are equal). */
double between(Rng &rng, double lo, double hi) { return hi > lo ? lo + (hi - lo) * rng.uniform01() : lo; }

/* A world seed from the set's range: the distribution's training range, or the validation
 * or test block (disjoint from training by construction, spec.h). */
uint64_t world_seed(Rng &rng, const Distribution &d, WorldSet set)
{
    uint64_t lo = d.seed_lo, span = d.seed_hi - d.seed_lo + 1;
    switch (set) {
    case WorldSet::Training:
        break;
    case WorldSet::Validation:
        lo = kValidationSeedBase;
        span = kHeldOutSeedSpan;
        break;
    case WorldSet::Test:
        lo = kTestSeedBase;
        span = kHeldOutSeedSpan;
        break;
    }
    return lo + rng.next_u64() % span; /* span <= 10^6: the modulo bias is below 10^-13 */
}

} // namespace

WorldDraw draw_world(const Scenario &s, uint64_t episode_seed)
{
    const Distribution &d = *s.distribution;
    Rng rng(label_seed(episode_seed, "world"));
    double total = 0;
    for (const FamilySpec &f : d.families) {
        total += f.weight;
    }
    WorldDraw w;
    const double u = rng.uniform01() * total;
    double acc = 0;
    w.family = d.families.size() - 1;
    for (std::size_t i = 0; i < d.families.size(); ++i) {
        acc += d.families[i].weight;
        if (u < acc) {
            w.family = i;
            break;
        }
    }
    const FamilySpec &f = d.families[w.family];
    // every draw is made whatever the component, so each part's stream stays aligned
    const uint64_t seed = world_seed(rng, d, s.worlds);
    // a world is (family, seed): its difficulty follows from them, so a finite seed range
    // is a finite set of worlds (each generated once and cached, SimWorlds)
    Rng world_rng(mix_seed(seed, fnv1a64(f.family.data(), f.family.size())));
    const double difficulty = between(world_rng, f.difficulty_lo, f.difficulty_hi);
    const uint32_t sectors_pick = d.sectors.empty() ? 0 : rng.below(static_cast<uint32_t>(d.sectors.size()));
    const double noise = between(rng, d.noise_lo, d.noise_hi);

    w.scenario = s;
    w.scenario.distribution.reset();
    w.scenario.worlds = WorldSet::Training;
    if (f.family.empty()) {
        w.scenario.environment = f.environment;
    } else {
        w.world_seed = seed;
        w.scenario.environment = family_env_spec(f.family, seed, difficulty, s.robot);
    }
    if (!d.sectors.empty()) {
        w.scenario.sectors = d.sectors[sectors_pick];
    }
    if (d.noise_drawn) {
        w.scenario.sensor_noise = w.scenario.actuation_noise = noise;
    }
    w.start_seed = label_seed(episode_seed, "start");
    return w;
}

DistributionRunner::DistributionRunner(const Scenario &scenario, uint64_t context_seed, WorldRunnerFactory make,
                                       std::size_t cache_size)
    : scenario_(scenario), context_seed_(context_seed), make_(std::move(make)), cache_size_(std::max<std::size_t>(1, cache_size))
{
    // the reference policy depends on the robot only: any world of the distribution
    prob_ = runner_for(draw_world(scenario_, 0).scenario).probabilistic_policy();
}

EpisodeRunner &DistributionRunner::runner_for(const Scenario &concrete)
{
    const std::string key = concrete.describe();
    for (auto it = cache_.begin(); it != cache_.end(); ++it) {
        if (it->first == key) {
            cache_.splice(cache_.begin(), cache_, it);
            return *cache_.front().second;
        }
    }
    if (cache_.size() >= cache_size_) {
        cache_.pop_back();
    }
    cache_.emplace_front(key, make_(concrete, context_seed_));
    return *cache_.front().second;
}

EpisodeOutcome DistributionRunner::run(const qnav_policy_t &policy, uint64_t episode_seed)
{
    const WorldDraw w = draw_world(scenario_, episode_seed);
    return runner_for(w.scenario).run(policy, w.start_seed);
}

EpisodeOutcome DistributionRunner::run_controller(const char *controller, uint64_t episode_seed)
{
    const WorldDraw w = draw_world(scenario_, episode_seed);
    return runner_for(w.scenario).run_controller(controller, w.start_seed);
}

qnav_policy_t DistributionRunner::probabilistic_policy() const { return prob_; }

std::vector<std::string> named_environments()
{
    const std::string dir = resource_dir("QNAV_DATA_DIR", "data", QNAV_SIMEVO_DATA_DIR) + "/envs";
    std::vector<std::string> names;
    DIR *d = ::opendir(dir.c_str());
    if (d == nullptr) {
        throw UserError(dir + ": cannot open the environments folder (set QNAV_DATA_DIR)");
    }
    while (const dirent *e = ::readdir(d)) {
        const std::string n = e->d_name;
        if (n.size() > 5 && n[0] != '.' && n.compare(n.size() - 5, 5, ".toml") == 0) {
            names.push_back(n.substr(0, n.size() - 5));
        }
    }
    ::closedir(d);
    std::sort(names.begin(), names.end());
    return names;
}

std::vector<std::string> world_families()
{
    std::vector<std::string> out;
    const std::string all = qnav_sim_world_families();
    std::size_t start = 0;
    while (start < all.size()) {
        std::size_t end = all.find(',', start);
        if (end == std::string::npos) {
            end = all.size();
        }
        std::string name = all.substr(start, end - start);
        name.erase(0, name.find_first_not_of(' '));
        name.erase(name.find_last_not_of(' ') + 1);
        if (!name.empty()) {
            out.push_back(name);
        }
        start = end + 1;
    }
    return out;
}

std::vector<HeldOutWorld> held_out_worlds(const Scenario &target)
{
    Scenario base = target;
    base.distribution.reset();
    base.worlds = WorldSet::Training;
    if (!base.held_out_robot.empty()) {
        base.robot = base.held_out_robot;
    }
    std::vector<HeldOutWorld> v;
    for (const std::string &f : world_families()) {
        auto d = std::make_shared<Distribution>();
        d->name = "held-out-" + f;
        FamilySpec fs;
        fs.family = f;
        d->families.push_back(fs);
        HeldOutWorld w;
        w.label = f;
        w.family = true;
        w.scenario = base;
        w.scenario.distribution = d;
        w.scenario.worlds = WorldSet::Test;
        v.push_back(w);
    }
    if (target.distribution) {
        /* escapes take time (issue 18): a distribution's families again at twice each
         * world's limit */
        const std::size_t families = v.size();
        for (std::size_t i = 0; i < families; ++i) {
            HeldOutWorld w = v[i];
            w.label += kTwiceLimitSuffix;
            w.scenario.limit_factor = 2.0;
            v.push_back(w);
        }
    }
    for (const std::string &e : named_environments()) {
        HeldOutWorld w;
        w.label = e;
        w.scenario = base;
        w.scenario.environment = e;
        v.push_back(w);
    }
    return v;
}

Scenario validation_scenario(const Scenario &s)
{
    Scenario v = s;
    if (v.distribution) {
        v.worlds = WorldSet::Validation;
    }
    if (!v.held_out_robot.empty()) {
        v.robot = v.held_out_robot;
    }
    return v;
}

} // namespace qnav
