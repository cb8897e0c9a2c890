/*
 * Simulator-backed episode runner: controller set-up per episode and error mapping.
 */
#include "sim_runner.h"

#include "qnav/nav.h"
#include "worlds.h"

#include <cstring>


namespace qnav {

SimWorlds::~SimWorlds()
{
    for (auto &kv : robots_) {
        qnav_sim_robot_free(kv.second);
    }
    for (auto &kv : envs_) {
        qnav_sim_env_free(kv.second);
    }
}

namespace {
/* The cached handle for spec, loading it on first use. */
template <typename T>
const T *load_once(std::map<std::string, T *> &cache, const std::string &spec, const char *what,
                   qnav_sim_status_t (*load)(const char *, T **, char *, size_t))
{
    auto it = cache.find(spec);
    if (it != cache.end()) {
        return it->second;
    }
    char err[QNAV_SIM_ERRLEN] = {0};
    T *h = nullptr;
    if (load(spec.c_str(), &h, err, sizeof err) != QNAV_SIM_OK) {
        throw UserError(std::string(what) + " '" + spec + "': " + err);
    }
    cache[spec] = h;
    return h;
}
} // namespace

const qnav_sim_robot_t *SimWorlds::robot(const std::string &spec)
{
    std::lock_guard<std::mutex> lock(mu_);
    return load_once(robots_, spec, "robot", qnav_sim_robot_load);
}

const qnav_sim_env_t *SimWorlds::env(const std::string &spec)
{
    std::lock_guard<std::mutex> lock(mu_);
    return load_once(envs_, spec, "environment", qnav_sim_env_load);
}

std::shared_ptr<const qnav_sim_env_t> SimWorlds::generated(const std::string &spec)
{
    {
        std::lock_guard<std::mutex> lock(mu_);
        auto it = generated_.find(spec);
        if (it != generated_.end()) {
            return it->second;
        }
    }
    // made outside the lock: other threads go on with their worlds meanwhile
    char err[QNAV_SIM_ERRLEN] = {0};
    qnav_sim_env_t *h = nullptr;
    if (qnav_sim_env_load(spec.c_str(), &h, err, sizeof err) != QNAV_SIM_OK) {
        throw UserError("environment '" + spec + "': " + err);
    }
    std::shared_ptr<const qnav_sim_env_t> env(h, [](const qnav_sim_env_t *e) {
        qnav_sim_env_free(const_cast<qnav_sim_env_t *>(e));
    });
    std::lock_guard<std::mutex> lock(mu_);
    auto ins = generated_.emplace(spec, env);
    if (ins.second) {
        generated_order_.push_back(spec);
        if (generated_order_.size() > kGeneratedKept) {
            generated_.erase(generated_order_.front());
            generated_order_.pop_front();
        }
    }
    return ins.first->second;
}

SimRunner::SimRunner(SimWorlds &worlds, const Scenario &scenario, uint64_t context_seed,
                     bool use_table)
    : use_table_(use_table)
{
    const qnav_sim_robot_t *robot = worlds.robot(scenario.robot);
    if (scenario.distribution) {
        throw UserError("simulator (" + scenario.describe() + "): a distribution runs through DistributionRunner");
    }
    // a generated world is shared through its own cache (up to a million of them in a
    // training range: the context copies what it needs, so one may be dropped later)
    std::shared_ptr<const qnav_sim_env_t> generated;
    const qnav_sim_env_t *env = nullptr;
    if (scenario.environment.compare(0, 4, "gen:") == 0) {
        generated = worlds.generated(scenario.environment);
        env = generated.get();
    } else {
        env = worlds.env(scenario.environment);
    }
    qnav_sim_config_t cfg;
    qnav_sim_config_default(&cfg);
    cfg.n_sectors = static_cast<uint16_t>(scenario.sectors);
    cfg.sensor_noise = scenario.sensor_noise;
    cfg.actuation_noise = scenario.actuation_noise;
    cfg.seed = context_seed;
    cfg.episode_limit_s = scenario.episode_limit_s;
    if (scenario.limit_factor != 1.0) {
        qnav_sim_env_info_t ei;
        qnav_sim_env_info(env, &ei);
        cfg.episode_limit_s =
            scenario.limit_factor * (scenario.episode_limit_s > 0 ? scenario.episode_limit_s : ei.episode_limit_s);
    }
    cfg.fitness = scenario.fitness;
    char err[QNAV_SIM_ERRLEN] = {0};
    if (qnav_sim_create(robot, env, &cfg, &sim_, err, sizeof err) != QNAV_SIM_OK) {
        throw UserError(std::string("simulator (") + scenario.describe() + "): " + err);
    }
    /* the reading is a row of libqnav's controller table: its adjust hook (literal:
     * qnav_ctrl_config_literal) gives the configuration every episode uses */
    qnav_ctrl_config_t shared;
    qnav_sim_ctrl_config(sim_, &shared);
    const qnav_nav_method_t *m = qnav_nav_find(controller_reading_name(scenario.controller));
    if (m == nullptr || !m->uses_policy) {
        throw UserError(std::string("controller ") + controller_reading_name(scenario.controller) +
                        ": not a policy controller of libqnav's table");
    }
    qnav_nav_config(m, &shared, &ctrl_cfg_);
    qnav_sim_robot_prob_policy(robot, &prob_);
}

namespace {

/* A trace callback: the sample appended to the std::vector<qnav_sim_sample_t> in user. */
void append_sample(void *user, const qnav_sim_sample_t *smp)
{
    static_cast<std::vector<qnav_sim_sample_t> *>(user)->push_back(*smp);
}

} // namespace

/* The episode's figures, or UserError with the simulator's message. */
EpisodeOutcome SimRunner::outcome(qnav_sim_status_t s, const qnav_sim_result_t &res) const
{
    if (s != QNAV_SIM_OK) {
        throw UserError("simulator: episode failed (status " + std::to_string(static_cast<int>(s)) +
                        "): " + qnav_sim_last_error(sim_));
    }
    EpisodeOutcome out;
    out.R = res.R;
    out.f1 = res.f1;
    out.f2 = res.f2;
    out.tau_c = res.tau_c;
    out.reached = res.reached;
    return out;
}

SimRunner::~SimRunner() { qnav_sim_destroy(sim_); }

/* Whether a policy runs from a compiled quality table when tables are asked for: a
 * 2-input network does; a 3-input network has none (its key depends on the previous heading
 * too); the probabilistic policy runs as it is. */
static bool has_table(const qnav_policy_t &policy)
{
    switch (static_cast<qnav_policy_kind_t>(policy.kind)) {
    case QNAV_POLICY_NET:
        return policy.u.net.inputs == QNAV_NET_INPUTS_PAPER;
    case QNAV_POLICY_PROB:
        return false;
    }
    return false;
}

const qnav_ctrl_t &SimRunner::controller_for(const qnav_policy_t &policy)
{
    for (unsigned i = 0; i < 2; ++i) {
        if (compiled_[i].valid && std::memcmp(&compiled_[i].policy, &policy, sizeof policy) == 0) {
            least_recent_ = 1 - i;
            return compiled_[i].ctrl;
        }
    }
    Compiled &c = compiled_[least_recent_];
    c.valid = false;
    if (use_table_ && has_table(policy)) {
        /* each (level, dtheta) evaluated once: the table, and the row shapes from it */
        c.table.resize(QNAV_QTABLE_ENTRIES);
        const qnav_status_t st = qnav_ctrl_init_compiled(&c.ctrl, &ctrl_cfg_, &policy, c.table.data());
        if (st != QNAV_OK) {
            throw UserError("controller: could not compile the policy into a quality table (status " +
                            std::to_string(static_cast<int>(st)) + ")");
        }
    } else {
        const qnav_status_t st = qnav_ctrl_init(&c.ctrl, &ctrl_cfg_, &policy);
        if (st != QNAV_OK) {
            throw UserError("controller: qnav_ctrl_init refused the policy (status " +
                            std::to_string(static_cast<int>(st)) + ")");
        }
    }
    c.policy = policy;
    c.valid = true;
    least_recent_ = 1 - least_recent_;
    return c.ctrl;
}

EpisodeOutcome SimRunner::run(const qnav_policy_t &policy, uint64_t episode_seed)
{
    return run_traced(policy, episode_seed, nullptr);
}

EpisodeOutcome SimRunner::run_traced(const qnav_policy_t &policy, uint64_t episode_seed,
                                     std::vector<qnav_sim_sample_t> *trace)
{
    const qnav_ctrl_t &ctrl = controller_for(policy);
    qnav_sim_result_t res;
    const qnav_sim_status_t s = qnav_sim_run_episode(sim_, &ctrl, episode_seed, &res,
                                                     trace ? +append_sample : nullptr, trace);
    return outcome(s, res);
}

EpisodeOutcome SimRunner::run_controller(const char *controller, uint64_t episode_seed)
{
    return run_controller_traced(controller, episode_seed, nullptr);
}

EpisodeOutcome SimRunner::run_controller_traced(const char *controller, uint64_t episode_seed,
                                                std::vector<qnav_sim_sample_t> *trace)
{
    qnav_ctrl_config_t shared;
    qnav_sim_ctrl_config(sim_, &shared);
    qnav_nav_t nav;
    const qnav_status_t st = qnav_nav_init_named(&nav, controller, &shared, nullptr);
    if (st != QNAV_OK) {
        throw UserError(std::string("controller ") + controller + ": qnav_nav_init refused it (" +
                        qnav_status_str(st) + ")");
    }
    qnav_sim_result_t res;
    const qnav_sim_status_t s =
        qnav_sim_run_episode_nav(sim_, &nav, episode_seed, &res, trace ? +append_sample : nullptr, trace);
    return outcome(s, res);
}

void probe_scenario(SimWorlds &worlds, const Scenario &scenario, uint64_t context_seed, bool use_table)
{
    if (!scenario.distribution) {
        SimRunner probe(worlds, scenario, context_seed, use_table);
        return;
    }
    const Distribution &d = *scenario.distribution;
    std::vector<uint32_t> sectors = d.sectors;
    if (sectors.empty()) {
        sectors.push_back(scenario.sectors);
    }
    for (const FamilySpec &f : d.families) {
        Scenario s = scenario;
        s.distribution.reset();
        s.environment = f.family.empty() ? f.environment : family_env_spec(f.family, d.seed_lo, f.difficulty_lo, s.robot);
        for (uint32_t n : sectors) {
            s.sectors = n;
            try {
                SimRunner probe(worlds, s, context_seed, use_table);
            } catch (const UserError &e) {
                throw UserError("distribution " + d.name + ", " + f.label() + ": " + e.what());
            }
        }
    }
}

} // namespace qnav
