/*
 * A finished experiment's files other than the summary's text: the held-out worlds
 * (worlds.csv, recommended.policy), the quality map (quality.csv), the episode traces
 * (episodes.csv), best-<condition>.policy, and the plots drawn by tools/plot_*.py.
 */
#include "experiment_outputs.h"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <sstream>

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "experiment_report.h"
#include "files.h"
#include "qnav/ctrl.h"
#include "qnav/policy_io.h"
#include "rng.h"
#include "worlds.h"

namespace qnav {

Scenario picture_scenario(const Scenario &target)
{
    if (!target.distribution) {
        return target;
    }
    Scenario s = target;
    s.distribution.reset();
    s.environment.clear();
    for (const FamilySpec &f : target.distribution->families) {
        if (!f.environment.empty()) {
            s.environment = f.environment;
            break;
        }
    }
    if (s.environment.empty()) {
        const std::vector<std::string> named = named_environments();
        if (named.empty()) {
            throw UserError("data/envs: no named environment to draw the episodes in");
        }
        s.environment = named.front();
    }
    return s;
}

HeldOut evaluate_held_out(const ExperimentSpec &spec, const ExperimentSummary &S, const std::string &exp_dir,
                          SimWorlds &worlds, const RunOptions &opt)
{
    HeldOut H;
    H.episodes = spec.worlds_episodes;
    const bool use_table = opt.use_table;
    for (const HeldOutWorld &w : held_out_worlds(spec.target)) {
        try {
            if (!w.family) {
                SimRunner probe(worlds, w.scenario, spec.seed, use_table);
            }
            H.worlds.push_back(w);
        } catch (const UserError &e) {
            H.skipped.push_back(w.label + ": " + e.what());
        }
    }
    WorldRunnerFactory make = [&worlds, use_table](const Scenario &sc, uint64_t seed) -> std::unique_ptr<EpisodeRunner> {
        return std::make_unique<SimRunner>(worlds, sc, seed, use_table);
    };
    const std::vector<WorldRow> rows = evaluate_held_out_worlds(spec, S, exp_dir, H.worlds, make, opt.jobs);
    write_file_atomic(join_path(exp_dir, "worlds.csv"), world_rows_csv(rows));
    H.conditions = summarize_worlds(S, H.worlds, rows);
    if (spec.target.distribution) {
        H.recommended = recommend(S, H.worlds, rows, spec.eval_episodes);
        if (H.recommended.valid && H.recommended.reference()) {
            const SimRunner robot(worlds, picture_scenario(spec.target), spec.seed, use_table);
            const qnav_policy_t prob = robot.probabilistic_policy();
            char err[QNAV_POLICY_IO_ERRLEN] = {0};
            if (qnav_policy_write(recommended_policy_path(exp_dir).c_str(), &prob,
                                  "simevo: the robot's probabilistic policy (no evolved run was ahead of it "
                                  "on the validation worlds)", err, sizeof err) != 0) {
                throw UserError(err);
            }
        } else if (H.recommended.valid) {
            const std::string from = join_path(join_path(run_dir(exp_dir, H.recommended.run - 1), H.recommended.condition),
                                               "best.policy");
            std::string text;
            if (!read_file(from, text)) {
                throw UserError(from + ": cannot read (" + std::strerror(errno) + ")");
            }
            write_file_atomic(recommended_policy_path(exp_dir), text);
        }
    }
    return H;
}

namespace {

std::string quality_csv(const ExperimentSummary &S, const std::string &exp_dir, const qnav_ctrl_config_t &ccfg,
                        const qnav_policy_t &prob)
{
    std::vector<std::pair<std::string, qnav_policy_t>> policies;
    policies.emplace_back(condition_label(ConditionKind::Probabilistic), prob);
    for (const ConditionSummary &c : S.conditions) {
        if (!condition_decl(c.kind).evolved || c.best_run < 0) {
            continue;
        }
        const std::string path = join_path(join_path(run_dir(exp_dir, static_cast<uint32_t>(c.best_run)), c.label), "best.policy");
        policies.emplace_back(c.label + " (run " + std::to_string(c.best_run + 1) + ")", read_policy_file(path));
    }
    return quality_table_csv(policies, ccfg);
}

/* Held-out episodes whose trajectories are drawn per condition (episodes.png). */
constexpr uint32_t kPictureEpisodes = 3;

/* Trajectories of the best policy of every condition (and the probabilistic policy) on
 * the first held-out episodes: the episodes.csv that tools/plot_episodes.py draws. */
std::string episodes_csv(const ExperimentSummary &S, const std::string &exp_dir, SimRunner &runner,
                         uint64_t eval_base, uint32_t eval_episodes)
{
    std::ostringstream o;
    o << "condition,episode,tick,x_m,y_m,recovering,collided,R,reached,tau_c\n";
    for (const ConditionSummary &c : S.conditions) {
        qnav_policy_t policy = runner.probabilistic_policy();
        std::string name = c.label;
        if (condition_decl(c.kind).evolved) {
            if (c.best_run < 0) {
                continue;
            }
            const uint32_t run = static_cast<uint32_t>(c.best_run);
            policy = read_policy_file(join_path(join_path(run_dir(exp_dir, run), c.label), "best.policy"));
            name += " (run " + std::to_string(run + 1) + ")";
        }
        for (uint32_t i = 0; i < std::min(kPictureEpisodes, eval_episodes); ++i) {
            std::vector<qnav_sim_sample_t> trace;
            const uint64_t seed = mix_seed(eval_base, i);
            const ReferenceDecl *ref = condition_decl(c.kind).reference;
            const EpisodeOutcome out = ref != nullptr && ref->controller != nullptr
                                           ? runner.run_controller_traced(ref->controller, seed, &trace)
                                           : runner.run_traced(policy, seed, &trace);
            for (const qnav_sim_sample_t &smp : trace) {
                char b[256];
                std::snprintf(b, sizeof b, ",%u,%u,%.4f,%.4f,%d,%d,%.4f,%d,%u\n", i, smp.tick, smp.x_m, smp.y_m,
                              smp.recovering ? 1 : 0, smp.collided ? 1 : 0, out.R, out.reached ? 1 : 0, out.tau_c);
                o << name << b;
            }
        }
    }
    return o.str();
}

} // namespace

void run_plot(const RunOptions &opt, const std::string &script, const std::string &exp_dir)
{
    const std::string path = join_path(opt.tools_dir, script);
    if (!file_exists(path)) {
        throw UserError(path + ": plot script not found (set --tools-dir or QNAV_TOOLS_DIR, or use --no-plot)");
    }
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
        throw UserError(opt.python + ": cannot start (" + std::strerror(errno) + ")");
    }
    if (pid == 0) {
        // The plot dies with simevo (kill -9 included): a leftover plotter would race the
        // resumed run for the same output files.
        if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) {
            ::_exit(127);
        }
        ::execl(opt.python.c_str(), opt.python.c_str(), path.c_str(), exp_dir.c_str(), static_cast<char *>(nullptr));
        std::fprintf(stderr, "%s: cannot run (%s)\n", opt.python.c_str(), std::strerror(errno));
        ::_exit(127);
    }
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        throw UserError(path + ": plotting failed for " + exp_dir);
    }
}

namespace {
/* What a rank key stands for in real units: the output pre-activation z for
 * QNAV_RANK_PREACT (Q5.11 below the knee |z| = 8, 1/128 per key step beyond it;
 * docs/qformats.md), the quality for QNAV_RANK_QUALITY. */
double key_value(qnav_qkey_t key, qnav_rank_t rank)
{
    if (rank == QNAV_RANK_QUALITY) {
        return key / 32768.0;
    }
    const int32_t a = key < 0 ? -static_cast<int32_t>(key) : key;
    const double z = a < 16384 ? a / 2048.0 : 8.0 + (a - 16384) / 128.0;
    return key < 0 ? -z : z;
}
} // namespace

std::string quality_table_csv(const std::vector<std::pair<std::string, qnav_policy_t>> &policies,
                              const qnav_ctrl_config_t &ccfg)
{
    std::ostringstream o;
    // quality: what sets the speed; key: what the argmax ranks paths by (issue 21: a
    // saturated network's quality is flat where its pre-activation still decides)
    o << "policy,level,distance_m,dtheta_deg,quality,rank,key\n";
    for (auto &pp : policies) {
        qnav_ctrl_t ctrl;
        if (qnav_ctrl_init(&ctrl, &ccfg, &pp.second) != QNAV_OK) {
            throw UserError("quality map: the controller refused policy " + pp.first);
        }
        const qnav_rank_t rank = qnav_ctrl_rank(&ctrl);
        for (uint32_t level = 0; level < QNAV_DIST_LEVELS; ++level) {
            const double dist = static_cast<double>(level) / (QNAV_DIST_LEVELS - 1) * ccfg.max_range_mm / 1000.0;
            for (uint32_t dt = 0; dt <= QNAV_DTHETA_MAX; ++dt) {
                const qnav_qkey_t k = qnav_ctrl_key(&ctrl, static_cast<uint8_t>(level), static_cast<uint8_t>(dt));
                const qnav_q1_15_t q = qnav_ctrl_quality(&ctrl, static_cast<uint8_t>(level), static_cast<uint8_t>(dt));
                char b[200];
                std::snprintf(b, sizeof b, "%s,%u,%.4f,%u,%.6f,%s,%.6f\n", pp.first.c_str(), level, dist, dt,
                              q / 32768.0, rank == QNAV_RANK_PREACT ? "preact" : "quality", key_value(k, rank));
                o << b;
            }
        }
    }
    return o.str();
}

std::string best_policy_copy(const std::string &exp_dir, const std::string &condition)
{
    return join_path(exp_dir, "best-" + condition + ".policy");
}

namespace {

/* Each evolved condition's best policy (the run that scored highest held out) copied to
 * best-<condition>.policy beside summary.md: one stable name to take to a robot. */
void write_best_policies(const ExperimentSummary &S, const std::string &exp_dir)
{
    for (const ConditionSummary &c : S.conditions) {
        if (!condition_decl(c.kind).evolved || c.best_run < 0) {
            continue;
        }
        const std::string from =
            join_path(join_path(run_dir(exp_dir, static_cast<uint32_t>(c.best_run)), c.label), "best.policy");
        std::string text;
        if (!read_file(from, text)) {
            throw UserError(from + ": cannot read (" + std::strerror(errno) + ")");
        }
        write_file_atomic(best_policy_copy(exp_dir, c.label), text);
    }
}

} // namespace

void write_outputs(const ExperimentSpec &spec, const ExperimentSummary &S, const std::vector<TaskDef> &tasks,
                   const std::string &exp_dir, SimWorlds &worlds, SimRunner &target_runner, const RunOptions &opt,
                   const HeldOut &H)
{
    const std::string status_path = join_path(exp_dir, "STATUS");
    write_file_atomic(join_path(exp_dir, "curves.csv"), curves_csv(S));
    write_file_atomic(join_path(exp_dir, "quality.csv"), quality_csv(S, exp_dir, target_runner.ctrl_config(),
                                                                   target_runner.probabilistic_policy()));
    qnav_sim_env_info_t env_info;
    qnav_sim_env_info(worlds.env(picture_scenario(spec.target).environment), &env_info);
    qnav_sim_robot_info_t robot_info;
    qnav_sim_robot_info(worlds.robot(spec.target.robot), &robot_info);
    write_file_atomic(join_path(exp_dir, "summary.json"),
                      summary_json(spec, S, opt, env_info.source, robot_info.radius_m, H));
    write_best_policies(S, exp_dir);
    const uint64_t eval_base = tasks.back().eval_seed_base; // the probabilistic task's: the held-out set
    write_file_atomic(join_path(exp_dir, "episodes.csv"),
                      episodes_csv(S, exp_dir, target_runner, eval_base, spec.eval_episodes));
    if (opt.plots) {
        write_file_atomic(status_path, "incomplete: runs finished, plots missing\n");
        try {
            run_plot(opt, "plot_learning.py", exp_dir);
            run_plot(opt, "plot_policy.py", exp_dir);
            run_plot(opt, "plot_episodes.py", exp_dir);
        } catch (const UserError &e) {
            throw UserError(std::string(e.what()) + " (results are complete except plots; STATUS says so)");
        }
    }
}

} // namespace qnav
