/*
 * TOML experiment files -> ExperimentSpec, with strict checking of every key and value.
 */
#include "spec.h"
#include "files.h"
#include "worlds.h"

#include <algorithm>

#include <cmath>
#include <initializer_list>
#include <set>
#include <sstream>

#include <toml++/toml.h>

namespace qnav {

const char *controller_reading_name(ControllerReading c)
{
    switch (c) {
    case ControllerReading::Body:
        return "body";
    case ControllerReading::Literal:
        return "literal";
    }
    return "body";
}

bool controller_reading_parse(const std::string &name, ControllerReading *out)
{
    for (ControllerReading c : kControllerReadings) {
        if (name == controller_reading_name(c)) {
            *out = c;
            return true;
        }
    }
    return false;
}

std::string controller_reading_names()
{
    std::string s;
    for (ControllerReading c : kControllerReadings) {
        s += (s.empty() ? "" : ", ") + std::string(controller_reading_name(c));
    }
    return s;
}

const char *world_set_name(WorldSet w)
{
    switch (w) {
    case WorldSet::Training:
        return "training";
    case WorldSet::Validation:
        return "validation";
    case WorldSet::Test:
        return "test";
    }
    return "training";
}

std::string FamilySpec::label() const { return family.empty() ? "env:" + environment : family; }

std::string Distribution::describe() const
{
    std::ostringstream o;
    o.precision(17);
    o << name << "{families=";
    for (std::size_t i = 0; i < families.size(); ++i) {
        const FamilySpec &f = families[i];
        o << (i ? "," : "") << f.label() << ":w" << f.weight;
        if (!f.family.empty()) {
            o << ":d" << f.difficulty_lo << "-" << f.difficulty_hi;
        }
    }
    o << ";seeds=" << seed_lo << "-" << seed_hi;
    if (!sectors.empty()) {
        o << ";sectors=";
        for (std::size_t i = 0; i < sectors.size(); ++i) {
            o << (i ? "," : "") << sectors[i];
        }
    }
    if (noise_drawn) {
        o << ";noise=" << noise_lo << "-" << noise_hi;
    }
    o << "}";
    return o.str();
}

std::string Scenario::describe() const
{
    std::ostringstream o;
    o.precision(17);
    if (distribution) {
        o << "distribution=" << distribution->describe() << " worlds=" << world_set_name(worlds);
    } else {
        o << "environment=" << environment;
    }
    o << " robot=" << robot << " sectors=" << sectors
      << " sensor_noise=" << sensor_noise << " actuation_noise=" << actuation_noise
      << " episode_limit_s=" << episode_limit_s;
    if (limit_factor != 1.0) {
        o << " limit_factor=" << limit_factor; /* absent at 1: old fingerprints unchanged */
    }
    if (!held_out_robot.empty()) {
        o << " held_out_robot=" << held_out_robot; /* absent unset: the same */
    }
    o << " fitness=" << qnav_sim_fitness_rule_name(fitness)
      << " controller=" << controller_reading_name(controller);
    return o.str();
}

std::string SourceSpec::describe() const
{
    if (!fit.empty()) {
        return "the network fitted to the target robot's " + fit + " policy";
    }
    return policy_file.empty() ? scenario.describe() : "policy file " + policy_file;
}

namespace {

class Parser {
public:
    explicit Parser(std::string name) : name_(std::move(name)) {}

    [[noreturn]] void fail(const toml::node &n, const std::string &what) const
    {
        throw UserError(name_ + ":" + std::to_string(n.source().begin.line) + ": " + what);
    }
    [[noreturn]] void fail_line(std::size_t line, const std::string &what) const
    {
        throw UserError(name_ + ":" + std::to_string(line) + ": " + what);
    }

    void only_keys(const toml::table &t, const std::set<std::string> &allowed,
                   const std::string &where) const
    {
        for (auto &&[k, v] : t) {
            if (allowed.count(std::string(k.str())) == 0) {
                fail(v, "unknown key '" + std::string(k.str()) + "'" +
                            (where.empty() ? "" : " in [" + where + "]"));
            }
        }
    }

    std::string str(const toml::node &n, const std::string &key) const
    {
        if (!n.is_string()) {
            fail(n, key + ": expected a string");
        }
        return *n.value<std::string>();
    }
    int64_t integer(const toml::node &n, const std::string &key, int64_t lo, int64_t hi) const
    {
        if (!n.is_integer()) {
            fail(n, key + ": expected an integer");
        }
        const int64_t v = *n.value<int64_t>();
        if (v < lo || v > hi) {
            fail(n, key + ": " + std::to_string(v) + " is outside " + std::to_string(lo) +
                        ".." + std::to_string(hi));
        }
        return v;
    }
    double number(const toml::node &n, const std::string &key, double lo, double hi) const
    {
        double v;
        if (n.is_integer()) {
            v = static_cast<double>(*n.value<int64_t>());
        } else if (n.is_floating_point()) {
            v = *n.value<double>();
        } else {
            fail(n, key + ": expected a number");
        }
        if (!std::isfinite(v) || v < lo || v > hi) {
            std::ostringstream o;
            o << key << ": " << v << " is outside [" << lo << ", " << hi << "]";
            fail(n, o.str());
        }
        return v;
    }
    const toml::table &table(const toml::node &n, const std::string &key) const
    {
        if (!n.is_table()) {
            fail(n, key + ": expected a table");
        }
        return *n.as_table();
    }

    /* A strictly increasing array of target-episode counts (>= 1). */
    std::vector<uint64_t> checkpoint_list(const toml::node &n) const
    {
        if (!n.is_array()) {
            fail(n, "checkpoints: expected an array of episode counts, e.g. [100, 250, 500]");
        }
        std::vector<uint64_t> v;
        for (auto &&el : *n.as_array()) {
            const uint64_t c = static_cast<uint64_t>(integer(el, "checkpoints", 1, 100000000));
            if (!v.empty() && c <= v.back()) {
                fail(el, "checkpoints: must be increasing (" + std::to_string(c) + " after " +
                             std::to_string(v.back()) + ")");
            }
            v.push_back(c);
        }
        return v;
    }

    /* A [lo, hi] pair of numbers within [min, max], lo <= hi. */
    std::pair<double, double> range(const toml::node &n, const std::string &key, double min, double max) const
    {
        const toml::array *a = n.as_array();
        if (a == nullptr || a->size() != 2) {
            fail(n, key + ": expected [low, high]");
        }
        const double lo = number(*a->get(0), key, min, max);
        const double hi = number(*a->get(1), key, min, max);
        if (lo > hi) {
            fail(n, key + ": low is above high");
        }
        return {lo, hi};
    }

    /* Scenario keys shared by [target] and [[source]]. Returns true if key was one.
     * environment and distribution exclude each other (the last one given wins over an
     * inherited one; both in one table is an error). */
    bool scenario_key(Scenario &s, const std::string &k, const toml::node &v,
                      bool &noise_set, bool &split_noise_set) const
    {
        if (k == "environment") {
            if (s.distribution && distribution_set_) {
                fail(v, "environment: give either 'environment' or 'distribution', not both");
            }
            s.environment = str(v, k);
            s.distribution.reset();
            environment_set_ = true;
            if (s.environment.empty()) {
                fail(v, "environment: must not be empty");
            }
        } else if (k == "distribution") {
            if (environment_set_) {
                fail(v, "distribution: give either 'environment' or 'distribution', not both");
            }
            const std::string d = str(v, k);
            if (distributions_ == nullptr || distributions_->count(d) == 0) {
                std::string known;
                if (distributions_ != nullptr) {
                    for (auto &kv : *distributions_) {
                        known += (known.empty() ? "" : ", ") + kv.first;
                    }
                }
                fail(v, "distribution: no [distribution." + d + "] in this file" +
                            (known.empty() ? "" : " (known: " + known + ")"));
            }
            s.distribution = distributions_->at(d);
            distribution_set_ = true;
        } else if (k == "robot") {
            s.robot = str(v, k);
            if (s.robot.empty()) {
                fail(v, "robot: must not be empty");
            }
        } else if (k == "sectors") {
            s.sectors = static_cast<uint32_t>(integer(v, k, 0, QNAV_MAX_SECTORS));
        } else if (k == "noise") {
            s.sensor_noise = s.actuation_noise = number(v, k, 0.0, 1.0);
            noise_set = true;
        } else if (k == "sensor_noise") {
            s.sensor_noise = number(v, k, 0.0, 1.0);
            split_noise_set = true;
        } else if (k == "actuation_noise") {
            s.actuation_noise = number(v, k, 0.0, 1.0);
            split_noise_set = true;
        } else if (k == "episode_limit_s") {
            s.episode_limit_s = number(v, k, 0.0, 1e6);
        } else {
            return false;
        }
        if (noise_set && split_noise_set) {
            fail(v, "noise: give either 'noise' or 'sensor_noise'/'actuation_noise', not both");
        }
        return true;
    }

    const std::string &name() const { return name_; }
    /* The distributions scenario_key resolves names in. */
    void set_distributions(const std::map<std::string, std::shared_ptr<const Distribution>> *d) { distributions_ = d; }
    /* Start a new scenario table (environment / distribution given in it: none yet). */
    void begin_scenario() const { environment_set_ = distribution_set_ = false; }

private:
    std::string name_;
    const std::map<std::string, std::shared_ptr<const Distribution>> *distributions_ = nullptr;
    mutable bool environment_set_ = false, distribution_set_ = false;
};

} // namespace

bool valid_name(const std::string &s)
{
    if (s.empty() || s.size() > 64) {
        return false;
    }
    for (char c : s) {
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_')) {
            return false;
        }
    }
    return true;
}

namespace {

/* the top-level keys: name, title, figure, runs, seed, curve_bin. Throws UserError. */
void parse_header(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (!root.contains("name")) {
        p.fail_line(1, "name: missing (the experiment's identifier)");
    }
    spec.name = p.str(*root.get("name"), "name");
    if (!valid_name(spec.name)) {
        p.fail(*root.get("name"), "name: use 1-64 characters a-z, 0-9, '-', '_'");
    }
    if (auto *n = root.get("title")) {
        spec.title = p.str(*n, "title");
    }
    if (auto *n = root.get("figure")) {
        spec.figure = p.str(*n, "figure");
    }
    if (auto *n = root.get("runs")) {
        spec.runs = static_cast<uint32_t>(p.integer(*n, "runs", 1, 10000));
    }
    if (auto *n = root.get("seed")) {
        spec.seed = static_cast<uint64_t>(p.integer(*n, "seed", 0, INT64_MAX));
    }
    if (auto *n = root.get("curve_bin")) {
        spec.curve_bin = static_cast<uint32_t>(p.integer(*n, "curve_bin", 1, 100000));
    }
}

/* [evolution]'s fitness rule and controller reading: set on the target, which every source
 * inherits. Throws UserError. */
void parse_scenario_rules(const Parser &p, const toml::table &t, ExperimentSpec &spec)
{
    if (auto *v = t.get("fitness")) {
        // Every scenario (target, and the sources that inherit from it) uses this rule.
        const std::string s = p.str(*v, "fitness");
        if (qnav_sim_fitness_rule_parse(s.c_str(), &spec.target.fitness) != QNAV_SIM_OK) {
            p.fail(*v, "fitness: '" + s + "' is not one of " + qnav_sim_fitness_rule_names());
        }
    }
    if (auto *v = t.get("controller")) {
        // Like fitness: one reading for the target and every source.
        const std::string s = p.str(*v, "controller");
        if (!controller_reading_parse(s, &spec.target.controller)) {
            p.fail(*v, "controller: '" + s + "' is not one of " + controller_reading_names());
        }
    }
}

/* A value that must be one of `values`, spelled as name() spells them. Throws UserError
 * "KEY: 'VALUE' is not one of A, B". */
template <typename E>
E parse_named(const Parser &p, const toml::node &v, const char *key, std::initializer_list<E> values,
              const char *(*name)(E))
{
    const std::string s = p.str(v, key);
    std::string known;
    for (E e : values) {
        if (s == name(e)) {
            return e;
        }
        known += (known.empty() ? "" : ", ") + std::string(name(e));
    }
    p.fail(v, std::string(key) + ": '" + s + "' is not one of " + known);
}

/* [evolution]'s choice of search and the evolution strategy's settings. Throws UserError. */
void parse_search(const Parser &p, const toml::table &t, EvolutionParams &e)
{
    if (auto *v = t.get("algorithm")) {
        e.algorithm = parse_named(p, *v, "algorithm",
                                  {EvolutionParams::Algorithm::EpsilonGreedy, EvolutionParams::Algorithm::Es},
                                  algorithm_name);
    }
    if (auto *v = t.get("es_pairs")) {
        e.es_pairs = static_cast<uint32_t>(p.integer(*v, "es_pairs", 1, 10000));
    }
    if (auto *v = t.get("es_sigma")) {
        e.es_sigma = p.number(*v, "es_sigma", 1e-6, 16.0);
    }
    if (auto *v = t.get("es_step")) {
        e.es_step = p.number(*v, "es_step", 1e-6, 16.0);
    }
}

/* [evolution]: the algorithm's settings, the fitness rule and the controller reading. Throws UserError. */
void parse_evolution(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (auto *n = root.get("evolution")) {
        const toml::table &t = p.table(*n, "evolution");
        p.only_keys(t, {"population", "epsilon", "hidden", "inputs", "mutation_scale", "mutation_clip",
                        "episodes_per_candidate", "reevaluate_parent", "init", "init_scale",
                        "fitness", "controller", "world_sets", "algorithm", "es_pairs", "es_sigma", "es_step"},
                    "evolution");
        EvolutionParams &e = spec.evolution;
        if (auto *v = t.get("population")) {
            e.population = static_cast<uint32_t>(p.integer(*v, "population", 2, 100000));
        }
        if (auto *v = t.get("epsilon")) {
            e.epsilon = p.number(*v, "epsilon", 0.0, 1.0);
        }
        if (auto *v = t.get("hidden")) {
            e.hidden = static_cast<uint32_t>(p.integer(*v, "hidden", 1, QNAV_MAX_HIDDEN));
        }
        if (auto *v = t.get("inputs")) {
            e.inputs = static_cast<uint32_t>(p.integer(*v, "inputs", QNAV_NET_INPUTS_PAPER,
                                                       QNAV_NET_INPUTS_PREV));
        }
        if (auto *v = t.get("mutation_scale")) {
            e.mutation_scale = p.number(*v, "mutation_scale", 1e-6, 128.0);
        }
        if (auto *v = t.get("mutation_clip")) {
            e.mutation_clip = p.number(*v, "mutation_clip", 1e-6, 256.0);
        }
        if (auto *v = t.get("episodes_per_candidate")) {
            e.episodes_per_candidate = static_cast<uint32_t>(p.integer(*v, "episodes_per_candidate", 1, 1000));
        }
        if (auto *v = t.get("reevaluate_parent")) {
            if (!v->is_boolean()) {
                p.fail(*v, "reevaluate_parent: expected true or false");
            }
            e.reevaluate_parent = *v->value<bool>();
        }
        if (auto *v = t.get("init")) {
            e.init = parse_named(p, *v, "init", {InitKind::Cauchy, InitKind::Uniform}, init_kind_name);
        }
        if (auto *v = t.get("world_sets")) {
            e.world_sets = parse_named(p, *v, "world_sets",
                                       {EvolutionParams::WorldSets::PerStep, EvolutionParams::WorldSets::PerGeneration},
                                       world_sets_name);
        }
        if (auto *v = t.get("init_scale")) {
            e.init_scale = p.number(*v, "init_scale", 1e-6, 128.0);
        }
        parse_search(p, t, e);
        parse_scenario_rules(p, t, spec);
    }
}

/* One entry of a distribution's families array. Throws UserError. */
FamilySpec parse_family(const Parser &p, const toml::node &n, const std::string &where)
{
    const toml::table *t = n.as_table();
    if (t == nullptr) {
        p.fail(n, where + ": expected { family = \"NAME\", weight = W, difficulty = [LO, HI] } or "
                          "{ environment = \"NAME\", weight = W }");
    }
    p.only_keys(*t, {"family", "environment", "weight", "difficulty"}, where);
    FamilySpec f;
    if (auto *v = t->get("family")) {
        f.family = p.str(*v, "family");
        const std::vector<std::string> known = world_families();
        if (std::find(known.begin(), known.end(), f.family) == known.end()) {
            p.fail(*v, "family: '" + f.family + "' is not one of " + qnav_sim_world_families());
        }
    }
    if (auto *v = t->get("environment")) {
        f.environment = p.str(*v, "environment");
        if (f.environment.empty() || f.environment.find(':') != std::string::npos) {
            p.fail(*v, "environment: a name in data/envs or a file (a generated world is a 'family')");
        }
    }
    if (f.family.empty() == f.environment.empty()) {
        p.fail(n, where + ": give exactly one of 'family' and 'environment'");
    }
    if (auto *v = t->get("weight")) {
        f.weight = p.number(*v, "weight", 1e-9, 1e9);
    }
    if (auto *v = t->get("difficulty")) {
        if (!f.environment.empty()) {
            p.fail(*v, "difficulty: only a generated family has one");
        }
        const auto r = p.range(*v, "difficulty", 0.0, 1.0);
        f.difficulty_lo = r.first;
        f.difficulty_hi = r.second;
    }
    return f;
}

/* [distribution.NAME]: training distributions that [target] and [[source]] name. Throws UserError. */
void parse_distributions(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    const toml::node *n = root.get("distribution");
    if (n == nullptr) {
        return;
    }
    for (auto &&[k, v] : p.table(*n, "distribution")) {
        auto d = std::make_shared<Distribution>();
        d->name = std::string(k.str());
        const std::string where = "distribution." + d->name;
        if (!valid_name(d->name)) {
            p.fail(v, where + ": use 1-64 characters a-z, 0-9, '-', '_' in the name");
        }
        const toml::table &t = p.table(v, where);
        p.only_keys(t, {"families", "seeds", "sectors", "noise"}, where);
        const toml::node *fam = t.get("families");
        if (fam == nullptr || !fam->is_array() || fam->as_array()->empty()) {
            p.fail(fam ? *fam : v, where + ": families: expected a non-empty array of { family = ... } tables");
        }
        for (auto &&el : *fam->as_array()) {
            d->families.push_back(parse_family(p, el, where + ".families"));
        }
        if (auto *s = t.get("seeds")) {
            const auto r = p.range(*s, "seeds", 0.0, static_cast<double>(kValidationSeedBase - 1));
            if (!s->as_array()->get(0)->is_integer() || !s->as_array()->get(1)->is_integer()) {
                p.fail(*s, "seeds: expected two integers [low, high]");
            }
            d->seed_lo = static_cast<uint64_t>(r.first);
            d->seed_hi = static_cast<uint64_t>(r.second);
        }
        if (auto *s = t.get("sectors")) {
            if (!s->is_array() || s->as_array()->empty()) {
                p.fail(*s, "sectors: expected a non-empty array of sector counts");
            }
            for (auto &&el : *s->as_array()) {
                d->sectors.push_back(static_cast<uint32_t>(p.integer(el, "sectors", 1, QNAV_MAX_SECTORS)));
            }
        }
        if (auto *s = t.get("noise")) {
            const auto r = p.range(*s, "noise", 0.0, 1.0);
            d->noise_drawn = true;
            d->noise_lo = r.first;
            d->noise_hi = r.second;
        }
        spec.distributions[d->name] = d;
    }
}

/* [target]: the situation transfer and direct evolution share. Throws UserError. */
void parse_target(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (!root.contains("target")) {
        p.fail_line(1, "[target]: missing (the situation transfer and direct evolution share)");
    }
    {
        const toml::table &t = p.table(*root.get("target"), "target");
        bool ns = false, ss = false;
        p.begin_scenario();
        for (auto &&[k, v] : t) {
            const std::string key(k.str());
            if (p.scenario_key(spec.target, key, v, ns, ss)) {
                continue;
            }
            if (key == "episodes") {
                spec.target_episodes = static_cast<uint64_t>(p.integer(v, key, 1, 100000000));
            } else {
                p.fail(v, "unknown key '" + key + "' in [target]");
            }
        }
    }
}

/* [[source]]: the situations whose best policies seed transfers (they inherit [target]). Throws UserError. */
void parse_sources(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (auto *n = root.get("source")) {
        if (!n->is_array_of_tables()) {
            p.fail(*n, "source: expected [[source]] tables");
        }
        std::set<std::string> labels;
        for (auto &&el : *n->as_array()) {
            const toml::table &t = *el.as_table();
            SourceSpec s;
            s.scenario = spec.target;
            s.episodes = spec.target_episodes;
            bool ns = false, ss = false;
            p.begin_scenario();
            bool has_label = false;
            for (auto &&[k, v] : t) {
                const std::string key(k.str());
                if (p.scenario_key(s.scenario, key, v, ns, ss)) {
                    continue;
                }
                if (key == "label") {
                    s.label = p.str(v, key);
                    has_label = true;
                    if (!valid_name(s.label)) {
                        p.fail(v, "label: use 1-64 characters a-z, 0-9, '-', '_'");
                    }
                    if (!labels.insert(s.label).second) {
                        p.fail(v, "label: '" + s.label + "' is used by another [[source]]");
                    }
                } else if (key == "episodes") {
                    s.episodes = static_cast<uint64_t>(p.integer(v, key, 1, 100000000));
                } else if (key == "policy") {
                    s.policy_file = p.str(v, key);
                    if (s.policy_file.empty()) {
                        p.fail(v, "policy: must not be empty");
                    }
                } else if (key == "fit") {
                    s.fit = p.str(v, key);
                    if (s.fit != "probabilistic") {
                        p.fail(v, "fit: '" + s.fit + "' is not 'probabilistic' (the network fitted to the "
                                  "target robot's probabilistic policy)");
                    }
                } else {
                    p.fail(v, "unknown key '" + key + "' in [[source]]");
                }
            }
            if (!has_label) {
                p.fail(el, "[[source]]: missing label");
            }
            if (!s.policy_file.empty() && !s.fit.empty()) {
                p.fail(el, "[[source]] " + s.label + ": give 'policy' or 'fit', not both");
            }
            spec.sources.push_back(s);
        }
    }
    if (spec.sources.empty()) {
        p.fail_line(1, "[[source]]: at least one source situation is needed for a transfer");
    }
}

/* [evaluation]: the held-out set and the checkpoints. Throws UserError. */
void parse_evaluation(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (auto *n = root.get("evaluation")) {
        const toml::table &t = p.table(*n, "evaluation");
        p.only_keys(t, {"episodes", "seed", "checkpoints", "checkpoint_every", "checkpoint_episodes",
                        "arrival_threshold", "worlds_episodes", "robot"},
                    "evaluation");
        if (auto *v = t.get("robot")) {
            /* held-out episodes with this robot: the target's and every source's */
            const std::string robot = p.str(*v, "robot");
            if (robot.empty()) {
                p.fail(*v, "robot: must not be empty");
            }
            spec.target.held_out_robot = robot;
            for (SourceSpec &src : spec.sources) {
                src.scenario.held_out_robot = robot;
            }
        }
        if (auto *v = t.get("episodes")) {
            spec.eval_episodes = static_cast<uint32_t>(p.integer(*v, "episodes", 1, 1000000));
        }
        if (auto *v = t.get("seed")) {
            spec.eval_seed = static_cast<uint64_t>(p.integer(*v, "seed", 0, INT64_MAX));
        }
        if (auto *v = t.get("checkpoints")) {
            spec.checkpoints = p.checkpoint_list(*v);
        }
        if (auto *v = t.get("checkpoint_every")) {
            spec.checkpoint_every = static_cast<uint64_t>(p.integer(*v, "checkpoint_every", 0, 100000000));
        }
        if (auto *v = t.get("checkpoint_episodes")) {
            spec.checkpoint_episodes = static_cast<uint32_t>(p.integer(*v, "checkpoint_episodes", 1, 1000000));
        }
        if (auto *v = t.get("arrival_threshold")) {
            spec.arrival_threshold = p.number(*v, "arrival_threshold", 0.0, 100.0) / 100.0;
        }
        if (auto *v = t.get("worlds_episodes")) {
            spec.worlds_episodes = static_cast<uint32_t>(p.integer(*v, "worlds_episodes", 1, 1000000));
        }
    }
}

/* [preset.NAME]: overrides selected with --preset. Throws UserError. */
void parse_presets(const Parser &p, const toml::table &root, ExperimentSpec &spec)
{
    if (auto *n = root.get("preset")) {
        const toml::table &all = p.table(*n, "preset");
        for (auto &&[k, v] : all) {
            const std::string pname(k.str());
            if (pname == "full") {
                p.fail(v, "preset.full: reserved (it means the file's own values)");
            }
            const toml::table &t = p.table(v, "preset." + pname);
            p.only_keys(t, {"runs", "episodes", "source_episodes", "eval_episodes", "curve_bin",
                            "checkpoint_episodes", "worlds_episodes"},
                        "preset." + pname);
            Preset pr;
            if (auto *x = t.get("runs")) {
                pr.runs = static_cast<uint32_t>(p.integer(*x, "runs", 1, 10000));
            }
            if (auto *x = t.get("episodes")) {
                pr.episodes = static_cast<uint64_t>(p.integer(*x, "episodes", 1, 100000000));
            }
            if (auto *x = t.get("source_episodes")) {
                pr.source_episodes =
                    static_cast<uint64_t>(p.integer(*x, "source_episodes", 1, 100000000));
            }
            if (auto *x = t.get("eval_episodes")) {
                pr.eval_episodes = static_cast<uint32_t>(p.integer(*x, "eval_episodes", 1, 1000000));
            }
            if (auto *x = t.get("curve_bin")) {
                pr.curve_bin = static_cast<uint32_t>(p.integer(*x, "curve_bin", 1, 100000));
            }
            if (auto *x = t.get("checkpoint_episodes")) {
                pr.checkpoint_episodes =
                    static_cast<uint32_t>(p.integer(*x, "checkpoint_episodes", 1, 1000000));
            }
            if (auto *x = t.get("worlds_episodes")) {
                pr.worlds_episodes = static_cast<uint32_t>(p.integer(*x, "worlds_episodes", 1, 1000000));
            }
            spec.presets[pname] = pr;
        }
    }
}

} // namespace

ExperimentSpec parse_experiment(const std::string &text, const std::string &name)
{
    Parser p(name);
    toml::table root;
    try {
        root = toml::parse(text, name);
    } catch (const toml::parse_error &e) {
        throw UserError(name + ":" + std::to_string(e.source().begin.line) + ": " +
                        std::string(e.description()));
    }
    ExperimentSpec spec;
    spec.file = name;
    p.only_keys(root, {"name", "title", "figure", "runs", "seed", "curve_bin", "evolution",
                       "target", "source", "evaluation", "preset", "distribution"},
                "");
    parse_header(p, root, spec);
    parse_distributions(p, root, spec);
    p.set_distributions(&spec.distributions);
    parse_evolution(p, root, spec);
    parse_target(p, root, spec);
    parse_sources(p, root, spec);
    parse_evaluation(p, root, spec);
    parse_presets(p, root, spec);
    return spec;
}

ExperimentSpec load_experiment(const std::string &path)
{
    std::string text;
    if (!read_file(path, text)) {
        throw UserError(path + ": cannot open experiment file (No such file or directory)");
    }
    return parse_experiment(text, path);
}

void apply_preset(ExperimentSpec &spec, const std::string &preset)
{
    if (preset.empty() || preset == "full") {
        return;
    }
    auto it = spec.presets.find(preset);
    if (it == spec.presets.end()) {
        std::string known = "full";
        for (auto &kv : spec.presets) {
            known += ", " + kv.first;
        }
        throw UserError(spec.file + ": no preset '" + preset + "' (known: " + known + ")");
    }
    const Preset &p = it->second;
    if (p.runs) {
        spec.runs = *p.runs;
    }
    if (p.episodes) {
        spec.target_episodes = *p.episodes;
    }
    if (p.source_episodes) {
        for (auto &s : spec.sources) {
            s.episodes = *p.source_episodes;
        }
    }
    if (p.eval_episodes) {
        spec.eval_episodes = *p.eval_episodes;
    }
    if (p.curve_bin) {
        spec.curve_bin = *p.curve_bin;
    }
    if (p.checkpoint_episodes) {
        spec.checkpoint_episodes = *p.checkpoint_episodes;
    }
    if (p.worlds_episodes) {
        spec.worlds_episodes = *p.worlds_episodes;
    }
}

} // namespace qnav
