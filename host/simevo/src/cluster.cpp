/*
 * Shares, run records, unfinished-task reports and Slurm scripts for running one
 * experiment on many processes (docs/cluster.md).
 */
#include "cluster.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <regex>
#include <sstream>

#include "files.h"
#include "qnav/sim.h"
#include "sweep.h"

namespace qnav {

namespace {

/* set(scenario) for the target and every source of s (settings that apply to all). */
template <typename F>
void for_each_scenario(ExperimentSpec &s, F set)
{
    set(s.target);
    for (SourceSpec &src : s.sources) {
        set(src.scenario);
    }
}

void set_fitness(ExperimentSpec &s, const std::string &name)
{
    qnav_sim_fitness_rule_t rule = QNAV_SIM_FITNESS_PROGRESS;
    if (qnav_sim_fitness_rule_parse(name.c_str(), &rule) != QNAV_SIM_OK) {
        throw UserError("--fitness: '" + name + "' is not one of " + qnav_sim_fitness_rule_names());
    }
    for_each_scenario(s, [rule](Scenario &sc) { sc.fitness = rule; });
}

void set_controller(ExperimentSpec &s, const std::string &name)
{
    ControllerReading c;
    if (!controller_reading_parse(name, &c)) {
        throw UserError("--controller: '" + name + "' is not one of " + controller_reading_names());
    }
    for_each_scenario(s, [c](Scenario &sc) { sc.controller = c; });
}

/* Writes path unless it holds content already; a different file there is not ours to
 * overwrite unless it carries our header line. */
void write_script(const std::string &path, const std::string &content)
{
    std::string existing;
    if (read_file(path, existing) && existing != content &&
        existing.find("# written by simevo slurm") == std::string::npos) {
        throw UserError(path + ": exists and was not written by simevo slurm; move it away");
    }
    write_file_atomic(path, content);
}

/* v for a one-line message: control characters as \n, \t or \xNN. */
std::string shown(const std::string &v)
{
    std::string o;
    for (const char ch : v) {
        const auto c = static_cast<unsigned char>(ch);
        if (c == '\n') o += "\\n";
        else if (c == '\t') o += "\\t";
        else if (c < 0x20 || c == 0x7f) {
            char b[8];
            std::snprintf(b, sizeof b, "\\x%02x", c);
            o += b;
        } else o += static_cast<char>(c);
    }
    return o;
}

/* The folder in an #SBATCH --output pattern: in double quotes (sbatch splits the line at
 * blanks and ends it at an unquoted '#'), '%' doubled (Slurm's pattern escape). */
std::string sbatch_output(const std::string &dir, const std::string &file_pattern)
{
    std::string o = "\"";
    for (char c : dir) {
        o += c == '%' ? std::string("%%") : std::string(1, c);
    }
    return o + "/" + file_pattern + "\"";
}

} // namespace

void check_slurm_options(const SlurmOptions &o, const std::string &out_dir)
{
    // Slurm partition names (comma-separated for several) and time limits (minutes,
    // M:S, H:M:S, D-H, D-H:M, D-H:M:S, or unlimited): anything else would be sbatch's
    // error at best and, with a newline, a shell command in tasks.sbatch at worst.
    static const std::regex partition("[A-Za-z0-9_.-]+(,[A-Za-z0-9_.-]+)*");
    static const std::regex time("([0-9]+(:[0-9]+){0,2}|[0-9]+-[0-9]+(:[0-9]+){0,2}|UNLIMITED|unlimited|INFINITE|infinite)");
    if (!o.partition.empty() && !std::regex_match(o.partition, partition)) {
        throw UserError("--partition: '" + shown(o.partition) +
                        "' is not a Slurm partition name (letters, digits, '_', '.', '-'; several separated by ',')");
    }
    if (!o.time.empty() && !std::regex_match(o.time, time)) {
        throw UserError("--time: '" + shown(o.time) +
                        "' is not a Slurm time limit (MINUTES, M:S, H:M:S, D-H, D-H:M, D-H:M:S or unlimited)");
    }
    for (const char ch : out_dir) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x20 || c == 0x7f || c == '"' || c == '\\') {
            throw UserError("--out: '" + shown(out_dir) +
                            "' holds a control character, '\"' or '\\' and cannot go on an #SBATCH line");
        }
    }
}

std::string sh_quote(const std::string &s)
{
    std::string q = "'";
    for (char c : s) {
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    }
    return q + "'";
}

ExperimentSpec load_run_spec(const std::string &path, const RunArgs &a)
{
    ExperimentSpec s = load_experiment(path);
    apply_preset(s, a.preset);
    if (a.runs > 0) s.runs = static_cast<uint32_t>(a.runs);
    if (a.episodes > 0) s.target_episodes = static_cast<uint64_t>(a.episodes);
    if (a.source_episodes > 0) for (auto &src : s.sources) src.episodes = static_cast<uint64_t>(a.source_episodes);
    if (a.eval_episodes > 0) s.eval_episodes = static_cast<uint32_t>(a.eval_episodes);
    if (a.seed >= 0) s.seed = static_cast<uint64_t>(a.seed);
    if (a.per_candidate > 0) s.evolution.episodes_per_candidate = static_cast<uint32_t>(a.per_candidate);
    if (!a.fitness.empty()) set_fitness(s, a.fitness);
    if (!a.controller.empty()) set_controller(s, a.controller);
    if (!a.vary.empty()) apply_vary(s, a.vary);
    return s;
}

std::string override_flags(const RunArgs &a)
{
    std::string o;
    auto add = [&o](const char *flag, int64_t v, bool given) {
        if (given) {
            o += std::string(" ") + flag + " " + std::to_string(v);
        }
    };
    add("--runs", a.runs, a.runs > 0);
    add("--episodes", a.episodes, a.episodes > 0);
    add("--source-episodes", a.source_episodes, a.source_episodes > 0);
    add("--eval-episodes", a.eval_episodes, a.eval_episodes > 0);
    add("--seed", a.seed, a.seed >= 0);
    add("--per-candidate", a.per_candidate, a.per_candidate > 0);
    o += a.fitness.empty() ? "" : " --fitness " + a.fitness;
    o += a.controller.empty() ? "" : " --controller " + a.controller;
    o += a.vary.empty() ? "" : " --vary " + a.vary;
    return o;
}

std::string run_record_text(const std::string &experiment_file, const RunArgs &a)
{
    std::ostringstream o;
    o << "# simevo run record: what `simevo summarize` rebuilds this experiment from\n"
      << "file = " << experiment_file << "\npreset = " << a.preset << "\nruns = " << a.runs
      << "\nepisodes = " << a.episodes << "\nsource_episodes = " << a.source_episodes
      << "\neval_episodes = " << a.eval_episodes << "\nseed = " << a.seed << "\nper_candidate = " << a.per_candidate
      << "\nfitness = " << a.fitness << "\ncontroller = " << a.controller << "\n";
    if (!a.vary.empty()) {
        o << "vary = " << a.vary << "\n";
    }
    return o.str();
}

RunArgs parse_run_record(const std::string &text, const std::string &path, std::string *experiment_file)
{
    std::map<std::string, std::string> kv;
    std::istringstream in(text);
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
        if (line.empty() || line[0] == '#') {
            continue;
        }
        const std::size_t at = line.find(" = "); // an empty value is "key = "
        if (at == std::string::npos) {
            throw UserError(path + ":" + std::to_string(n) + ": expected 'key = value'");
        }
        kv[line.substr(0, at)] = line.substr(at + 3);
    }
    auto get = [&](const char *k) {
        auto it = kv.find(k);
        if (it == kv.end()) {
            throw UserError(path + ": no '" + k + "' line");
        }
        return it->second;
    };
    auto num = [&](const char *k) {
        const std::string v = get(k);
        char *end = nullptr;
        errno = 0;
        const long long x = std::strtoll(v.c_str(), &end, 10);
        if (v.empty() || *end || errno) {
            throw UserError(path + ": " + k + " = '" + v + "' is not an integer");
        }
        return static_cast<int64_t>(x);
    };
    RunArgs a;
    *experiment_file = get("file");
    a.preset = get("preset");
    a.runs = num("runs");
    a.episodes = num("episodes");
    a.source_episodes = num("source_episodes");
    a.eval_episodes = num("eval_episodes");
    a.seed = num("seed");
    a.per_candidate = num("per_candidate");
    a.fitness = get("fitness");
    a.controller = get("controller");
    a.vary = kv.count("vary") ? kv["vary"] : "";
    return a;
}

Share parse_share(const std::string &text, int stage)
{
    Share s;
    s.stage = stage;
    unsigned long i = 0, n = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lu/%lu%c", &i, &n, &tail) != 2 || i < 1 || n < 1 || i > n || n > 1000000) {
        throw UserError("--tasks: '" + text + "' is not I/N with 1 <= I <= N (the I-th of N shares)");
    }
    s.index = static_cast<uint32_t>(i);
    s.count = static_cast<uint32_t>(n);
    return s;
}

int task_stage(const TaskDef &t) { return t.source_task >= 0 ? 2 : 1; }

std::vector<std::size_t> stage_tasks(const std::vector<TaskDef> &tasks, int stage)
{
    std::vector<std::size_t> order;
    for (int st = 1; st <= 2; ++st) {
        for (std::size_t i = 0; i < tasks.size(); ++i) {
            if (task_stage(tasks[i]) == st && (stage == 0 || stage == st)) {
                order.push_back(i);
            }
        }
    }
    return order;
}

std::vector<char> select_share(const std::vector<TaskDef> &tasks, const Share &share)
{
    const std::vector<std::size_t> order = stage_tasks(tasks, share.stage);
    std::vector<char> selected(tasks.size(), 0);
    const std::size_t m = order.size();
    const std::size_t from = m * (share.index - 1) / share.count, to = m * share.index / share.count;
    for (std::size_t j = from; j < to; ++j) {
        selected[order[j]] = 1;
    }
    return selected;
}

std::vector<std::string> unfinished_tasks(const std::vector<TaskDef> &tasks, const std::string &exp_dir)
{
    std::vector<std::string> lines;
    for (const TaskDef &t : tasks) {
        if (file_exists(join_path(t.dir, "done"))) {
            continue;
        }
        const std::string name = t.dir.substr(exp_dir.size() + 1);
        std::string journal;
        if (!read_file(join_path(t.dir, "task.txt"), journal)) {
            lines.push_back(name + ": not started");
            continue;
        }
        std::size_t n = 0;
        if (read_file(join_path(t.dir, "episodes.csv"), journal)) {
            for (char c : journal) {
                n += c == '\n';
            }
        }
        lines.push_back(name + ": started, not finished (failed, killed or still running; " + std::to_string(n) +
                        " journal lines)");
    }
    return lines;
}

std::string write_sweep_submit(const std::string &sweep_dir, const std::vector<std::string> &member_scripts)
{
    const std::string dir = join_path(sweep_dir, "slurm");
    make_dirs(dir);
    std::string s = "#!/bin/sh\n# written by simevo slurm (docs/cluster.md); regenerate rather than edit\n"
                    "# submits every member of the sweep (each: stage 1, stage 2, summarize)\nset -e\n";
    for (const std::string &m : member_scripts) {
        s += "sh " + sh_quote(m) + "\n";
    }
    const std::string path = join_path(dir, "submit.sh");
    write_script(path, s);
    return path;
}

std::string write_slurm_scripts(const std::vector<TaskDef> &tasks, const std::string &exp_dir, const RunArgs &a,
                                const SlurmOptions &o)
{
    check_slurm_options(o, exp_dir);
    const std::string dir = join_path(exp_dir, "slurm");
    make_dirs(dir);
    std::string head = "#!/bin/sh\n# written by simevo slurm (docs/cluster.md); regenerate rather than edit\n";
    std::string sb;
    if (!o.partition.empty()) sb += "#SBATCH --partition=" + o.partition + "\n";
    if (!o.time.empty()) sb += "#SBATCH --time=" + o.time + "\n";
    const std::string run_cmd = sh_quote(o.simevo) + " run " + sh_quote(o.experiment_file) + " --out " +
                                sh_quote(o.out_dir) + " --preset " + sh_quote(a.preset) + override_flags(a) +
                                (a.network_mode ? " --network-mode" : "") + " --no-plot --no-progress -j " +
                                std::to_string(o.jobs);
    const std::string tasks_sh = head + "# usage (by submit.sh): sbatch --array=1-N tasks.sbatch STAGE N\n" + sb +
                                 "#SBATCH --cpus-per-task=" + std::to_string(o.jobs) + "\n#SBATCH --output=" +
                                 sbatch_output(dir, "%x-%A_%a.out") + "\n#SBATCH --job-name=simevo-tasks\nexec " + run_cmd +
                                 " --stage \"$1\" --tasks \"$SLURM_ARRAY_TASK_ID/$2\"\n";
    const std::string sum_sh = head + sb + "#SBATCH --output=" + sbatch_output(dir, "%x-%j.out") + "\n#SBATCH --job-name=simevo-summarize\nexec " +
                               sh_quote(o.simevo) + " summarize " + sh_quote(exp_dir) + " --tools-dir " +
                               sh_quote(o.tools_dir) + (o.plots ? "" : " --no-plot") + "\n";
    const std::size_t per = o.tasks_per_job;
    const std::size_t n1 = (stage_tasks(tasks, 1).size() + per - 1) / per;
    const std::size_t n2 = (stage_tasks(tasks, 2).size() + per - 1) / per;
    const std::string limit = o.array_limit ? "%" + std::to_string(o.array_limit) : "";
    std::string submit = head + "# submits stage 1, stage 2 after it (afterok) and the summarize job\nset -e\ncd " +
                         sh_quote(dir) + "\n";
    submit += "a=$(sbatch --parsable --array=1-" + std::to_string(n1) + limit + " tasks.sbatch 1 " + std::to_string(n1) +
              ")\na=${a%%;*}\nafter=$a\n";
    if (n2 > 0) {
        submit += "b=$(sbatch --parsable --array=1-" + std::to_string(n2) + limit +
                  " --dependency=afterok:$a --kill-on-invalid-dep=yes tasks.sbatch 2 " + std::to_string(n2) +
                  ")\nb=${b%%;*}\nafter=$a:$b\n";
    }
    submit += "c=$(sbatch --parsable --dependency=afterany:$after summarize.sbatch)\nc=${c%%;*}\n"
              "echo \"submitted: tasks $after, summarize $c\"\necho \"$after $c\" > jobs.txt\n";
    write_script(join_path(dir, "tasks.sbatch"), tasks_sh);
    write_script(join_path(dir, "summarize.sbatch"), sum_sh);
    const std::string submit_path = join_path(dir, "submit.sh");
    write_script(submit_path, submit);
    return submit_path;
}

} // namespace qnav
