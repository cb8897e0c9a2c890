/*
 * simevo: evolve navigation policies in the simulator with the paper's ε-greedy
 * neuro-evolution, transfer them between situations, and run the paper's five transfer
 * experiments with summaries and plots. Subcommands: run, list, evolve, eval, quality.
 * Every problem ends in one line on stderr: exit status 2 for bad usage or bad input found
 * before any work starts (options, experiment files, policy files, robots, environments),
 * 1 for a failure while running (docs/cli.md).
 */
#include <CLI/CLI.hpp>

#include "qnav/cli.hpp"
#include "qnav/paths.hpp"

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <algorithm>
#include <unistd.h>

#include "experiment.h"
#include "files.h"
#include "qnav/policy_io.h"
#include "sim_runner.h"
#include "stats.h"

#ifndef QNAV_SOURCE_DIR
#define QNAV_SOURCE_DIR "."
#endif

using namespace qnav;

namespace {

std::vector<std::string> list_experiments(const std::string &dir)
{
    std::vector<std::string> names;
    DIR *d = ::opendir(dir.c_str());
    if (!d) {
        throw UserError(dir + ": cannot open the experiments folder (set --experiments or QNAV_EXPERIMENTS_DIR)");
    }
    while (dirent *e = ::readdir(d)) {
        std::string n = e->d_name;
        if (n.size() > 5 && n.compare(n.size() - 5, 5, ".toml") == 0) {
            names.push_back(n.substr(0, n.size() - 5));
        }
    }
    ::closedir(d);
    std::sort(names.begin(), names.end());
    return names;
}

std::string resolve_experiment(const std::string &arg, const std::string &dir)
{
    if (arg.find('/') != std::string::npos || (arg.size() > 5 && arg.compare(arg.size() - 5, 5, ".toml") == 0)) {
        return arg;
    }
    const std::string path = join_path(dir, arg + ".toml");
    if (!file_exists(path)) {
        std::string known;
        for (const auto &n : list_experiments(dir)) {
            known += (known.empty() ? "" : ", ") + n;
        }
        throw UserError("unknown experiment '" + arg + "' (known: " + known + ", all)");
    }
    return path;
}

/* set(scenario) for the target and every source of s (settings that apply to all). */
template <typename F>
void for_each_scenario(ExperimentSpec &s, F set)
{
    set(s.target);
    for (SourceSpec &src : s.sources) {
        set(src.scenario);
    }
}

/* The rule --fitness names ("" = the default). Throws UserError. */
qnav_sim_fitness_rule_t fitness_option(const std::string &name)
{
    qnav_sim_fitness_rule_t rule = QNAV_SIM_FITNESS_PROGRESS;
    if (!name.empty() && qnav_sim_fitness_rule_parse(name.c_str(), &rule) != QNAV_SIM_OK) {
        throw UserError("--fitness: '" + name + "' is not one of " + qnav_sim_fitness_rule_names());
    }
    return rule;
}

/* --controller NAME for every scenario of s. Throws UserError. */
void set_controller(ExperimentSpec &s, const std::string &name)
{
    ControllerReading c;
    if (!controller_reading_parse(name, &c)) {
        throw UserError("--controller: '" + name + "' is not one of body, literal");
    }
    for_each_scenario(s, [c](Scenario &sc) { sc.controller = c; });
}

/* --fitness NAME for every scenario of s. Throws UserError. */
void set_fitness(ExperimentSpec &s, const std::string &name)
{
    const qnav_sim_fitness_rule_t rule = fitness_option(name);
    for_each_scenario(s, [rule](Scenario &sc) { sc.fitness = rule; });
}

/* The overrides given to `simevo run` that change results, as flags (" --runs 3 --fitness
 * paper"); --network-mode is not one (bit-identical to table mode by design). */
std::string override_flags(int64_t runs, int64_t episodes, int64_t source_episodes, int64_t eval_episodes, int64_t seed,
                           int64_t per_candidate, const std::string &fitness, const std::string &controller)
{
    std::string o;
    auto add = [&o](const char *flag, int64_t v, bool given) {
        if (given) {
            o += std::string(" ") + flag + " " + std::to_string(v);
        }
    };
    add("--runs", runs, runs > 0);
    add("--episodes", episodes, episodes > 0);
    add("--source-episodes", source_episodes, source_episodes > 0);
    add("--eval-episodes", eval_episodes, eval_episodes > 0);
    add("--seed", seed, seed >= 0);
    add("--per-candidate", per_candidate, per_candidate > 0);
    o += fitness.empty() ? "" : " --fitness " + fitness;
    o += controller.empty() ? "" : " --controller " + controller;
    return o;
}

/* What a user takes to a robot: each transfer's best policy and how often it arrives. */
void print_transfer_arrival(const ExperimentSpec &s, const std::string &dir)
{
    const ExperimentSummary S = summarize(s, plan_tasks(s, dir));
    for (const ConditionSummary &c : S.conditions) {
        if (c.kind != ConditionKind::Transfer || c.best_run < 0) {
            continue;
        }
        std::printf("%s: best transferred policy %s (run %d) arrives in %.0f%% of %u held-out episodes "
                    "(all runs: %.0f%%)\n",
                    s.name.c_str(), best_policy_copy(dir, c.label).c_str(), c.best_run + 1,
                    100.0 * c.arrival_per_run[static_cast<std::size_t>(c.best_run)], s.eval_episodes,
                    100.0 * c.arrival.mean);
    }
}

Scenario scenario_from(const std::string &env, const std::string &robot, uint32_t sectors, double noise,
                       double sensor_noise, double actuation_noise, const std::string &fitness)
{
    Scenario s;
    s.fitness = fitness_option(fitness);
    s.environment = env;
    s.robot = robot;
    s.sectors = sectors;
    s.sensor_noise = sensor_noise >= 0 ? sensor_noise : noise;
    s.actuation_noise = actuation_noise >= 0 ? actuation_noise : noise;
    return s;
}

} // namespace

int main(int argc, char **argv)
{
    CLI::App app{"simevo: ε-greedy neuro-evolution and policy transfer for qnav (paper §3.3, §4)"};
    app.require_subcommand(1);
    qnav::cli::add_version(app, "simevo");
    std::string experiments_dir =
        resource_dir("QNAV_EXPERIMENTS_DIR", "experiments", std::string(QNAV_SOURCE_DIR) + "/experiments");
    app.add_option("--experiments", experiments_dir, "folder of experiment files")->capture_default_str();

    // run
    auto *run = app.add_subcommand("run", "run named experiments (resumes an interrupted run in the same --out)");
    std::vector<std::string> names;
    RunOptions opt;
    opt.tools_dir = resource_dir("QNAV_TOOLS_DIR", "tools", std::string(QNAV_SOURCE_DIR) + "/tools");
    std::string preset = "full";
    int64_t runs = 0, episodes = 0, source_episodes = 0, eval_episodes = 0, seed = -1, per_candidate = 0;
    std::string fitness, controller;
    bool no_plot = false, no_progress = false, network_mode = false;
    run->add_option("experiment", names, "experiment name(s), a .toml path, or 'all'")->required();
    run->add_option("--preset", preset, "'full' (the file's values) or a preset the file defines, e.g. 'quick'")->capture_default_str();
    run->add_option("--out", opt.out_dir, "output folder; results go to OUT/<experiment>")->capture_default_str();
    run->add_option("-j,--jobs", opt.jobs, "worker threads (0 = all cores)")->capture_default_str();
    run->add_option("--runs", runs, "override the number of independent runs")->check(CLI::Range(int64_t(1), int64_t(10000)));
    run->add_option("--episodes", episodes, "override target episodes")->check(CLI::Range(int64_t(1), int64_t(100000000)));
    run->add_option("--source-episodes", source_episodes, "override source episodes")->check(CLI::Range(int64_t(1), int64_t(100000000)));
    run->add_option("--eval-episodes", eval_episodes, "override held-out evaluation episodes")->check(CLI::Range(int64_t(1), int64_t(1000000)));
    run->add_option("--seed", seed, "override the master seed")->check(CLI::Range(int64_t(0), INT64_MAX));
    run->add_option("--per-candidate", per_candidate, "override episodes per candidate (k)")->check(CLI::Range(int64_t(1), int64_t(1000)));
    run->add_option("--fitness", fitness, "override the fitness rule: progress or paper (docs/sim.md)");
    run->add_option("--controller", controller,
                    "override the controller's reading: body, or literal (the paper's per-sector "
                    "mapping, no speed guard, rank by quality; docs/architecture.md)");
    run->add_option("--tools-dir", opt.tools_dir, "folder with plot_learning.py and plot_policy.py")->capture_default_str();
    run->add_flag("--no-plot", no_plot, "skip the PNG plots");
    run->add_flag("--no-progress", no_progress, "no progress line even on a terminal");
    run->add_flag("--network-mode", network_mode, "run the controller in network mode instead of table mode");

    auto *lst = app.add_subcommand("list", "list the experiment files");

    // evolve: one evolution, optionally seeded from a policy file (transfer)
    auto *evolve = app.add_subcommand("evolve", "evolve one population in one situation (transfer with --from)");
    std::string env = "dense", robot = "tekbot", from, out_dir = "runs/evolve";
    uint32_t sectors = 0;
    double noise = 0, sensor_noise = -1, actuation_noise = -1;
    uint64_t ev_episodes = 1000, ev_seed = 1;
    uint32_t ev_eval = 50;
    EvolutionParams ep;
    evolve->add_option("--env", env, "environment name or file")->capture_default_str();
    evolve->add_option("--robot", robot, "robot profile name or file")->capture_default_str();
    evolve->add_option("--sectors", sectors, "sonar sectors (0 = robot default)")->check(CLI::Range(0, 360));
    evolve->add_option("--noise", noise, "sensor and actuation noise level p (0.05 = 5%)")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--sensor-noise", sensor_noise, "sensor noise only")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--actuation-noise", actuation_noise, "actuation noise only")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--from", from, "policy file to seed the population from (transfer)");
    evolve->add_option("--episodes", ev_episodes, "episodes")->capture_default_str()->check(CLI::Range(uint64_t(1), uint64_t(100000000)));
    evolve->add_option("--eval-episodes", ev_eval, "held-out evaluation episodes of the best")->capture_default_str()->check(CLI::Range(1u, 1000000u));
    evolve->add_option("--seed", ev_seed, "seed")->capture_default_str();
    evolve->add_option("--fitness", fitness, "fitness rule: progress (default) or paper");
    evolve->add_option("--population", ep.population, "population size")->capture_default_str();
    evolve->add_option("--epsilon", ep.epsilon, "probability of mutating a random member")->capture_default_str();
    evolve->add_option("--hidden", ep.hidden, "hidden units of random networks")->capture_default_str();
    evolve->add_option("--mutation-scale", ep.mutation_scale, "Cauchy scale, weight units")->capture_default_str();
    evolve->add_option("--mutation-clip", ep.mutation_clip, "Cauchy clip, weight units")->capture_default_str();
    evolve->add_option("--per-candidate", ep.episodes_per_candidate, "episodes averaged per fitness value")->capture_default_str();
    evolve->add_flag("--reevaluate-parent", ep.reevaluate_parent, "also re-run the parent each step (noisy fitness)");
    evolve->add_option("--out", out_dir, "output folder")->capture_default_str();

    // eval: a policy over held-out episodes
    auto *eval = app.add_subcommand("eval", "evaluate a policy file ('prob' = the probabilistic policy) over episodes");
    std::string policy_arg;
    std::string e_env = "dense", e_robot = "tekbot";
    uint32_t e_sectors = 0, e_episodes = 50;
    double e_noise = 0;
    uint64_t e_seed = 1;
    eval->add_option("policy", policy_arg, "policy file, or 'prob'")->required();
    eval->add_option("--env", e_env, "environment")->capture_default_str();
    eval->add_option("--robot", e_robot, "robot profile")->capture_default_str();
    eval->add_option("--sectors", e_sectors, "sonar sectors (0 = robot default)")->check(CLI::Range(0, 360));
    eval->add_option("--noise", e_noise, "noise level p")->check(qnav::cli::finite_range(0.0, 1.0));
    eval->add_option("--episodes", e_episodes, "episodes")->capture_default_str()->check(CLI::Range(1u, 1000000u));
    eval->add_option("--seed", e_seed, "seed")->capture_default_str();
    eval->add_option("--fitness", fitness, "fitness rule: progress (default) or paper");

    // quality: Figs. 2-3 for any policy files
    auto *quality = app.add_subcommand("quality", "plot path quality over (dtheta, distance) of policy files (paper Figs. 2-3)");
    std::vector<std::string> q_policies;
    std::string q_out = "runs/quality";
    uint32_t q_range = 5000;
    std::string q_robot = "tekbot";
    quality->add_option("policy", q_policies, "policy files, or 'prob' (the robot's tuned probabilistic policy)")->required();
    quality->add_option("--robot", q_robot, "robot profile whose probabilistic policy 'prob' means")->capture_default_str();
    quality->add_option("--out", q_out, "folder for quality.csv and policy.png")->capture_default_str();
    quality->add_option("--range-mm", q_range, "sonar maximum range for the distance axis, mm")
        ->capture_default_str()->check(CLI::Range(1, 65535));
    quality->add_option("--tools-dir", opt.tools_dir, "folder with plot_policy.py")->capture_default_str();

    if (const int status = qnav::cli::parse(app, argc, argv, "simevo"); status >= 0) {
        return status;
    }

    // Bad input found before any episode runs is exit 2; what goes wrong once work has
    // started (a write, a plot, a journal from other settings) is 1.
    bool started = false;
    try {
        if (*lst) {
            for (const auto &n : list_experiments(experiments_dir)) {
                const ExperimentSpec s = load_experiment(join_path(experiments_dir, n + ".toml"));
                std::printf("%-20s %-8s %s\n", n.c_str(), s.figure.c_str(), s.title.c_str());
            }
            return 0;
        }
        if (*run) {
            std::vector<std::string> paths;
            for (const auto &n : names) {
                if (n == "all") {
                    for (const auto &k : list_experiments(experiments_dir)) {
                        paths.push_back(join_path(experiments_dir, k + ".toml"));
                    }
                } else {
                    paths.push_back(resolve_experiment(n, experiments_dir));
                }
            }
            // Parse everything first: a bad file fails before any work starts.
            std::vector<ExperimentSpec> specs;
            for (const auto &p : paths) {
                ExperimentSpec s = load_experiment(p);
                apply_preset(s, preset);
                if (runs > 0) s.runs = static_cast<uint32_t>(runs);
                if (episodes > 0) s.target_episodes = static_cast<uint64_t>(episodes);
                if (source_episodes > 0) for (auto &src : s.sources) src.episodes = static_cast<uint64_t>(source_episodes);
                if (eval_episodes > 0) s.eval_episodes = static_cast<uint32_t>(eval_episodes);
                if (seed >= 0) s.seed = static_cast<uint64_t>(seed);
                if (per_candidate > 0) s.evolution.episodes_per_candidate = static_cast<uint32_t>(per_candidate);
                if (!fitness.empty()) set_fitness(s, fitness);
                if (!controller.empty()) set_controller(s, controller);
                specs.push_back(s);
            }
            opt.plots = !no_plot;
            opt.progress = no_progress ? 0 : -1;
            opt.use_table = !network_mode;
            opt.preset = preset;
            opt.overrides = override_flags(runs, episodes, source_episodes, eval_episodes, seed, per_candidate, fitness,
                                           controller);
            // every robot, environment and source policy file now, not after other runs
            SimWorlds probe_worlds;
            for (const auto &s : specs) {
                SimRunner target(probe_worlds, s.target, s.seed, true);
                for (const auto &src : s.sources) {
                    SimRunner source(probe_worlds, src.scenario, s.seed, true);
                    if (!src.policy_file.empty()) {
                        (void)read_policy_file(src.policy_file);
                    }
                }
            }
            started = true;
            for (const auto &s : specs) {
                const auto t0 = std::chrono::steady_clock::now();
                const std::string dir = run_experiment(s, opt);
                const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                std::printf("%s: complete in %.1f s; summary %s/summary.md\n", s.name.c_str(), secs, dir.c_str());
                if (opt.plots) {
                    std::printf("%s: plot %s/learning.png\n", s.name.c_str(), dir.c_str());
                }
                print_transfer_arrival(s, dir);
                std::fflush(stdout);
            }
            return 0;
        }
        if (*evolve) {
            if (const char *p = evolution_params_problem(ep); *p) {
                throw UserError(std::string("--") + p);
            }
            TaskDef t;
            t.label = from.empty() ? "direct" : "transfer";
            t.dir = out_dir;
            t.scenario = scenario_from(env, robot, sectors, noise, sensor_noise, actuation_noise, fitness);
            t.context_seed = ev_seed;
            t.episodes = ev_episodes;
            t.evolution = ep;
            t.evolution_seed = mix_seed(ev_seed, 1);
            t.episode_seed_base = mix_seed(ev_seed, 2);
            t.eval_episodes = ev_eval;
            t.eval_seed_base = mix_seed(ev_seed, 3);
            t.source_policy_file = from;
            SimWorlds worlds;
            RunnerFactory make = [&worlds](const Scenario &sc, uint64_t s) -> std::unique_ptr<EpisodeRunner> {
                return std::make_unique<SimRunner>(worlds, sc, s, true);
            };
            if (!from.empty()) {
                (void)read_policy_file(from); // a bad --from is bad input, found now
            }
            {
                SimRunner probe(worlds, t.scenario, t.context_seed, true); // bad env/robot: now
            }
            started = true;
            run_tasks({t}, make, 1, ::isatty(2) != 0, "evolve");
            std::printf("best policy %s/best.policy; episodes %s/episodes.csv; held-out %s/eval.csv\n",
                        out_dir.c_str(), out_dir.c_str(), out_dir.c_str());
            return 0;
        }
        if (*quality) {
            std::vector<std::pair<std::string, qnav_policy_t>> policies;
            for (const auto &arg : q_policies) {
                qnav_policy_t p;
                if (arg == "prob") {
                    SimWorlds worlds;
                    qnav_sim_robot_prob_policy(worlds.robot(q_robot), &p);
                } else {
                    p = read_policy_file(arg);
                }
                // Label: the last two path components (run folders all hold "best.policy"),
                // made unique with a number when needed.
                std::string label = condition_label(ConditionKind::Probabilistic);
                if (arg != "prob") {
                    const std::size_t last = arg.find_last_of('/');
                    const std::size_t prev = last == std::string::npos || last == 0 ? std::string::npos
                                                                                    : arg.find_last_of('/', last - 1);
                    label = prev == std::string::npos ? arg : arg.substr(prev + 1);
                }
                for (const auto &q : policies) {
                    if (q.first == label) {
                        label += " #" + std::to_string(policies.size() + 1);
                        break;
                    }
                }
                std::replace(label.begin(), label.end(), ',', ' ');
                policies.emplace_back(label, p);
            }
            qnav_ctrl_config_t ccfg;
            qnav_ctrl_config_default(&ccfg);
            ccfg.max_range_mm = static_cast<qnav_mm_t>(q_range);
            started = true;
            make_dirs(q_out);
            write_file_atomic(join_path(q_out, "quality.csv"), quality_table_csv(policies, ccfg));
            run_plot(opt, "plot_policy.py", q_out);
            std::printf("plot %s/policy.png\n", q_out.c_str());
            return 0;
        }
        if (*eval) {
            SimWorlds worlds;
            SimRunner runner(worlds, scenario_from(e_env, e_robot, e_sectors, e_noise, -1, -1, fitness), e_seed, true);
            qnav_policy_t p;
            if (policy_arg == "prob") {
                p = runner.probabilistic_policy();
            } else {
                p = read_policy_file(policy_arg);
            }
            started = true;
            std::vector<double> R, tau;
            uint32_t reached = 0;
            for (uint32_t i = 0; i < e_episodes; ++i) {
                const EpisodeOutcome o = runner.run(p, mix_seed(e_seed, i));
                R.push_back(o.R);
                reached += o.reached;
                tau.push_back(o.tau_c);
            }
            double lo = 0, hi = 0;
            wilson_ci95(reached, e_episodes, &lo, &hi);
            std::printf("episodes %u  mean R %.3f ± %.3f (95%% CI)  sd %.3f  reached %.0f%% (95%% CI %.0f-%.0f%%)  "
                        "mean tau_c %.1f ± %.1f ticks\n",
                        e_episodes, mean_of(R), ci95_half_width(R), sd_of(R), 100.0 * reached / std::max(1u, e_episodes),
                        100.0 * lo, 100.0 * hi, mean_of(tau), ci95_half_width(tau));
            return 0;
        }
    } catch (const UserError &e) {
        std::fprintf(stderr, "simevo: %s\n", e.what());
        return started ? QNAV_EXIT_FAILURE : QNAV_EXIT_USAGE;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "simevo: internal error: %s\n", e.what());
        return 1;
    }
    return 0;
}
