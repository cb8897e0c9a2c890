/*
 * Experiment orchestration: prepare the folder (settings.txt, run.txt, every input
 * checked), run the selected tasks on the pool, then the summary and every output. The
 * parts live beside it: experiment_plan.cpp (conditions, tasks), experiment_pool.cpp
 * (threads, task locks) with experiment_progress.cpp, experiment_summary.cpp (statistics),
 * experiment_outputs.cpp and experiment_report.cpp (files written at the end).
 */
#include "experiment.h"

#include <optional>
#include <set>

#include <unistd.h>

#include "experiment_outputs.h"
#include "experiment_report.h"
#include "files.h"
#include "fit.h"
#include "sim_runner.h"

namespace qnav {

namespace {

/* FILE holds CONTENT, or it is written now; a folder made with other settings is refused
 * before anything in it is touched. */
void write_or_compare(const std::string &path, const std::string &content, const std::string &what)
{
    std::string existing;
    if (read_file(path, existing)) {
        if (existing != content) {
            throw UserError(path + ": this output folder holds " + what + "; use another --out");
        }
    } else {
        write_file_atomic(path, content);
    }
}

std::string settings_text(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, const std::string &exp_dir)
{
    std::string settings = "# simevo experiment " + spec.name + ": the settings of every task\n";
    for (const TaskDef &t : tasks) {
        // a transfer's source policy does not exist yet: name the task that will make it;
        // a fitted source lies in the folder: named within it, so the folder can move
        const std::string in_folder = exp_dir + "/";
        const std::string source =
            t.source_task >= 0 ? "best policy of " + tasks[static_cast<std::size_t>(t.source_task)].dir.substr(exp_dir.size() + 1)
            : t.source_policy_file.compare(0, in_folder.size(), in_folder) == 0 ? t.source_policy_file.substr(in_folder.size())
                                                                                 : t.source_policy_file;
        settings += "\n[" + t.dir.substr(exp_dir.size() + 1) + "]\n" + task_settings_text(t, source);
    }
    return settings;
}

/* Every robot, environment and source policy file of the plan, so a bad one fails before
 * any work. */
void probe_inputs(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, SimWorlds &worlds, bool use_table)
{
    std::set<std::string> probed;
    for (const TaskDef &t : tasks) {
        if (probed.insert(t.scenario.describe()).second) {
            probe_scenario(worlds, t.scenario, t.context_seed, use_table);
        }
    }
    for (const SourceSpec &s : spec.sources) {
        if (!s.policy_file.empty()) {
            try {
                load_source_policy(s.policy_file);
            } catch (const UserError &e) {
                throw UserError(std::string(e.what()) + " (source '" + s.label + "' of " + spec.file + ")");
            }
        }
    }
}

/* Each `fit` source's network, fitted to the target robot's probabilistic policy with the
 * experiment's hidden units (one fit for all of them), written once into the experiment's
 * folder. A file already there was fitted with these settings (settings.txt, compared
 * before, holds the robot and the hidden units), so a rerun or another share does not fit
 * again. */
void write_fitted_sources(const ExperimentSpec &spec, const std::string &exp_dir, SimWorlds &worlds, bool use_table)
{
    std::optional<FitResult> fit;
    for (const SourceSpec &s : spec.sources) {
        const std::string path = fitted_source_path(exp_dir, s);
        if (s.fit.empty() || file_exists(path)) {
            continue;
        }
        if (!fit) {
            const SimRunner target(worlds, picture_scenario(spec.target), spec.seed, use_table);
            FitSettings fs;
            fs.hidden = static_cast<int>(spec.evolution.hidden);
            fit = fit_network(target.ctrl_config(), target.probabilistic_policy(), fs);
        }
        write_fit(path, spec.target.robot, *fit, "simevo");
    }
}

} // namespace

std::vector<TaskDef> prepare_experiment(const ExperimentSpec &spec, const RunOptions &opt)
{
    const std::string exp_dir = join_path(opt.out_dir, spec.name);
    make_dirs(exp_dir);
    const std::vector<TaskDef> tasks = plan_tasks(spec, exp_dir);
    write_or_compare(join_path(exp_dir, "settings.txt"), settings_text(spec, tasks, exp_dir),
                     spec.name + " with other settings (preset, runs, episodes or seeds)");
    if (!opt.run_record.empty()) {
        write_or_compare(join_path(exp_dir, "run.txt"), opt.run_record,
                         spec.name + " run with other options (experiment file, preset or overrides)");
    }
    if (!file_exists(join_path(exp_dir, "summary.md"))) {
        write_file_atomic(join_path(exp_dir, "STATUS"),
                          "incomplete: running or interrupted; rerun the same command to resume\n");
    }
    SimWorlds worlds;
    probe_inputs(spec, tasks, worlds, opt.use_table);
    write_fitted_sources(spec, exp_dir, worlds, opt.use_table);
    return tasks;
}

void finish_experiment(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, const RunOptions &opt)
{
    const std::string exp_dir = join_path(opt.out_dir, spec.name);
    SimWorlds worlds;
    SimRunner target_runner(worlds, picture_scenario(spec.target), spec.seed, opt.use_table);
    const ExperimentSummary S = summarize(spec, tasks);
    const HeldOut H = evaluate_held_out(spec, S, exp_dir, worlds, opt);
    write_outputs(spec, S, tasks, exp_dir, worlds, target_runner, opt, H);
    write_file_atomic(join_path(exp_dir, "summary.md"), summary_md(spec, S, opt, opt.plots, H));
    write_file_atomic(join_path(exp_dir, "STATUS"), "complete\n");
}

void run_experiment_tasks(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks, const RunOptions &opt,
                          const std::vector<char> &selected)
{
    SimWorlds worlds;
    const bool use_table = opt.use_table;
    RunnerFactory make = [&worlds, use_table](const Scenario &sc, uint64_t seed) -> std::unique_ptr<EpisodeRunner> {
        return std::make_unique<SimRunner>(worlds, sc, seed, use_table);
    };
    const bool progress = opt.progress < 0 ? ::isatty(2) != 0 : opt.progress != 0;
    run_tasks(tasks, make, opt.jobs, progress, spec.name, selected);
}

std::string run_experiment(const ExperimentSpec &spec, const RunOptions &opt)
{
    const std::vector<TaskDef> tasks = prepare_experiment(spec, opt);
    run_experiment_tasks(spec, tasks, opt, {});
    finish_experiment(spec, tasks, opt);
    return join_path(opt.out_dir, spec.name);
}

} // namespace qnav
