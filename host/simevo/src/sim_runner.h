/*
 * The EpisodeRunner that drives the Box2D simulator (sim/include/qnav/sim.h) with the
 * fixed-point libqnav controller. A network policy is compiled once per episode into a
 * quality table (qnav_ctrl_build_table + qnav_ctrl_init_table): bit-identical to network
 * mode by libqnav's design, and much cheaper over an episode's ticks. One SimRunner owns
 * one simulator context and is used by one thread; robots and environments are loaded
 * once (SimWorlds) and shared read-only.
 */
#ifndef QNAV_SIMEVO_SIM_RUNNER_H
#define QNAV_SIMEVO_SIM_RUNNER_H

#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "evolution.h"
#include "qnav/sim.h"
#include "spec.h"

namespace qnav {

/* Loaded robot profiles and environments by name, shared by all threads. */
class SimWorlds {
public:
    SimWorlds() = default;
    ~SimWorlds();
    SimWorlds(const SimWorlds &) = delete;
    SimWorlds &operator=(const SimWorlds &) = delete;
    /* Load (once) what the scenario names. Throws UserError with the sim's message. */
    const qnav_sim_robot_t *robot(const std::string &spec);
    const qnav_sim_env_t *env(const std::string &spec);
    /* A generated world ("gen:..."), made once and kept while at most kGeneratedKept are
     * (the oldest dropped first; a caller's reference keeps its own alive). */
    std::shared_ptr<const qnav_sim_env_t> generated(const std::string &spec);
    static constexpr std::size_t kGeneratedKept = 8192;

private:
    std::mutex mu_;
    std::map<std::string, qnav_sim_robot_t *> robots_;
    std::map<std::string, qnav_sim_env_t *> envs_;
    std::map<std::string, std::shared_ptr<const qnav_sim_env_t>> generated_;
    std::deque<std::string> generated_order_; /* oldest first */
};

class SimRunner : public EpisodeRunner {
public:
    /* context_seed: qnav_sim_config_t.seed. use_table: table mode (default) or network
     * mode (for the equivalence check). Throws UserError on bad scenarios. */
    SimRunner(SimWorlds &worlds, const Scenario &scenario, uint64_t context_seed,
              bool use_table = true);
    ~SimRunner() override;
    SimRunner(const SimRunner &) = delete;
    SimRunner &operator=(const SimRunner &) = delete;

    EpisodeOutcome run(const qnav_policy_t &policy, uint64_t episode_seed) override;
    /* The same episode driven by a policy-free controller ("vfh"), configured from the
     * robot profile like the path-quality controller. Throws UserError. */
    EpisodeOutcome run_controller(const char *controller, uint64_t episode_seed) override;
    /* run_controller, with every tick's sample appended to *trace when not null. */
    EpisodeOutcome run_controller_traced(const char *controller, uint64_t episode_seed,
                                         std::vector<qnav_sim_sample_t> *trace);
    /* The same episode, with every trajectory sample appended to *trace (for pictures). */
    EpisodeOutcome run_traced(const qnav_policy_t &policy, uint64_t episode_seed,
                              std::vector<qnav_sim_sample_t> *trace);
    /* The robot profile's hand-tuned probabilistic policy (qnav_sim_robot_prob_policy). */
    qnav_policy_t probabilistic_policy() const override { return prob_; }
    /* The controller configuration of this context (sectors, max range). */
    const qnav_ctrl_config_t &ctrl_config() const { return ctrl_cfg_; }

private:
    /* An episode's figures from the simulator's status and result; UserError on failure. */
    EpisodeOutcome outcome(qnav_sim_status_t s, const qnav_sim_result_t &res) const;
    /* A controller initialised with policy (in table mode when this runner uses tables and
     * the policy has one), built once per policy: a candidate's k episodes, and the next
     * step's parent, reuse it instead of evaluating the network over every (level, dtheta)
     * pair again (issue 19). The last two are kept: an evolution step runs a new candidate
     * and then, mostly, the same best member as its parent. Throws UserError. */
    const qnav_ctrl_t &controller_for(const qnav_policy_t &policy);

    struct Compiled {
        qnav_policy_t policy{};
        std::vector<qnav_qkey_t> table; /* the table ctrl reads in table mode */
        qnav_ctrl_t ctrl{};
        bool valid = false;
    };
    qnav_sim_t *sim_ = nullptr;
    qnav_ctrl_config_t ctrl_cfg_{};
    qnav_policy_t prob_{};
    bool use_table_;
    Compiled compiled_[2];
    unsigned least_recent_ = 0; /* index into compiled_ to overwrite next */
};

/* Check that every world a scenario can meet loads and runs: the scenario itself, or for
 * a distribution each component (a family at its lowest training seed and difficulty) with
 * each sector count. Throws UserError with the simulator's message. */
void probe_scenario(SimWorlds &worlds, const Scenario &scenario, uint64_t context_seed, bool use_table);

} // namespace qnav

#endif
