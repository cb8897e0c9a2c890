/*
 * simevo: evolve navigation policies in the simulator with the paper's ε-greedy
 * neuro-evolution, transfer them between situations, and run the paper's five transfer
 * experiments with summaries and plots. Subcommands: run, summarize, slurm, list, evolve,
 * eval, quality.
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
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <sys/wait.h>
#include <dirent.h>
#include <algorithm>
#include <unistd.h>

#include "cluster.h"
#include "experiment.h"
#include "files.h"
#include "fit.h"
#include "heldout.h"
#include "qnav/policy_io.h"
#include "sim_runner.h"
#include "stats.h"
#include "sweep.h"

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

/* A relative file path that does not exist from the working folder is taken from the folder
 * that holds the experiments folder: qnav's share folder when installed (sweeps/ and
 * experiments/extra/ are installed there), the source tree otherwise. So
 * `simevo run sweeps/open-to-dense-noise.toml` works from any folder. */
std::string resolve_file_argument(const std::string &arg, const std::string &experiments_dir)
{
    if (arg.empty() || arg[0] == '/' || file_exists(arg)) {
        return arg;
    }
    const std::string shared = join_path(experiments_dir + "/..", arg);
    return file_exists(shared) ? shared : arg;
}

std::string resolve_experiment(const std::string &arg, const std::string &dir)
{
    if (arg.find('/') != std::string::npos || (arg.size() > 5 && arg.compare(arg.size() - 5, 5, ".toml") == 0)) {
        return resolve_file_argument(arg, dir);
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

/* The rule --fitness names ("" = the default). Throws UserError. */
qnav_sim_fitness_rule_t fitness_option(const std::string &name)
{
    qnav_sim_fitness_rule_t rule = QNAV_SIM_FITNESS_PROGRESS;
    if (!name.empty() && qnav_sim_fitness_rule_parse(name.c_str(), &rule) != QNAV_SIM_OK) {
        throw UserError("--fitness: '" + name + "' is not one of " + qnav_sim_fitness_rule_names());
    }
    return rule;
}

/* The options of `simevo run` that change results (also taken by `simevo slurm`). */
void add_run_args(CLI::App *c, RunArgs &a)
{
    c->add_option("--preset", a.preset, "'full' (the file's values) or a preset the file defines, e.g. 'quick'")->capture_default_str();
    c->add_option("--runs", a.runs, "override the number of independent runs")->check(CLI::Range(int64_t(1), int64_t(10000)));
    c->add_option("--episodes", a.episodes, "override target episodes")->check(CLI::Range(int64_t(1), int64_t(100000000)));
    c->add_option("--source-episodes", a.source_episodes, "override source episodes")->check(CLI::Range(int64_t(1), int64_t(100000000)));
    c->add_option("--eval-episodes", a.eval_episodes, "override held-out evaluation episodes")->check(CLI::Range(int64_t(1), int64_t(1000000)));
    c->add_option("--seed", a.seed, "override the master seed")->check(CLI::Range(int64_t(0), INT64_MAX));
    c->add_option("--per-candidate", a.per_candidate, "override episodes per candidate (k)")->check(CLI::Range(int64_t(1), int64_t(1000)));
    c->add_option("--fitness", a.fitness, "override the fitness rule: progress or paper (docs/sim.md)");
    c->add_option("--controller", a.controller,
                  "override the controller's reading: one of " + controller_reading_names() +
                      " (literal: the paper's per-sector mapping, no speed guard, rank by "
                      "quality; docs/architecture.md)");
    c->add_option("--vary", a.vary,
                  "KEY=VALUE: set the target situation's noise or sectors and name the experiment "
                  "NAME.KEY-VALUE (one member of a sweep; docs/cluster.md)");
    c->add_flag("--network-mode", a.network_mode, "run the controller in network mode instead of table mode");
}

/* An absolute path for a file that exists (scripts and run.txt must work from anywhere). */
std::string absolute_path(const std::string &path)
{
    char *r = ::realpath(path.c_str(), nullptr);
    if (!r) {
        throw UserError(path + ": " + std::strerror(errno));
    }
    std::string out = r;
    std::free(r);
    return out;
}

/* OUT made absolute (created if missing). */
std::string absolute_dir(const std::string &dir)
{
    make_dirs(dir);
    return absolute_path(dir);
}

/* One experiment to run: its file (absolute), the options it runs with, its spec. */
struct RunItem {
    std::string file;
    RunArgs args;
    ExperimentSpec spec;
};

/* An experiment file or a sweep file's members as (path, args) pairs in order. */
void add_run_paths(const std::string &path, const RunArgs &args, const std::string &experiments_dir,
                   std::vector<std::pair<std::string, RunArgs>> &paths, std::vector<Sweep> &sweeps)
{
    if (!is_sweep_file(path)) {
        paths.emplace_back(path, args);
        return;
    }
    if (!args.vary.empty()) {
        throw UserError("--vary: not with a sweep file (" + path + "); its members are the variations");
    }
    sweeps.push_back(load_sweep(path, [&](const std::string &n) { return resolve_experiment(n, experiments_dir); }));
    for (const SweepMember &mb : sweeps.back().members) {
        RunArgs a = args;
        a.vary = mb.vary;
        paths.emplace_back(mb.experiment_file, a);
    }
}

/* Every experiment named, sweeps expanded into their members (all parsed first: a bad file
 * fails before any work), with every robot, environment and source policy file checked. */
std::vector<RunItem> load_run_specs(const std::vector<std::string> &names, const std::string &experiments_dir,
                                    const RunArgs &args, std::vector<Sweep> &sweeps)
{
    std::vector<std::pair<std::string, RunArgs>> paths;
    for (const auto &n : names) {
        if (n == "all") {
            // the paper's experiments (a file that names the figure it reproduces); the
            // others (generalist) run by name
            for (const auto &k : list_experiments(experiments_dir)) {
                const std::string path = join_path(experiments_dir, k + ".toml");
                if (!load_experiment(path).figure.empty()) {
                    paths.emplace_back(path, args);
                }
            }
        } else {
            add_run_paths(resolve_experiment(n, experiments_dir), args, experiments_dir, paths, sweeps);
        }
    }
    std::vector<RunItem> items;
    for (const auto &p : paths) {
        items.push_back({absolute_path(p.first), p.second, load_run_spec(p.first, p.second)});
    }
    SimWorlds probe_worlds;
    for (const RunItem &it : items) {
        const ExperimentSpec &s = it.spec;
        try {
            probe_scenario(probe_worlds, s.target, s.seed, true);
        } catch (const UserError &e) {
            throw UserError(s.file + ": [target]: " + e.what());
        }
        for (const auto &src : s.sources) {
            try {
                probe_scenario(probe_worlds, src.scenario, s.seed, true);
            } catch (const UserError &e) {
                throw UserError(s.file + ": [[source]] " + src.label + ": " + e.what());
            }
            if (!src.policy_file.empty()) {
                (void)read_policy_file(src.policy_file);
            }
        }
    }
    return items;
}

/* RunOptions of a run with these args (plots, progress and folders set by the caller). */
void set_run_options(RunOptions &opt, const RunArgs &args, const std::string &experiment_file)
{
    opt.use_table = !args.network_mode;
    opt.preset = args.preset;
    opt.overrides = override_flags(args);
    opt.run_record = run_record_text(experiment_file, args);
    opt.experiment_file = experiment_file;
}

int summarize_sweep(const std::string &dir, const std::string &record_path, const RunOptions &opt, bool &started);
void print_recommendation(const ExperimentSpec &s, const std::string &dir);

/* `simevo summarize DIR`: the experiment's spec from DIR/run.txt, every task finished, then
 * the same outputs as a local run. Returns the exit status. */
int summarize_folder(const std::string &dir_arg, RunOptions opt, bool &started)
{
    std::string dir = dir_arg;
    while (dir.size() > 1 && dir.back() == '/') {
        dir.pop_back();
    }
    const std::string record_path = join_path(dir, "run.txt");
    if (file_exists(join_path(dir, "sweep.txt"))) {
        return summarize_sweep(dir, join_path(dir, "sweep.txt"), opt, started);
    }
    std::string record;
    if (!read_file(record_path, record)) {
        throw UserError(record_path + ": not found; " + dir + " is not a simevo experiment folder");
    }
    std::string file;
    const RunArgs args = parse_run_record(record, record_path, &file);
    const ExperimentSpec spec = load_run_spec(file, args);
    const std::size_t slash = dir.find_last_of('/');
    const std::string base = slash == std::string::npos ? dir : dir.substr(slash + 1);
    if (base != spec.name) {
        throw UserError(dir + ": holds experiment '" + spec.name + "' (" + record_path + "), the folder must be named so");
    }
    opt.out_dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : dir.substr(0, slash));
    set_run_options(opt, args, file);
    started = true; // bad input above is exit 2; what fails from here on, 1
    const std::vector<TaskDef> tasks = prepare_experiment(spec, opt);
    const std::vector<std::string> missing = unfinished_tasks(tasks, join_path(opt.out_dir, spec.name));
    for (const std::string &m : missing) {
        std::fprintf(stderr, "simevo: %s/%s\n", dir.c_str(), m.c_str());
    }
    if (!missing.empty()) {
        std::fprintf(stderr, "simevo: %s: %zu of %zu tasks not finished; no summary written (rerun their shares)\n",
                     dir.c_str(), missing.size(), tasks.size());
        return QNAV_EXIT_FAILURE;
    }
    finish_experiment(spec, tasks, opt);
    std::printf("%s: merged %zu tasks; summary %s/summary.md\n", spec.name.c_str(), tasks.size(), dir.c_str());
    print_recommendation(spec, join_path(opt.out_dir, spec.name));
    return 0;
}

/* `simevo summarize DIR/SWEEP`: every member folder listed in DIR/SWEEP/sweep.txt merged
 * as `simevo summarize DIR/MEMBER` would; each member's unfinished tasks are named. Returns
 * the exit status (1 when any member is not finished). */
int summarize_sweep(const std::string &dir, const std::string &record_path, const RunOptions &opt, bool &started)
{
    std::string record;
    (void)read_file(record_path, record);
    const std::vector<std::string> members = parse_sweep_record(record, record_path);
    const std::string out = dir.find('/') == std::string::npos ? "." : dir.substr(0, dir.find_last_of('/'));
    std::size_t unfinished = 0;
    for (const std::string &name : members) {
        const std::string member_dir = join_path(out.empty() ? "/" : out, name);
        if (!file_exists(join_path(member_dir, "run.txt"))) {
            std::fprintf(stderr, "simevo: %s: not started (no run.txt)\n", member_dir.c_str());
            ++unfinished;
            continue;
        }
        bool member_started = false;
        unfinished += summarize_folder(member_dir, opt, member_started) != 0;
        started = started || member_started;
        std::fflush(stdout);
    }
    if (unfinished > 0) {
        std::fprintf(stderr, "simevo: %s: %zu of %zu experiments not finished (their missing tasks above)\n",
                     dir.c_str(), unfinished, members.size());
        return QNAV_EXIT_FAILURE;
    }
    std::printf("%s: merged %zu experiment%s\n", dir.c_str(), members.size(), members.size() == 1 ? "" : "s");
    return 0;
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

/* A distribution target's recommended policy and its test figures, one line per world
 * (nothing for other experiments). */
void print_recommendation(const ExperimentSpec &s, const std::string &dir)
{
    if (!s.target.distribution) {
        return;
    }
    const ExperimentSummary S = summarize(s, plan_tasks(s, dir));
    const std::vector<HeldOutWorld> worlds = held_out_worlds(s.target);
    const Recommendation r = recommend(S, worlds, read_world_rows(join_path(dir, "worlds.csv")), s.eval_episodes);
    for (const std::string &line : recommendation_lines(s.name, r, dir)) {
        std::printf("%s\n", line.c_str());
    }
}

/* `simevo run --tasks I/N [--stage S]`: the share's tasks only, no summary. */
void run_share(const ExperimentSpec &s, const RunOptions &opt, const Share &share,
               std::chrono::steady_clock::time_point t0)
{
    const std::vector<TaskDef> tasks = prepare_experiment(s, opt);
    const std::vector<char> selected = select_share(tasks, share);
    std::size_t n = 0;
    for (char c : selected) {
        n += c != 0;
    }
    run_experiment_tasks(s, tasks, opt, selected);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s: share %u/%u%s: %zu tasks done in %.1f s; when every share is done: simevo summarize %s\n",
                s.name.c_str(), share.index, share.count,
                share.stage ? (" of stage " + std::to_string(share.stage)).c_str() : "", n, secs,
                join_path(opt.out_dir, s.name).c_str());
}

/* `simevo slurm` for one experiment: the folder prepared as for a run and the scripts
 * written. Returns the submit.sh path. */
std::string write_slurm(const RunItem &it, RunOptions opt, SlurmOptions so, bool plots)
{
    so.simevo = absolute_path("/proc/self/exe");
    so.experiment_file = it.file;
    so.out_dir = absolute_dir(opt.out_dir);
    so.tools_dir = absolute_path(opt.tools_dir);
    so.plots = plots;
    opt.out_dir = so.out_dir;
    set_run_options(opt, it.args, it.file);
    const std::vector<TaskDef> tasks = prepare_experiment(it.spec, opt);
    const std::string exp_dir = join_path(so.out_dir, it.spec.name);
    const std::string script = write_slurm_scripts(tasks, exp_dir, it.args, so);
    std::printf("%s: %zu tasks (%zu in stage 1, %zu in stage 2 after their sources); submit with: sh %s\n",
                it.spec.name.c_str(), tasks.size(), stage_tasks(tasks, 1).size(), stage_tasks(tasks, 2).size(),
                script.c_str());
    return script;
}

/* `simevo slurm NAME|SWEEP`: every experiment's scripts (a sweep's members each, plus the
 * sweep's submit.sh that submits them all), and with --submit the last submitted. */
int write_slurm_all(const std::vector<RunItem> &items, const std::vector<Sweep> &sweeps, const RunOptions &opt,
                    const SlurmOptions &so, bool plots, bool submit)
{
    std::vector<std::string> scripts;
    for (const RunItem &it : items) {
        scripts.push_back(write_slurm(it, opt, so, plots));
    }
    std::string script = scripts.front();
    if (!sweeps.empty()) {
        const std::string dir = write_sweep_record(absolute_dir(opt.out_dir), sweeps.front());
        script = write_sweep_submit(dir, scripts);
        std::printf("%s: %zu experiments; submit them all with: sh %s\n", sweeps.front().name.c_str(), scripts.size(),
                    script.c_str());
    }
    if (!submit) {
        return 0;
    }
    std::fflush(stdout);
    const int rc = std::system(("/bin/sh " + sh_quote(script)).c_str());
    if (rc != 0) {
        throw UserError(script + ": sbatch failed (exit " + std::to_string(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1) + ")");
    }
    return 0;
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

/* ---- subcommands: each one's options (add_*_command) and its work (*_command) ---------- */

/* `simevo run`'s options. */
struct RunCommand {
    std::vector<std::string> names;
    RunOptions opt;
    RunArgs run_args;
    bool no_plot = false, no_progress = false;
    std::string share_text;
    int stage = 0;
};

CLI::App *add_run_command(CLI::App &app, RunCommand &c)
{
    auto *run = app.add_subcommand("run", "run named experiments (resumes an interrupted run in the same --out)");
    run->add_option("experiment", c.names, "experiment name(s), a .toml path, a sweep file, or 'all' (the paper's five; generalist by name)")->required();
    add_run_args(run, c.run_args);
    run->add_option("--out", c.opt.out_dir, "output folder; results go to OUT/<experiment>")->capture_default_str();
    run->add_option("-j,--jobs", c.opt.jobs, "worker threads (0 = all cores)")->capture_default_str();
    run->add_option("--tools-dir", c.opt.tools_dir, "folder with plot_learning.py and plot_policy.py")->capture_default_str();
    run->add_option("--tasks", c.share_text,
                    "run only the I-th of N shares of the tasks (I/N); no summary: 'simevo summarize' merges "
                    "(docs/cluster.md)");
    run->add_option("--stage", c.stage, "with --tasks: share out only stage 1 (no dependency) or stage 2 (transfers "
                                        "from an evolved source)")->check(CLI::Range(1, 2));
    run->add_flag("--no-plot", c.no_plot, "skip the PNG plots");
    run->add_flag("--no-progress", c.no_progress, "no progress line even on a terminal");
    return run;
}

/* One experiment of `simevo run` to its end, and what to take from it. */
void run_whole(const ExperimentSpec &s, const RunOptions &opt, std::chrono::steady_clock::time_point t0)
{
    const std::string dir = run_experiment(s, opt);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s: complete in %.1f s; summary %s/summary.md\n", s.name.c_str(), secs, dir.c_str());
    if (opt.plots) {
        std::printf("%s: plot %s/learning.png\n", s.name.c_str(), dir.c_str());
    }
    print_transfer_arrival(s, dir);
    print_recommendation(s, dir);
}

/* `simevo run NAME...`: every experiment named, whole or one share of its tasks. */
int run_command(RunCommand &c, const std::string &experiments_dir, bool &started)
{
    if (c.stage != 0 && c.share_text.empty()) {
        c.share_text = "1/1";
    }
    const Share share = c.share_text.empty() ? Share{} : parse_share(c.share_text, c.stage);
    std::vector<Sweep> sweeps;
    const auto items = load_run_specs(c.names, experiments_dir, c.run_args, sweeps);
    c.opt.plots = !c.no_plot;
    c.opt.progress = c.no_progress ? 0 : -1;
    started = true;
    for (const Sweep &sw : sweeps) {
        (void)write_sweep_record(c.opt.out_dir, sw);
    }
    for (const RunItem &it : items) {
        const ExperimentSpec &s = it.spec;
        set_run_options(c.opt, it.args, it.file);
        const auto t0 = std::chrono::steady_clock::now();
        if (c.share_text.empty()) {
            run_whole(s, c.opt, t0);
        } else {
            run_share(s, c.opt, share, t0);
        }
        std::fflush(stdout);
    }
    return 0;
}

/* `simevo summarize`'s options. */
struct SummarizeCommand {
    std::string summ_dir;
    RunOptions opt;
    bool no_plot = false;
};

CLI::App *add_summarize_command(CLI::App &app, SummarizeCommand &c)
{
    auto *summ = app.add_subcommand("summarize", "merge the finished tasks of an experiment folder into its summary");
    summ->add_option("folder", c.summ_dir, "experiment or sweep folder (OUT/<experiment>, OUT/<sweep>)")->required();
    summ->add_option("--tools-dir", c.opt.tools_dir, "folder with the plot scripts")->capture_default_str();
    summ->add_flag("--no-plot", c.no_plot, "skip the PNG plots");
    return summ;
}

int summarize_command(SummarizeCommand &c, bool &started)
{
    c.opt.plots = !c.no_plot;
    return summarize_folder(c.summ_dir, c.opt, started);
}

/* `simevo slurm`'s options. */
struct SlurmCommand {
    std::string slurm_name;
    RunArgs run_args;
    RunOptions opt;
    SlurmOptions so;
    bool no_plot = false, submit = false;
};

CLI::App *add_slurm_command(CLI::App &app, SlurmCommand &c)
{
    auto *slurm = app.add_subcommand("slurm", "write (and with --submit submit) Slurm job arrays for an experiment");
    slurm->add_option("experiment", c.slurm_name, "experiment name, .toml path or sweep file")->required();
    add_run_args(slurm, c.run_args);
    slurm->add_option("--out", c.opt.out_dir, "output folder (shared by every node); results go to OUT/<experiment>")->capture_default_str();
    slurm->add_option("--partition", c.so.partition, "Slurm partition (default: the cluster's)");
    slurm->add_option("--time", c.so.time, "time limit per array task, e.g. 2:00:00 (default: the partition's)");
    slurm->add_option("--array-limit", c.so.array_limit, "at most this many array tasks at once (0 = no limit)")->capture_default_str();
    slurm->add_option("--tasks-per-job", c.so.tasks_per_job, "simevo tasks per array task")->capture_default_str()->check(CLI::Range(1u, 1000000u));
    slurm->add_option("-j,--jobs", c.so.jobs, "threads per array task (--cpus-per-task)")->capture_default_str()->check(CLI::Range(1u, 1024u));
    slurm->add_option("--tools-dir", c.opt.tools_dir, "folder with the plot scripts, for the summarize job")->capture_default_str();
    slurm->add_flag("--no-plot", c.no_plot, "the summarize job skips the PNG plots");
    slurm->add_flag("--submit", c.submit, "submit the arrays with sbatch now");
    return slurm;
}

int slurm_command(const SlurmCommand &c, const std::string &experiments_dir, bool &started)
{
    std::vector<Sweep> sweeps;
    const auto items = load_run_specs({c.slurm_name}, experiments_dir, c.run_args, sweeps);
    check_slurm_options(c.so, c.opt.out_dir);
    started = true;
    return write_slurm_all(items, sweeps, c.opt, c.so, !c.no_plot, c.submit);
}

/* `simevo list`: every experiment file with its figure and title. */
int list_command(const std::string &experiments_dir)
{
    for (const auto &n : list_experiments(experiments_dir)) {
        const ExperimentSpec s = load_experiment(join_path(experiments_dir, n + ".toml"));
        std::printf("%-20s %-8s %s\n", n.c_str(), s.figure.c_str(), s.title.c_str());
    }
    return 0;
}

/* `simevo evolve`'s options: one evolution, optionally seeded from a policy file (transfer). */
struct EvolveCommand {
    std::string env = "dense", robot = "tekbot", from, out_dir = "runs/evolve";
    uint32_t sectors = 0;
    double noise = 0, sensor_noise = -1, actuation_noise = -1;
    uint64_t ev_episodes = 1000, ev_seed = 1;
    uint32_t ev_eval = 50;
    std::string fitness;
    std::string algorithm = algorithm_name(EvolutionParams::Algorithm::EpsilonGreedy);
    EvolutionParams ep;
};

CLI::App *add_evolve_command(CLI::App &app, EvolveCommand &c)
{
    auto *evolve = app.add_subcommand("evolve", "evolve one population in one situation (transfer with --from)");
    evolve->add_option("--env", c.env, "environment name or file")->capture_default_str();
    evolve->add_option("--robot", c.robot, "robot profile name or file")->capture_default_str();
    evolve->add_option("--sectors", c.sectors, "sonar sectors (0 = robot default)")->check(CLI::Range(0, 360));
    evolve->add_option("--noise", c.noise, "sensor and actuation noise level p (0.05 = 5%)")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--sensor-noise", c.sensor_noise, "sensor noise only")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--actuation-noise", c.actuation_noise, "actuation noise only")->check(qnav::cli::finite_range(0.0, 1.0));
    evolve->add_option("--from", c.from, "policy file to seed the population from (transfer)");
    evolve->add_option("--episodes", c.ev_episodes, "episodes")->capture_default_str()->check(CLI::Range(uint64_t(1), uint64_t(100000000)));
    evolve->add_option("--eval-episodes", c.ev_eval, "held-out evaluation episodes of the best")->capture_default_str()->check(CLI::Range(1u, 1000000u));
    evolve->add_option("--seed", c.ev_seed, "seed")->capture_default_str();
    evolve->add_option("--fitness", c.fitness, "fitness rule: progress (default) or paper");
    evolve->add_option("--population", c.ep.population, "population size")->capture_default_str();
    evolve->add_option("--epsilon", c.ep.epsilon, "probability of mutating a random member")->capture_default_str();
    evolve->add_option("--hidden", c.ep.hidden, "hidden units of random networks")->capture_default_str();
    evolve->add_option("--mutation-scale", c.ep.mutation_scale, "Cauchy scale, weight units")->capture_default_str();
    evolve->add_option("--mutation-clip", c.ep.mutation_clip, "Cauchy clip, weight units")->capture_default_str();
    evolve->add_option("--per-candidate,--episodes-per-candidate", c.ep.episodes_per_candidate, "episodes averaged per fitness value")->capture_default_str();
    evolve->add_flag("--reevaluate-parent", c.ep.reevaluate_parent, "also re-run the parent each step (noisy fitness)");
    evolve->add_option("--algorithm", c.algorithm, "search: epsilon-greedy (the paper's) or es (evolution strategy)")
        ->capture_default_str()
        ->check(CLI::IsMember({algorithm_name(EvolutionParams::Algorithm::EpsilonGreedy),
                               algorithm_name(EvolutionParams::Algorithm::Es)}));
    evolve->add_option("--es-pairs", c.ep.es_pairs, "es: antithetic pairs per iteration")->capture_default_str();
    evolve->add_option("--es-sigma", c.ep.es_sigma, "es: perturbation SD, weight units")->capture_default_str();
    evolve->add_option("--es-step", c.ep.es_step, "es: Adam step, weight units")->capture_default_str();
    evolve->add_option("--out", c.out_dir, "output folder")->capture_default_str();
    return evolve;
}

/* The one task `simevo evolve` runs: its seeds all follow from --seed. Throws UserError. */
TaskDef evolve_task(const EvolveCommand &c)
{
    TaskDef t;
    t.label = c.from.empty() ? "direct" : "transfer";
    t.dir = c.out_dir;
    t.scenario = scenario_from(c.env, c.robot, c.sectors, c.noise, c.sensor_noise, c.actuation_noise, c.fitness);
    t.context_seed = c.ev_seed;
    t.episodes = c.ev_episodes;
    t.evolution = c.ep;
    t.evolution.algorithm = c.algorithm == algorithm_name(EvolutionParams::Algorithm::Es)
                                ? EvolutionParams::Algorithm::Es
                                : EvolutionParams::Algorithm::EpsilonGreedy;
    t.evolution_seed = mix_seed(c.ev_seed, 1);
    t.episode_seed_base = mix_seed(c.ev_seed, 2);
    t.eval_episodes = c.ev_eval;
    t.eval_seed_base = mix_seed(c.ev_seed, 3);
    t.source_policy_file = c.from;
    return t;
}

int evolve_command(const EvolveCommand &c, bool &started)
{
    if (const char *p = evolution_params_problem(c.ep); *p) {
        std::string msg(p); // "field: problem", the field spelled as the option is
        std::replace(msg.begin(), msg.begin() + static_cast<std::ptrdiff_t>(msg.find(':')), '_', '-');
        throw UserError("--" + msg);
    }
    const TaskDef t = evolve_task(c);
    SimWorlds worlds;
    RunnerFactory make = [&worlds](const Scenario &sc, uint64_t s) -> std::unique_ptr<EpisodeRunner> {
        return std::make_unique<SimRunner>(worlds, sc, s, true);
    };
    if (!c.from.empty()) {
        (void)read_policy_file(c.from); // a bad --from is bad input, found now
    }
    {
        SimRunner probe(worlds, t.scenario, t.context_seed, true); // bad env/robot: now
    }
    started = true;
    run_tasks({t}, make, 1, ::isatty(2) != 0, "evolve");
    std::printf("best policy %s/best.policy; episodes %s/episodes.csv; held-out %s/eval.csv\n",
                c.out_dir.c_str(), c.out_dir.c_str(), c.out_dir.c_str());
    return 0;
}

/* `simevo eval`'s options: a policy over held-out episodes. */
struct EvalCommand {
    std::string policy_arg;
    std::string e_env = "dense", e_robot = "tekbot";
    uint32_t e_sectors = 0, e_episodes = 50;
    double e_noise = 0;
    uint64_t e_seed = 1;
    std::string fitness;
};

CLI::App *add_eval_command(CLI::App &app, EvalCommand &c)
{
    auto *eval = app.add_subcommand("eval", "evaluate a policy file ('prob' = the probabilistic policy) over episodes");
    eval->add_option("policy", c.policy_arg, "policy file, or 'prob'")->required();
    eval->add_option("--env", c.e_env, "environment")->capture_default_str();
    eval->add_option("--robot", c.e_robot, "robot profile")->capture_default_str();
    eval->add_option("--sectors", c.e_sectors, "sonar sectors (0 = robot default)")->check(CLI::Range(0, 360));
    eval->add_option("--noise", c.e_noise, "noise level p")->check(qnav::cli::finite_range(0.0, 1.0));
    eval->add_option("--episodes", c.e_episodes, "episodes")->capture_default_str()->check(CLI::Range(1u, 1000000u));
    eval->add_option("--seed", c.e_seed, "seed")->capture_default_str();
    eval->add_option("--fitness", c.fitness, "fitness rule: progress (default) or paper");
    return eval;
}

int eval_command(const EvalCommand &c, bool &started)
{
    SimWorlds worlds;
    SimRunner runner(worlds, scenario_from(c.e_env, c.e_robot, c.e_sectors, c.e_noise, -1, -1, c.fitness), c.e_seed, true);
    qnav_policy_t p;
    if (c.policy_arg == "prob") {
        p = runner.probabilistic_policy();
    } else {
        p = read_policy_file(c.policy_arg);
    }
    started = true;
    std::vector<double> R, tau;
    uint32_t reached = 0;
    for (uint32_t i = 0; i < c.e_episodes; ++i) {
        const EpisodeOutcome o = runner.run(p, mix_seed(c.e_seed, i));
        R.push_back(o.R);
        reached += o.reached;
        tau.push_back(o.tau_c);
    }
    double lo = 0, hi = 0;
    wilson_ci95(reached, c.e_episodes, &lo, &hi);
    std::printf("episodes %u  mean R %.3f ± %.3f (95%% CI)  sd %.3f  reached %.0f%% (95%% CI %.0f-%.0f%%)  "
                "mean tau_c %.1f ± %.1f ticks\n",
                c.e_episodes, mean_of(R), ci95_half_width(R), sd_of(R), 100.0 * reached / std::max(1u, c.e_episodes),
                100.0 * lo, 100.0 * hi, mean_of(tau), ci95_half_width(tau));
    return 0;
}

/* `simevo fit`'s options: a network fitted to a robot's probabilistic policy. */
struct FitCommand {
    std::string robot = "tekbot", out;
    uint32_t sectors = 0;
    FitSettings fit;
};

CLI::App *add_fit_command(CLI::App &app, FitCommand &c)
{
    auto *fit = app.add_subcommand("fit", "write the network fitted to a robot's probabilistic policy (a start for evolution)");
    fit->add_option("--robot", c.robot, "robot profile (name or file)")->capture_default_str();
    fit->add_option("--sectors", c.sectors, "sonar sectors (0 = the profile's)")->check(CLI::Range(0, 360));
    fit->add_option("--hidden", c.fit.hidden, "hidden units")->capture_default_str()->check(CLI::Range(1, QNAV_MAX_HIDDEN));
    fit->add_option("--starts", c.fit.starts, "random starts; the best fit is kept")->capture_default_str()->check(CLI::Range(1, 1000));
    fit->add_option("--iterations", c.fit.iterations, "Adam steps per start")->capture_default_str()->check(CLI::Range(1, 1000000));
    fit->add_option("--seed", c.fit.seed, "seed of the starts")->capture_default_str();
    fit->add_option("--out", c.out, "policy file to write (must not exist)")->required();
    return fit;
}

int fit_command(const FitCommand &c, bool &started)
{
    if (file_exists(c.out)) {
        throw UserError(c.out + ": exists; not overwritten");
    }
    SimWorlds worlds;
    const SimRunner runner(worlds, scenario_from("dense", c.robot, c.sectors, 0.0, -1, -1, ""), c.fit.seed, true);
    started = true;
    const FitResult r = fit_network(runner.ctrl_config(), runner.probabilistic_policy(), c.fit);
    write_fit(c.out, c.robot, r, "simevo fit");
    std::printf("%s: %d hidden units fitted to %s's probabilistic policy; quality error over %d levels x %d "
                "dtheta: rms %.4f, max %.4f\n",
                c.out.c_str(), c.fit.hidden, c.robot.c_str(), QNAV_DIST_LEVELS, QNAV_DTHETA_MAX + 1, r.rms, r.max);
    return 0;
}

/* `simevo quality`'s options: Figs. 2-3 for any policy files. */
struct QualityCommand {
    std::vector<std::string> q_policies;
    std::string q_out = "runs/quality";
    uint32_t q_range = 5000;
    std::string q_robot = "tekbot";
    RunOptions opt;
};

CLI::App *add_quality_command(CLI::App &app, QualityCommand &c)
{
    auto *quality = app.add_subcommand("quality", "plot path quality over (dtheta, distance) of policy files (paper Figs. 2-3)");
    quality->add_option("policy", c.q_policies, "policy files, or 'prob' (the robot's tuned probabilistic policy)")->required();
    quality->add_option("--robot", c.q_robot, "robot profile whose probabilistic policy 'prob' means")->capture_default_str();
    quality->add_option("--out", c.q_out, "folder for quality.csv and policy.png")->capture_default_str();
    quality->add_option("--range-mm", c.q_range, "sonar maximum range for the distance axis, mm")
        ->capture_default_str()->check(CLI::Range(1, 65535));
    quality->add_option("--tools-dir", c.opt.tools_dir, "folder with plot_policy.py")->capture_default_str();
    return quality;
}

/* A policy's name in quality.csv: the last two path components (run folders all hold
 * "best.policy"), made unique among those named so far with a number when needed. */
std::string quality_label(const std::string &arg, const std::vector<std::pair<std::string, qnav_policy_t>> &policies)
{
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
    return label;
}

int quality_command(const QualityCommand &c, bool &started)
{
    std::vector<std::pair<std::string, qnav_policy_t>> policies;
    for (const auto &arg : c.q_policies) {
        qnav_policy_t p;
        if (arg == "prob") {
            SimWorlds worlds;
            qnav_sim_robot_prob_policy(worlds.robot(c.q_robot), &p);
        } else {
            p = read_policy_file(arg);
        }
        policies.emplace_back(quality_label(arg, policies), p);
    }
    qnav_ctrl_config_t ccfg;
    qnav_ctrl_config_default(&ccfg);
    ccfg.max_range_mm = static_cast<qnav_mm_t>(c.q_range);
    started = true;
    make_dirs(c.q_out);
    write_file_atomic(join_path(c.q_out, "quality.csv"), quality_table_csv(policies, ccfg));
    run_plot(c.opt, "plot_policy.py", c.q_out);
    std::printf("plot %s/policy.png\n", c.q_out.c_str());
    return 0;
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

    // every subcommand that plots finds the scripts here unless told otherwise
    const std::string tools_dir = resource_dir("QNAV_TOOLS_DIR", "tools", std::string(QNAV_SOURCE_DIR) + "/tools");
    RunCommand run_c;
    SummarizeCommand summ_c;
    SlurmCommand slurm_c;
    QualityCommand quality_c;
    run_c.opt.tools_dir = summ_c.opt.tools_dir = slurm_c.opt.tools_dir = quality_c.opt.tools_dir = tools_dir;
    EvolveCommand evolve_c;
    EvalCommand eval_c;
    CLI::App *run = add_run_command(app, run_c);
    CLI::App *summ = add_summarize_command(app, summ_c);
    CLI::App *slurm = add_slurm_command(app, slurm_c);
    CLI::App *lst = app.add_subcommand("list", "list the experiment files");
    CLI::App *evolve = add_evolve_command(app, evolve_c);
    CLI::App *eval = add_eval_command(app, eval_c);
    CLI::App *quality = add_quality_command(app, quality_c);
    FitCommand fit_c;
    CLI::App *fit = add_fit_command(app, fit_c);

    if (const int status = qnav::cli::parse(app, argc, argv, "simevo"); status >= 0) {
        return status;
    }

    // Bad input found before any episode runs is exit 2; what goes wrong once work has
    // started (a write, a plot, a journal from other settings) is 1.
    bool started = false;
    try {
        if (*lst) {
            return list_command(experiments_dir);
        }
        if (*run) {
            return run_command(run_c, experiments_dir, started);
        }
        if (*summ) {
            return summarize_command(summ_c, started);
        }
        if (*slurm) {
            return slurm_command(slurm_c, experiments_dir, started);
        }
        if (*evolve) {
            return evolve_command(evolve_c, started);
        }
        if (*quality) {
            return quality_command(quality_c, started);
        }
        if (*eval) {
            return eval_command(eval_c, started);
        }
        if (*fit) {
            return fit_command(fit_c, started);
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
