/*
 * Experiment orchestration: task plan, thread pool, progress display, summary, plots.
 */
#include "experiment.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <set>
#include <chrono>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <fcntl.h>
#include <csignal>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "files.h"
#include "heldout.h"
#include "qnav/terminal.hpp"
#include "qnav/ctrl.h"
#include "qnav/policy_io.h"
#include "rng.h"
#include "sim_runner.h"
#include "stats.h"
#include "worlds.h"

namespace qnav {

namespace {

uint64_t label_hash(const std::string &s) { return fnv1a64(s.data(), s.size()); }


/* ---- progress -------------------------------------------------------------------- */

/* "m:ss", or "h:mm:ss" from an hour on. */
std::string eta_text(long s)
{
    char b[48];
    if (s >= 3600) {
        std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
    } else {
        std::snprintf(b, sizeof b, "%ld:%02ld", s / 60, s % 60);
    }
    return b;
}

/* label with its leading words cut to their first letter ("transfer-open" -> "t-open");
 * words that start with a digit are kept ("8-sectors"). */
std::string abbreviate_label(const std::string &label)
{
    std::string out;
    std::size_t start = 0;
    for (;;) {
        const std::size_t dash = label.find('-', start);
        const std::string word = label.substr(start, dash == std::string::npos ? std::string::npos : dash - start);
        if (dash == std::string::npos) {
            return out + word;
        }
        const bool letters = !word.empty() && std::isalpha(static_cast<unsigned char>(word[0])) != 0;
        out += (letters ? word.substr(0, 1) : word) + "-";
        start = dash + 1;
    }
}

std::size_t columns_of(const std::string &s)
{
    std::size_t n = 0;
    for (char c : s) {
        n += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
    }
    return n;
}

/* The progress line in at most columns - 1 characters. The best R of every condition is
 * what a reader watches, so when the whole line is too wide the other fields give way
 * first, least telling first: the experiment's name, the episode counts, the rate, the
 * percentage's decimal; then the labels are abbreviated ("t-open" for "transfer-open", when
 * still unique), "best R:" becomes "R:", R gets one decimal and the fields one space
 * between them. Only a line still too wide after all that is cut (docs/cli.md, "Progress"). */
std::string progress_line(const std::string &title, uint64_t done, uint64_t total, double rate, long eta_s,
                          const std::map<std::string, double> &best, int columns)
{
    const double pct = total ? 100.0 * static_cast<double>(done) / static_cast<double>(total) : 100.0;
    char b[160];
    std::set<std::string> short_labels;
    for (auto &kv : best) {
        short_labels.insert(abbreviate_label(kv.first));
    }
    const bool can_abbreviate = short_labels.size() == best.size();
    struct Shape {
        bool title, counts, rate, pct_decimal, abbreviated, short_head, r_decimal2, wide_gaps;
    };
    const Shape shapes[] = {
        {true, true, true, true, false, false, true, true},
        {false, true, true, true, false, false, true, true},
        {false, false, true, true, false, false, true, true},
        {false, false, false, true, false, false, true, true},
        {false, false, false, false, false, false, true, true},
        {false, false, false, false, can_abbreviate, false, true, true},
        {false, false, false, false, can_abbreviate, true, true, true},
        {false, false, false, false, can_abbreviate, true, false, false},
    };
    const std::size_t room = columns > 1 ? static_cast<std::size_t>(columns - 1) : 1;
    std::string line;
    for (const Shape &sh : shapes) {
        const char *gap = sh.wide_gaps ? "  " : " ";
        line.clear();
        if (sh.title) {
            line += "[" + title + "] ";
        }
        if (sh.counts) {
            std::snprintf(b, sizeof b, "%" PRIu64 "/%" PRIu64 " episodes%s", done, total, gap);
            line += b;
        }
        // whole percent rounded down: "100%" only when every episode is done
        std::snprintf(b, sizeof b, sh.pct_decimal ? "%.1f%%%s" : "%.0f%%%s", sh.pct_decimal ? pct : std::floor(pct), gap);
        line += b;
        if (sh.rate) {
            std::snprintf(b, sizeof b, "%.0f ep/s%s", rate, gap);
            line += b;
        }
        // once every episode is done there is no time left to tell
        line += total != 0 && done >= total ? "done" : "ETA " + eta_text(eta_s);
        if (!best.empty()) {
            line += gap;
            line += sh.short_head ? "R:" : "best R:";
        }
        for (auto &kv : best) {
            std::snprintf(b, sizeof b, sh.r_decimal2 ? " %.2f" : " %.1f", kv.second);
            line += " " + (sh.abbreviated ? abbreviate_label(kv.first) : kv.first) + b;
        }
        if (columns_of(line) <= room) {
            return line;
        }
    }
    return qnav::cli::fit_line(line, columns);
}


class Progress {
public:
    Progress(uint64_t total, bool enabled, std::string title)
        : total_(total), enabled_(enabled), title_(std::move(title)),
          t0_(std::chrono::steady_clock::now())
    {
        if (enabled_) {
            printer_ = std::thread([this] { loop(); });
        }
    }
    ~Progress() { finish(); }

    void finish()
    {
        {
            std::lock_guard<std::mutex> l(mu_);
            if (finished_) {
                return;
            }
            finished_ = true;
        }
        cv_.notify_all();
        if (printer_.joinable()) {
            printer_.join();
            print_line();
            std::fputc('\n', stderr);
        }
    }

    void add(uint64_t n, bool replayed)
    {
        done_ += n;
        if (replayed) {
            replayed_ += n;
        }
    }
    void best(const std::string &label, double r)
    {
        std::lock_guard<std::mutex> l(mu_);
        // A label names a condition, not a run: keep the best over all its runs.
        auto it = best_.find(label);
        if (it == best_.end() || r > it->second) {
            best_[label] = r;
        }
    }

private:
    void loop()
    {
        std::unique_lock<std::mutex> l(mu_);
        while (!finished_) {
            cv_.wait_for(l, std::chrono::milliseconds(500));
            if (finished_) {
                break;
            }
            l.unlock();
            print_line();
            l.lock();
        }
    }
    void print_line()
    {
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
        const uint64_t done = done_.load();
        const uint64_t fresh = done - replayed_.load();
        const double rate = secs > 0 ? static_cast<double>(fresh) / secs : 0.0;
        const double left = rate > 0 ? static_cast<double>(total_ - std::min(done, total_)) / rate : 0.0;
        std::map<std::string, double> bests;
        {
            std::lock_guard<std::mutex> l(mu_);
            bests = best_;
        }
        // fitted to the terminal (asked each time: it may be resized): a wrapped line would
        // scroll instead of being redrawn in place
        const std::string line = progress_line(title_, done, total_, rate, static_cast<long>(left), bests,
                                               qnav::cli::terminal_columns(2));
        std::fprintf(stderr, "\r\033[K%s", line.c_str());
        std::fflush(stderr);
    }

    std::atomic<uint64_t> done_{0}, replayed_{0};
    uint64_t total_;
    bool enabled_;
    std::string title_;
    std::chrono::steady_clock::time_point t0_;
    std::mutex mu_;
    std::condition_variable cv_;
    bool finished_ = false;
    std::map<std::string, double> best_;
    std::thread printer_;
};

std::string fmt(double v, int prec = 2)
{
    if (!std::isfinite(v)) {
        return "n/a";
    }
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", prec, v);
    return b;
}

std::string fmt_p(const TestResult &t)
{
    if (!t.valid) {
        return "n/a";
    }
    char b[64];
    if (t.p < 1e-4) {
        std::snprintf(b, sizeof b, "%.1e", t.p);
    } else {
        std::snprintf(b, sizeof b, "%.4f", t.p);
    }
    return b;
}

std::string json_num(double v)
{
    if (!std::isfinite(v)) {
        return "null";
    }
    char b[64];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

std::string json_str(const std::string &s)
{
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') {
            o += '\\';
            o += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", c);
            o += b;
        } else {
            o += c;
        }
    }
    return o + "\"";
}

} // namespace

std::string run_dir(const std::string &exp_dir, uint32_t run)
{
    char buf[32];
    std::snprintf(buf, sizeof buf, "run-%03u", run + 1);
    return join_path(exp_dir, buf);
}

/* ---- plan ------------------------------------------------------------------------ */

std::vector<uint64_t> checkpoint_grid(const ExperimentSpec &spec)
{
    std::set<uint64_t> g;
    for (uint64_t c : spec.checkpoints) {
        if (c <= spec.target_episodes) {
            g.insert(c);
        }
    }
    for (uint64_t c = spec.checkpoint_every; spec.checkpoint_every > 0 && c <= spec.target_episodes;
         c += spec.checkpoint_every) {
        g.insert(c);
    }
    return std::vector<uint64_t>(g.begin(), g.end());
}

std::vector<TaskDef> plan_tasks(const ExperimentSpec &spec, const std::string &exp_dir)
{
    std::vector<TaskDef> tasks;
    const uint64_t eval_base = mix_seed(spec.eval_seed, label_hash("held-out evaluation"));
    const std::vector<uint64_t> grid = checkpoint_grid(spec);
    // A target task's held-out evaluations: at the end, and at the checkpoints.
    auto held_out = [&](TaskDef &t) {
        t.eval_episodes = spec.eval_episodes;
        t.eval_seed_base = eval_base;
        t.checkpoints = grid;
        t.checkpoint_episodes = grid.empty() ? 0 : spec.checkpoint_episodes;
    };
    for (uint32_t r = 0; r < spec.runs; ++r) {
        const uint64_t run_seed = mix_seed(spec.seed, r + 1);
        const std::string rdir = run_dir(exp_dir, r);
        // An evolution task of this run; its evolution seed follows from its label.
        auto evolve = [&](const std::string &label, const Scenario &scenario, uint64_t episodes,
                          uint64_t episode_seed_base) {
            TaskDef t;
            t.label = label;
            t.dir = join_path(rdir, label);
            t.run = r;
            t.scenario = scenario;
            t.context_seed = spec.seed;
            t.episodes = episodes;
            t.evolution = spec.evolution;
            t.evolution_seed = mix_seed(run_seed, label_hash("evolution:" + label));
            t.episode_seed_base = episode_seed_base;
            return t;
        };
        // Transfer and direct runs of one run face the same episode sequence (common
        // random numbers): the comparison is paired by construction.
        const uint64_t target_episodes_base = mix_seed(run_seed, label_hash("episodes:target"));
        for (const SourceSpec &s : spec.sources) {
            int src_index = -1;
            if (s.policy_file.empty()) {
                const std::string label = "source-" + s.label;
                tasks.push_back(evolve(label, s.scenario, s.episodes,
                                       mix_seed(run_seed, label_hash("episodes:" + label))));
                src_index = static_cast<int>(tasks.size() - 1);
            }
            TaskDef tr = evolve(condition_label(ConditionKind::Transfer, s.label), spec.target, spec.target_episodes, target_episodes_base);
            tr.source_task = src_index;
            tr.source_policy_file = s.policy_file;
            held_out(tr);
            tasks.push_back(tr);
        }
        TaskDef d = evolve(condition_label(ConditionKind::Direct), spec.target, spec.target_episodes, target_episodes_base);
        held_out(d);
        tasks.push_back(d);
    }
    TaskDef p;
    p.kind = TaskKind::EvalProbabilistic;
    p.label = condition_label(ConditionKind::Probabilistic);
    p.dir = join_path(exp_dir, p.label);
    p.scenario = spec.target;
    p.context_seed = spec.seed;
    p.eval_episodes = spec.eval_episodes;
    p.eval_seed_base = eval_base;
    tasks.push_back(p);
    return tasks;
}

/* ---- conditions ------------------------------------------------------------------ */

const ConditionDecl kConditions[4] = {
    {ConditionKind::Transfer, "transfer-", true, nullptr},
    {ConditionKind::Direct, "direct", true, nullptr},
    {ConditionKind::Probabilistic, kReferences[0].label, false, &kReferences[0]},
    {ConditionKind::Vfh, kReferences[1].label, false, &kReferences[1]},
};

const ConditionDecl &condition_decl(ConditionKind kind)
{
    switch (kind) {
    case ConditionKind::Transfer:
        return kConditions[0];
    case ConditionKind::Direct:
        return kConditions[1];
    case ConditionKind::Probabilistic:
        return kConditions[2];
    case ConditionKind::Vfh:
        return kConditions[3];
    }
    return kConditions[1];
}

std::string condition_label(ConditionKind kind, const std::string &source)
{
    const ConditionDecl &d = condition_decl(kind);
    switch (kind) {
    case ConditionKind::Transfer:
        return std::string(d.label) + source;
    case ConditionKind::Direct:
    case ConditionKind::Probabilistic:
    case ConditionKind::Vfh:
        break;
    }
    return d.label;
}

/* ---- pool ------------------------------------------------------------------------ */

namespace {

/* Holds flock on DIR/.lock for one task: any number of simevo processes may work on one
 * experiment, but never two on the same task (their journals would interleave). */
class TaskLock {
public:
    explicit TaskLock(const std::string &dir)
    {
        make_dirs(dir);
        const std::string path = join_path(dir, ".lock");
        fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd_ < 0 || ::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
            if (fd_ >= 0) {
                ::close(fd_);
            }
            throw UserError(dir + ": another simevo is running this task (or its .lock cannot be locked)");
        }
    }
    ~TaskLock() { ::close(fd_); }
    TaskLock(const TaskLock &) = delete;
    TaskLock &operator=(const TaskLock &) = delete;

private:
    int fd_ = -1;
};

/* A selected transfer whose source task is neither selected nor done cannot start. */
void check_sources_finished(const std::vector<TaskDef> &tasks, const std::vector<char> &selected)
{
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        const int src = tasks[i].source_task;
        if (!selected[i] || src < 0 || selected[static_cast<std::size_t>(src)]) {
            continue;
        }
        const TaskDef &s = tasks[static_cast<std::size_t>(src)];
        if (!file_exists(join_path(s.dir, "done"))) {
            throw UserError(tasks[i].dir + ": its source task " + s.dir +
                            " is not finished (run the share that holds it first, e.g. --stage 1)");
        }
    }
}

} // namespace

void run_tasks(const std::vector<TaskDef> &tasks, const RunnerFactory &make, unsigned jobs,
               bool progress, const std::string &title, std::vector<char> selected)
{
    if (selected.empty()) {
        selected.assign(tasks.size(), 1);
    }
    check_sources_finished(tasks, selected);
    uint64_t total = 0;
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        total += selected[i] ? task_total_episodes(tasks[i]) : 0;
    }
    Progress prog(total, progress, title);
    TaskObserver obs;
    obs.episodes_done = [&prog](uint64_t n, bool replayed) { prog.add(n, replayed); };
    obs.best = [&prog](const std::string &label, double r) { prog.best(label, r); };

    enum State { Pending, Running, Done, Failed };
    std::vector<State> state(tasks.size(), Pending);
    for (std::size_t i = 0; i < tasks.size(); ++i) {
        state[i] = selected[i] ? Pending : Done; // another share's (checked above)
    }
    std::mutex mu;
    std::condition_variable cv;
    std::atomic<bool> stop{false};
    std::string first_error;

    auto worker = [&]() {
        std::unique_lock<std::mutex> l(mu);
        for (;;) {
            if (stop.load()) {
                return;
            }
            std::size_t pick = tasks.size();
            bool any_pending = false;
            for (std::size_t i = 0; i < tasks.size(); ++i) {
                if (state[i] != Pending) {
                    continue;
                }
                any_pending = true;
                const int src = tasks[i].source_task;
                if (src < 0 || state[static_cast<std::size_t>(src)] == Done) {
                    pick = i;
                    break;
                }
            }
            if (!any_pending) {
                return;
            }
            if (pick == tasks.size()) {
                cv.wait(l);
                continue;
            }
            state[pick] = Running;
            l.unlock();
            const TaskDef &t = tasks[pick];
            std::string source_path;
            if (t.source_task >= 0) {
                source_path = join_path(tasks[static_cast<std::size_t>(t.source_task)].dir, "best.policy");
            } else if (!t.source_policy_file.empty()) {
                source_path = t.source_policy_file;
            }
            bool ok = false;
            std::string error;
            try {
                const TaskLock lock(t.dir);
                ok = run_task(t, source_path, make, obs, stop);
            } catch (const std::exception &e) {
                error = e.what();
            }
            l.lock();
            state[pick] = ok ? Done : Failed;
            if (!ok) {
                if (first_error.empty() && !error.empty()) {
                    first_error = error;
                }
                stop = true;
            }
            cv.notify_all();
        }
    };
    if (jobs == 0) {
        jobs = std::max(1u, std::thread::hardware_concurrency());
    }
    std::vector<std::thread> pool;
    for (unsigned i = 0; i < jobs; ++i) {
        pool.emplace_back(worker);
    }
    for (auto &th : pool) {
        th.join();
    }
    prog.finish();
    if (!first_error.empty()) {
        throw UserError(first_error);
    }
    if (stop.load()) {
        throw UserError(title + ": stopped before completion");
    }
}

/* ---- summary --------------------------------------------------------------------- */

Interval t_interval(const std::vector<double> &x, double lo_bound, double hi_bound)
{
    Interval v;
    v.mean = mean_of(x);
    const double h = ci95_half_width(x);
    v.lo = std::max(lo_bound, v.mean - h);
    v.hi = std::min(hi_bound, v.mean + h);
    return v;
}

Interval wilson_interval(double successes, double n)
{
    Interval v;
    v.mean = n > 0 ? successes / n : 0.0;
    wilson_ci95(successes, n, &v.lo, &v.hi);
    return v;
}

namespace {

/* One target run's held-out figures: R, arrival fraction, recovery ticks per episode. */
void add_eval(ConditionSummary &c, const std::vector<EpisodeOutcome> &ev, uint64_t &reached, uint64_t &evals)
{
    std::vector<double> r;
    double arrived = 0, tau = 0;
    for (const auto &o : ev) {
        r.push_back(o.R);
        arrived += o.reached ? 1 : 0;
        tau += o.tau_c;
    }
    reached += static_cast<uint64_t>(arrived);
    evals += ev.size();
    c.final_per_run.push_back(mean_of(r));
    const double n = ev.empty() ? 1.0 : static_cast<double>(ev.size());
    c.arrival_per_run.push_back(arrived / n);
    c.tau_c_per_run.push_back(tau / n);
}

/* A run's checkpoints into c (one entry per checkpoint, runs appended), and the episodes
 * until its arrival first reached the threshold. */
void add_checkpoints(ConditionSummary &c, const std::string &path, const std::vector<uint64_t> &grid,
                     double threshold)
{
    const std::vector<CheckpointRow> rows = read_checkpoints(path);
    if (rows.size() != grid.size()) {
        throw UserError(path + ": has " + std::to_string(rows.size()) + " checkpoints, expected " +
                        std::to_string(grid.size()));
    }
    if (c.checkpoints.empty()) {
        for (uint64_t g : grid) {
            CheckpointSummary cs;
            cs.checkpoint = g;
            c.checkpoints.push_back(cs);
        }
    }
    double first = std::nan("");
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const double arrival = static_cast<double>(rows[i].arrived) / rows[i].n;
        c.checkpoints[i].R.push_back(rows[i].R);
        c.checkpoints[i].arrival.push_back(arrival);
        c.checkpoints[i].tau_c.push_back(static_cast<double>(rows[i].tau_c) / rows[i].n);
        if (std::isnan(first) && arrival >= threshold) {
            first = static_cast<double>(rows[i].checkpoint);
        }
    }
    c.to_threshold.push_back(first);
    c.threshold_not_reached += std::isnan(first) ? 1u : 0u;
}

/* One run's learning curves, binned: candidates' R, the population best, arrivals. */
void add_curves(const JournalColumns &J, uint64_t steps_per_bin, uint32_t k, std::vector<std::vector<double>> &bins,
                std::vector<std::vector<double>> &best_bins, std::vector<std::vector<double>> &arrival_bins)
{
    for (std::size_t b = 0; b < bins.size(); ++b) {
        const std::size_t lo = b * steps_per_bin;
        const std::size_t hi = std::min<std::size_t>(lo + steps_per_bin, J.R.size());
        std::vector<double> part(J.R.begin() + static_cast<long>(lo), J.R.begin() + static_cast<long>(hi));
        double arrived = 0;
        for (std::size_t i = lo; i < hi; ++i) {
            arrived += J.arrived[i];
        }
        bins[b].push_back(mean_of(part));
        best_bins[b].push_back(J.best_fitness[hi - 1]);
        arrival_bins[b].push_back(arrived / (static_cast<double>(hi - lo) * k));
    }
}

void finish_curves(ConditionSummary &c, const ExperimentSummary &S, const std::vector<std::vector<double>> &bins,
                   const std::vector<std::vector<double>> &best_bins,
                   const std::vector<std::vector<double>> &arrival_bins)
{
    for (std::size_t b = 0; b < bins.size(); ++b) {
        c.curve_mean.push_back(mean_of(bins[b]));
        c.curve_ci.push_back(ci95_half_width(bins[b]));
        c.best_mean.push_back(mean_of(best_bins[b]));
        c.best_ci.push_back(ci95_half_width(best_bins[b]));
        c.arrival_curve_mean.push_back(mean_of(arrival_bins[b]));
        c.arrival_curve_ci.push_back(ci95_half_width(arrival_bins[b]));
    }
    if (c.curve_mean.empty()) {
        return;
    }
    c.start = c.curve_mean.front();
    c.end = c.curve_mean.back();
    c.best_end = c.best_mean.back();
    if (c.end > c.start) {
        const double goal = c.start + 0.9 * (c.end - c.start);
        for (std::size_t b = 0; b < c.curve_mean.size(); ++b) {
            if (c.curve_mean[b] >= goal) {
                c.episodes_to_90 = static_cast<double>(S.bin_end[b]);
                break;
            }
        }
    }
}

ConditionSummary summarize_condition(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks,
                                     const std::string &label, ConditionKind kind, const ExperimentSummary &S,
                                     uint64_t steps, uint64_t steps_per_bin)
{
    ConditionSummary c;
    c.label = label;
    c.kind = kind;
    const std::size_t nbins = S.bin_end.size();
    std::vector<std::vector<double>> bins(nbins), best_bins(nbins), arrival_bins(nbins);
    double best_final = -std::numeric_limits<double>::infinity();
    uint64_t reached = 0, evals = 0;
    for (const TaskDef &t : tasks) {
        if (t.label != label) {
            continue;
        }
        add_eval(c, read_eval(join_path(t.dir, "eval.csv")), reached, evals);
        if (c.final_per_run.back() > best_final) {
            best_final = c.final_per_run.back();
            c.best_run = static_cast<int>(t.run);
        }
        if (!t.checkpoints.empty()) {
            add_checkpoints(c, join_path(t.dir, "checkpoints.csv"), t.checkpoints, spec.arrival_threshold);
        }
        const std::string journal = join_path(t.dir, "episodes.csv");
        const JournalColumns J = read_journal(journal);
        if (J.R.size() != steps) {
            throw UserError(journal + ": has " + std::to_string(J.R.size()) + " steps, expected " +
                            std::to_string(steps));
        }
        c.online_per_run.push_back(mean_of(J.R));
        add_curves(J, steps_per_bin, S.k, bins, best_bins, arrival_bins);
    }
    c.final_mean = mean_of(c.final_per_run);
    c.final_sd = sd_of(c.final_per_run);
    c.final_ci = ci95_half_width(c.final_per_run);
    c.reached_rate = evals ? static_cast<double>(reached) / static_cast<double>(evals) : 0.0;
    c.arrival = t_interval(c.arrival_per_run, 0.0, 1.0);
    c.tau_c = t_interval(c.tau_c_per_run, 0.0, std::numeric_limits<double>::infinity());
    c.online_mean = mean_of(c.online_per_run);
    for (CheckpointSummary &cs : c.checkpoints) {
        cs.listed = std::find(spec.checkpoints.begin(), spec.checkpoints.end(), cs.checkpoint) != spec.checkpoints.end();
        cs.R_ci = t_interval(cs.R, -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity());
        cs.arrival_ci = t_interval(cs.arrival, 0.0, 1.0);
        cs.tau_c_ci = t_interval(cs.tau_c, 0.0, std::numeric_limits<double>::infinity());
    }
    finish_curves(c, S, bins, best_bins, arrival_bins);
    return c;
}

/* A reference (its row's STEM.csv in the reference task's folder): one policy or
 * controller, so its CIs are over episodes. */
ConditionSummary summarize_reference(const std::vector<TaskDef> &tasks, ConditionKind kind)
{
    ConditionSummary prob;
    prob.kind = kind;
    prob.label = condition_label(prob.kind);
    for (const TaskDef &t : tasks) {
        if (t.kind != TaskKind::EvalProbabilistic) {
            continue;
        }
        double reached = 0;
        const auto ev = read_eval(join_path(t.dir, std::string(condition_decl(kind).reference->eval_stem) + ".csv"));
        for (const auto &o : ev) {
            prob.final_per_run.push_back(o.R);
            prob.arrival_per_run.push_back(o.reached ? 1.0 : 0.0);
            prob.tau_c_per_run.push_back(o.tau_c);
            reached += o.reached ? 1 : 0;
        }
        prob.reached_rate = ev.empty() ? 0.0 : reached / static_cast<double>(ev.size());
        prob.arrival = wilson_interval(reached, static_cast<double>(ev.size()));
    }
    prob.tau_c = t_interval(prob.tau_c_per_run, 0.0, std::numeric_limits<double>::infinity());
    prob.final_mean = mean_of(prob.final_per_run);
    prob.final_sd = sd_of(prob.final_per_run);
    prob.final_ci = ci95_half_width(prob.final_per_run);
    prob.start = prob.end = prob.final_mean;
    return prob;
}

/* Transfer vs direct at every checkpoint and in episodes to the threshold. */
void compare_checkpoints(ConditionSummary &c, const ConditionSummary &direct, uint64_t budget)
{
    for (std::size_t i = 0; i < c.checkpoints.size() && i < direct.checkpoints.size(); ++i) {
        c.checkpoints[i].R_vs_direct = welch_t_test(c.checkpoints[i].R, direct.checkpoints[i].R);
        c.checkpoints[i].arrival_vs_direct = mann_whitney(c.checkpoints[i].arrival, direct.checkpoints[i].arrival);
    }
    auto ranked = [budget](const std::vector<double> &v) {
        std::vector<double> r;
        for (double x : v) {
            r.push_back(std::isnan(x) ? static_cast<double>(budget + 1) : x);
        }
        return r;
    };
    c.threshold_vs_direct = mann_whitney(ranked(c.to_threshold), ranked(direct.to_threshold));
}

} // namespace

ExperimentSummary summarize(const ExperimentSpec &spec, const std::vector<TaskDef> &tasks)
{
    ExperimentSummary S;
    S.curve_bin = spec.curve_bin;
    S.episodes = spec.target_episodes;
    S.k = spec.evolution.episodes_per_candidate;
    S.arrival_threshold = spec.arrival_threshold;
    S.checkpoint_episodes = spec.checkpoint_episodes;
    std::vector<std::pair<ConditionKind, std::string>> labels;
    for (const SourceSpec &s : spec.sources) {
        labels.emplace_back(ConditionKind::Transfer, condition_label(ConditionKind::Transfer, s.label));
    }
    labels.emplace_back(ConditionKind::Direct, condition_label(ConditionKind::Direct));
    TaskDef probe;
    probe.episodes = spec.target_episodes;
    probe.evolution = spec.evolution;
    const uint64_t steps = task_steps(probe);
    // Bins hold whole steps: curve_bin episodes rounded to a multiple of k.
    const uint64_t steps_per_bin = std::max<uint64_t>(1, (spec.curve_bin + S.k / 2) / S.k);
    for (uint64_t lo = 0; lo < steps; lo += steps_per_bin) {
        S.bin_end.push_back(std::min(lo + steps_per_bin, steps) * S.k);
    }
    for (const auto &kl : labels) {
        S.conditions.push_back(summarize_condition(spec, tasks, kl.second, kl.first, S, steps, steps_per_bin));
    }
    const std::size_t first_reference = S.conditions.size();
    for (const ConditionDecl &d : kConditions) {
        if (d.reference != nullptr) {
            S.conditions.push_back(summarize_reference(tasks, d.kind));
        }
    }

    const ConditionSummary &direct = S.conditions[labels.size() - 1];
    auto pct = [](double a, double b) { return std::fabs(b) >= 1.0 ? (a - b) / std::fabs(b) * 100.0 : std::nan(""); };
    for (std::size_t i = 0; i + 1 < labels.size(); ++i) {
        ConditionSummary &c = S.conditions[i];
        compare_checkpoints(c, direct, spec.target_episodes);
        Comparison cmp;
        cmp.a = c.label;
        cmp.b = direct.label;
        cmp.b_kind = direct.kind;
        cmp.difference = c.final_mean - direct.final_mean;
        cmp.improvement_pct = pct(c.final_mean, direct.final_mean);
        cmp.speedup_pct = (c.episodes_to_90 > 0 && direct.episodes_to_90 > 0)
                              ? (direct.episodes_to_90 - c.episodes_to_90) / direct.episodes_to_90 * 100.0
                              : std::nan("");
        cmp.test = "welch";
        cmp.t = welch_t_test(c.final_per_run, direct.final_per_run);
        cmp.mann_whitney = mann_whitney(c.final_per_run, direct.final_per_run);
        cmp.online_difference = c.online_mean - direct.online_mean;
        cmp.online = welch_t_test(c.online_per_run, direct.online_per_run);
        S.comparisons.push_back(cmp);
    }
    for (std::size_t r = first_reference; r < S.conditions.size(); ++r) {
        const ConditionSummary &prob = S.conditions[r];
        for (std::size_t i = 0; i < labels.size(); ++i) {
            const ConditionSummary &c = S.conditions[i];
            Comparison cmp;
            cmp.a = c.label;
            cmp.b = prob.label;
            cmp.b_kind = prob.kind;
            cmp.difference = c.final_mean - prob.final_mean;
            cmp.improvement_pct = pct(c.final_mean, prob.final_mean);
            cmp.speedup_pct = std::nan("");
            cmp.test = "one-sample";
            cmp.t = one_sample_t_test(c.final_per_run, prob.final_mean);
            S.comparisons.push_back(cmp);
        }
    }
    return S;
}

/* ---- outputs --------------------------------------------------------------------- */

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

namespace {

/* The held-out worlds of a finished experiment: every best policy and reference driven in
 * them (worlds.csv), their figures, and for a distribution target the recommended policy
 * (written to recommended.policy). */
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
        if (H.recommended.valid) {
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


std::string curves_csv(const ExperimentSummary &S)
{
    std::ostringstream o;
    o << "condition,episode,mean,ci_low,ci_high,best_mean,best_ci_low,best_ci_high,arrival_mean,arrival_ci_low,"
         "arrival_ci_high\n";
    for (const ConditionSummary &c : S.conditions) {
        for (std::size_t b = 0; b < c.curve_mean.size(); ++b) {
            const double a = c.arrival_curve_mean[b], ah = c.arrival_curve_ci[b];
            o << c.label << "," << S.bin_end[b] << "," << json_num(c.curve_mean[b]) << ","
              << json_num(c.curve_mean[b] - c.curve_ci[b]) << "," << json_num(c.curve_mean[b] + c.curve_ci[b]) << ","
              << json_num(c.best_mean[b]) << "," << json_num(c.best_mean[b] - c.best_ci[b]) << ","
              << json_num(c.best_mean[b] + c.best_ci[b]) << "," << json_num(a) << ","
              << json_num(std::max(0.0, a - ah)) << "," << json_num(std::min(1.0, a + ah)) << "\n";
        }
    }
    return o.str();
}

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

std::string json_interval(const Interval &v)
{
    return "{\"mean\": " + json_num(v.mean) + ", \"ci95_low\": " + json_num(v.lo) + ", \"ci95_high\": " +
           json_num(v.hi) + "}";
}

std::string json_p(const TestResult &t) { return json_num(t.valid ? t.p : std::nan("")); }

/* A condition's checkpoints and episodes-to-threshold as JSON members (", ..."). */
std::string json_checkpoints(const ConditionSummary &c)
{
    if (c.checkpoints.empty()) {
        return "";
    }
    std::ostringstream o;
    o << ", \"checkpoints\": [";
    for (std::size_t i = 0; i < c.checkpoints.size(); ++i) {
        const CheckpointSummary &k = c.checkpoints[i];
        o << (i ? ", " : "") << "{\"episodes\": " << k.checkpoint
          << ", \"listed\": " << (k.listed ? "true" : "false") << ", \"R\": " << json_interval(k.R_ci)
          << ", \"arrival\": " << json_interval(k.arrival_ci) << ", \"tau_c\": " << json_interval(k.tau_c_ci)
          << ", \"R_p_vs_direct\": " << json_p(k.R_vs_direct)
          << ", \"arrival_p_vs_direct\": " << json_p(k.arrival_vs_direct) << "}";
    }
    o << "], \"episodes_to_threshold\": [";
    for (std::size_t i = 0; i < c.to_threshold.size(); ++i) {
        o << (i ? ", " : "") << json_num(c.to_threshold[i]);
    }
    o << "], \"threshold_not_reached\": " << c.threshold_not_reached
      << ", \"threshold_p_vs_direct\": " << json_p(c.threshold_vs_direct);
    return o.str();
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

/* The held-out worlds and the recommended policy as JSON members (",\n  ..."). */
std::string worlds_json(const HeldOut &H)
{
    std::ostringstream o;
    o << ",\n  \"held_out_worlds\": {\"episodes\": " << H.episodes << ", \"seed\": " << kHeldOutWorldsSeed
      << ", \"worlds\": [";
    for (std::size_t i = 0; i < H.worlds.size(); ++i) {
        o << (i ? ", " : "") << "{\"label\": " << json_str(H.worlds[i].label)
          << ", \"family\": " << (H.worlds[i].family ? "true" : "false") << "}";
    }
    o << "],\n    \"conditions\": [";
    for (std::size_t i = 0; i < H.conditions.size(); ++i) {
        const ConditionWorlds &c = H.conditions[i];
        o << (i ? "," : "") << "\n      {\"label\": " << json_str(c.label) << ", \"worlds\": [";
        for (std::size_t j = 0; j < c.cells.size(); ++j) {
            const WorldCell &w = c.cells[j];
            o << (j ? ", " : "") << "{\"world\": " << json_str(w.world) << ", \"runs\": " << w.runs
              << ", \"episodes\": " << w.episodes << ", \"arrival\": " << json_interval(w.arrival)
              << ", \"tau_c\": " << json_interval(w.tau_c) << ", \"R\": " << json_interval(w.R) << "}";
        }
        o << "]}";
    }
    o << "\n    ]}";
    if (H.recommended.valid) {
        const Recommendation &r = H.recommended;
        o << ",\n  \"recommended\": {\"condition\": " << json_str(r.condition) << ", \"run\": " << r.run
          << ", \"validation_arrival\": " << json_num(r.validation_arrival)
          << ", \"validation_R\": " << json_num(r.validation_R)
          << ", \"validation_episodes\": " << r.validation_episodes << ", \"test\": [";
        for (std::size_t j = 0; j < r.test.size(); ++j) {
            const WorldCell &w = r.test[j];
            o << (j ? ", " : "") << "{\"world\": " << json_str(w.world) << ", \"episodes\": " << w.episodes
              << ", \"arrival\": " << json_interval(w.arrival) << ", \"tau_c\": " << json_interval(w.tau_c)
              << ", \"R\": " << json_interval(w.R) << "}";
        }
        o << "]}";
    }
    return o.str();
}

std::string summary_json(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt,
                         const std::string &env_file, double robot_radius_m, const HeldOut &H)
{
    std::ostringstream o;
    o << "{\n  \"name\": " << json_str(spec.name) << ",\n  \"title\": " << json_str(spec.title)
      << ",\n  \"figure\": " << json_str(spec.figure) << ",\n  \"preset\": " << json_str(opt.preset)
      << ",\n  \"runs\": " << spec.runs << ",\n  \"episodes\": " << spec.target_episodes
      << ",\n  \"eval_episodes\": " << spec.eval_episodes << ",\n  \"curve_bin\": " << spec.curve_bin
      << ",\n  \"episodes_per_candidate\": " << S.k << ",\n  \"fitness\": "
      << json_str(qnav_sim_fitness_rule_name(spec.target.fitness))
      << ",\n  \"controller\": " << json_str(controller_reading_name(spec.target.controller))
      << ",\n  \"arrival_threshold\": " << json_num(S.arrival_threshold)
      << ",\n  \"checkpoint_episodes\": " << S.checkpoint_episodes
      << ",\n  \"environment_file\": " << json_str(env_file) << ",\n  \"robot_radius_m\": " << json_num(robot_radius_m)
      << ",\n  \"target\": " << json_str(spec.target.describe()) << ",\n  \"sources\": [";
    for (std::size_t i = 0; i < spec.sources.size(); ++i) {
        const SourceSpec &s = spec.sources[i];
        o << (i ? ", " : "") << "{\"label\": " << json_str(s.label) << ", \"scenario\": "
          << json_str(s.policy_file.empty() ? s.scenario.describe() : "policy file " + s.policy_file)
          << ", \"episodes\": " << (s.policy_file.empty() ? s.episodes : 0) << "}";
    }
    o << "],\n  \"conditions\": [\n";
    for (std::size_t i = 0; i < S.conditions.size(); ++i) {
        const ConditionSummary &c = S.conditions[i];
        o << "    {\"label\": " << json_str(c.label) << ", \"final_mean\": " << json_num(c.final_mean)
          << ", \"final_ci95\": " << json_num(c.final_ci) << ", \"final_sd\": " << json_num(c.final_sd)
          << ", \"n\": " << c.final_per_run.size() << ", \"start\": " << json_num(c.start)
          << ", \"end\": " << json_num(c.end) << ", \"best_end\": " << json_num(c.best_end) << ", \"episodes_to_90\": "
          << (c.episodes_to_90 > 0 ? json_num(c.episodes_to_90) : "null")
          << ", \"reached_rate\": " << json_num(c.reached_rate) << ", \"arrival\": " << json_interval(c.arrival)
          << ", \"tau_c\": " << json_interval(c.tau_c) << json_checkpoints(c)
          << ", \"online_mean\": " << json_num(!condition_decl(c.kind).evolved ? std::nan("") : c.online_mean) << ", \"best_run\": " << (c.best_run + 1) << "}"
          << (i + 1 < S.conditions.size() ? "," : "") << "\n";
    }
    o << "  ],\n  \"comparisons\": [\n";
    for (std::size_t i = 0; i < S.comparisons.size(); ++i) {
        const Comparison &c = S.comparisons[i];
        o << "    {\"a\": " << json_str(c.a) << ", \"b\": " << json_str(c.b)
          << ", \"difference\": " << json_num(c.difference)
          << ", \"improvement_pct\": " << json_num(c.improvement_pct)
          << ", \"speedup_pct\": " << json_num(c.speedup_pct) << ", \"test\": " << json_str(c.test)
          << ", \"t\": " << json_num(c.t.valid ? c.t.statistic : std::nan(""))
          << ", \"df\": " << json_num(c.t.valid ? c.t.df : std::nan(""))
          << ", \"p\": " << json_num(c.t.valid ? c.t.p : std::nan(""))
          << ", \"mann_whitney_p\": " << json_num(c.mann_whitney.valid ? c.mann_whitney.p : std::nan(""))
          << ", \"online_difference\": " << json_num(c.b_kind == ConditionKind::Direct ? c.online_difference : std::nan(""))
          << ", \"online_p\": " << json_num(c.online.valid ? c.online.p : std::nan("")) << "}"
          << (i + 1 < S.comparisons.size() ? "," : "") << "\n";
    }
    o << "  ],\n  \"references\": [";
    for (std::size_t i = 0; i < kReferenceCount; ++i) {
        const ReferenceDecl &r = kReferences[i];
        o << (i ? ", " : "") << "{\"label\": " << json_str(r.label) << ", \"plot_name\": " << json_str(r.plot_name)
          << ", \"plot_style\": " << json_str(r.plot_style) << ", \"plot_color\": " << json_str(r.plot_color) << "}";
    }
    o << "]" << worlds_json(H) << "\n}\n";
    return o.str();
}

std::string pct_interval(const Interval &v)
{
    return fmt(100.0 * v.mean, 0) + "% (" + fmt(100.0 * v.lo, 0) + "–" + fmt(100.0 * v.hi, 0) + ")";
}

std::string num_interval(const Interval &v, int prec = 2)
{
    return fmt(v.mean, prec) + " (" + fmt(v.lo, prec) + "–" + fmt(v.hi, prec) + ")";
}

/* The equal-budget table and the episodes-to-threshold table (transfer and direct). */
std::string checkpoint_tables_md(const ExperimentSummary &S)
{
    std::ostringstream o;
    bool any = false;
    for (const ConditionSummary &c : S.conditions) {
        any = any || !c.checkpoints.empty();
    }
    if (!any) {
        return "";
    }
    o << "## Held out at equal target budgets\n\n"
      << "Best member of each run after the given target episodes, on the first " << S.checkpoint_episodes
      << " held-out episodes (mean over runs, 95% CI); p: transfer vs direct over the runs. summary.json also "
         "holds the checkpoint_every grid used for the threshold below.\n\n"
      << "| condition | target episodes | R | arrival | recovery ticks per episode | p R (Welch) | p arrival (Mann-Whitney) |\n"
      << "|---|---|---|---|---|---|---|\n";
    for (const ConditionSummary &c : S.conditions) {
        for (const CheckpointSummary &k : c.checkpoints) {
            if (!k.listed) {
                continue;
            }
            const bool direct = c.kind == ConditionKind::Direct;
            o << "| " << c.label << " | " << k.checkpoint << " | " << num_interval(k.R_ci) << " | "
              << pct_interval(k.arrival_ci) << " | " << num_interval(k.tau_c_ci, 1) << " | "
              << (direct ? "-" : fmt_p(k.R_vs_direct)) << " | " << (direct ? "-" : fmt_p(k.arrival_vs_direct))
              << " |\n";
        }
    }
    o << "\n| condition | target episodes until held-out arrival ≥ " << fmt(100.0 * S.arrival_threshold, 0)
      << "% (median of the runs that reached it) | runs that reached it | not reached | p vs direct (Mann-Whitney) |\n"
      << "|---|---|---|---|---|\n";
    for (const ConditionSummary &c : S.conditions) {
        if (c.checkpoints.empty()) {
            continue;
        }
        std::vector<double> reached;
        for (double x : c.to_threshold) {
            if (!std::isnan(x)) {
                reached.push_back(x);
            }
        }
        std::sort(reached.begin(), reached.end());
        const double median = reached.empty() ? std::nan("")
                              : reached.size() % 2 ? reached[reached.size() / 2]
                                                   : 0.5 * (reached[reached.size() / 2 - 1] + reached[reached.size() / 2]);
        o << "| " << c.label << " | " << fmt(median, 0) << " | " << reached.size() << " | " << c.threshold_not_reached
          << " | " << (c.kind == ConditionKind::Direct ? "-" : fmt_p(c.threshold_vs_direct)) << " |\n";
    }
    o << "\nCheckpoints are checked at the end of the first step that reaches them (k = " << S.k
      << " episodes per step); a run that does not reach the threshold within the budget is ranked after every run "
         "that does.\n\n";
    return o.str();
}

/* The held-out worlds: per world and condition arrival, recovery ticks, R (95% CIs), the
 * arrival matrix, and the recommended policy. */
std::string worlds_md(const ExperimentSpec &spec, const HeldOut &H)
{
    std::ostringstream o;
    o << "## Held-out worlds\n\n"
      << "Each evolved condition's best policy of every run and the references, " << H.episodes
      << " episodes in the test worlds of every world family (new seeds from " << kTestSeedBase
      << ", difficulty drawn in [0, 1], never trained on) and in every named environment of data/envs/ "
         "(new start points), with the target's robot, sectors and noise; the same episodes in every experiment. "
         "Evolved: 95% CI over runs; references: over episodes (arrival: Wilson).\n\n"
      << "| condition | world | arrival (95% CI) | recovery ticks per episode (95% CI) | R (95% CI) |\n"
      << "|---|---|---|---|---|\n";
    for (const ConditionWorlds &c : H.conditions) {
        for (const WorldCell &w : c.cells) {
            o << "| " << c.label << " | " << (w.family ? "family " : "") << w.world << " | "
              << pct_interval(w.arrival) << " | " << num_interval(w.tau_c, 2) << " | " << num_interval(w.R) << " |\n";
        }
    }
    for (const std::string &why : H.skipped) {
        o << "\nNot evaluated: " << why << "\n";
    }
    o << "\nArrival held out, mean (cross-environment matrix):\n\n| condition |";
    for (const HeldOutWorld &w : H.worlds) {
        o << " " << w.label << " |";
    }
    o << "\n|---|";
    for (std::size_t i = 0; i < H.worlds.size(); ++i) {
        o << "---|";
    }
    o << "\n";
    for (const ConditionWorlds &c : H.conditions) {
        o << "| " << c.label << " |";
        for (const WorldCell &w : c.cells) {
            o << " " << fmt(100.0 * w.arrival.mean, 0) << "% |";
        }
        o << "\n";
    }
    o << "\n";
    if (H.recommended.valid) {
        const Recommendation &r = H.recommended;
        o << "## Recommended policy\n\n`recommended.policy` = " << r.condition << " run " << r.run
          << ": of every run's best policy of every evolved condition, the highest arrival in the "
          << r.validation_episodes << " validation episodes (worlds seeded from " << kValidationSeedBase
          << ", disjoint from training and test; never training scores): " << fmt(100.0 * r.validation_arrival, 0)
          << "%, R " << fmt(r.validation_R) << ". Its test figures (95% CI over its episodes):\n\n"
          << "| world | arrival (95% CI) | recovery ticks per episode (95% CI) | R (95% CI) |\n|---|---|---|---|\n";
        for (const WorldCell &w : r.test) {
            o << "| " << (w.family ? "family " : "") << w.world << " | " << pct_interval(w.arrival) << " | "
              << num_interval(w.tau_c, 2) << " | " << num_interval(w.R) << " |\n";
        }
        o << "\n";
    }
    (void)spec;
    return o.str();
}

std::string summary_md(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt, bool plots,
                       const HeldOut &H)
{
    std::ostringstream o;
    o << "# " << spec.name << (spec.figure.empty() ? "" : " (paper " + spec.figure + ")") << "\n\n"
      << spec.title << "\n\n"
      << "Preset `" << opt.preset << "`: " << spec.runs << " runs, " << spec.target_episodes
      << " target episodes per run (" << S.k << " per candidate), fitness rule `"
      << qnav_sim_fitness_rule_name(spec.target.fitness) << "`, controller `"
      << controller_reading_name(spec.target.controller) << "`, population " << spec.evolution.population << ", epsilon "
      << fmt(spec.evolution.epsilon, 2) << ", " << spec.evolution.hidden << " hidden units; final performance = each run's best policy over "
      << spec.eval_episodes << " held-out episodes (the same set for every run and condition).\n\n"
      << "Target: " << spec.target.describe() << "\n\n";
    if (spec.target.distribution) {
        o << "The target is a distribution of worlds: its held-out episodes (final performance, checkpoints, the "
             "references) run in its validation worlds (world seeds from "
          << kValidationSeedBase << ", never trained on; docs/simevo.md \"Held-out worlds\"); the episode pictures in `"
          << picture_scenario(spec.target).environment << "`.\n\n";
    }
    for (const SourceSpec &s : spec.sources) {
        o << "Source `" << s.label << "`: "
          << (s.policy_file.empty() ? s.scenario.describe() + ", " + std::to_string(s.episodes) + " episodes"
                                    : "policy file " + s.policy_file)
          << "\n\n";
    }
    o << "| condition | final R held out (mean ± 95% CI) | arrival held out (95% CI) | recovery ticks per episode (95% CI) | sd of R | candidates' R, first "
      << S.bin_end.front() << " episodes | last bin | episodes to 90% | best fitness at the end |\n"
      << "|---|---|---|---|---|---|---|---|---|\n";
    for (const ConditionSummary &c : S.conditions) {
        const bool prob = !condition_decl(c.kind).evolved;
        o << "| " << c.label << " | " << fmt(c.final_mean) << " ± " << fmt(c.final_ci) << " | " << pct_interval(c.arrival)
          << " | " << num_interval(c.tau_c, 1) << " | " << fmt(c.final_sd)
          << " | " << (prob ? "-" : fmt(c.start)) << " | " << (prob ? "-" : fmt(c.end)) << " | "
          << (prob ? "-" : (c.episodes_to_90 > 0 ? fmt(c.episodes_to_90, 0) : "n/a")) << " | "
          << (prob ? "-" : fmt(c.best_end)) << " |\n";
    }
    o << "\n| comparison | difference in final R | improvement | faster to 90% | test | p | Mann-Whitney p | difference in online R (Welch p) |\n|---|---|---|---|---|---|---|---|\n";
    for (const Comparison &c : S.comparisons) {
        o << "| " << c.a << " vs " << c.b << " | " << fmt(c.difference) << " | "
          << (std::isfinite(c.improvement_pct) ? fmt(c.improvement_pct, 1) + "%" : "n/a") << " | "
          << (std::isfinite(c.speedup_pct) ? fmt(c.speedup_pct, 0) + "%" : "-") << " | "
          << (c.test == "welch" ? "Welch t" : "one-sample t") << " | " << fmt_p(c.t) << " | "
          << (!condition_decl(c.b_kind).evolved ? "-" : fmt_p(c.mann_whitney)) << " | "
          << (!condition_decl(c.b_kind).evolved ? "-" : fmt(c.online_difference) + " (" + fmt_p(c.online) + ")") << " |\n";
    }
    o << "\nArrival and recovery ticks: per run the fraction of its best policy's held-out episodes that reached the "
         "destination and its mean recovery ticks (tau_c) per episode, 95% CI over runs (Student t, clipped to the "
         "possible range); the references (the probabilistic policy hand-tuned for the robot, and VFH+: libqnav's "
         "'vfh' controller with its documented defaults, docs/architecture.md) are one policy or controller each, so "
         "their CIs are over episodes (arrival: Wilson score interval). "
         "Candidates' R = mean R of the networks evaluated (mutants, each on k episodes), binned by target episodes, mean over runs. "
         "Best fitness = the population's best member's fitness (mean R of its episodes; biased upwards by selection), mean over runs. "
         "Online R = mean R of all candidates of a run (the area under its learning curve; higher = learns faster and better). "
         "Improvement = (mean_a − mean_b) / |mean_b| (n/a when |mean_b| < 1). Episodes to 90% = first bin at "
         "which the candidates' mean curve has covered 90% of its rise from its first to its last bin. "
         "The probabilistic policy's p-value is a one-sample t-test of the runs against its held-out mean.\n\n";
    o << checkpoint_tables_md(S);
    o << worlds_md(spec, H);
    if (plots) {
        o << "![learning curves](learning.png)\n\n![policy quality](policy.png)\n\n"
          << "![held-out episodes of the best policies](episodes.png)\n\n";
    }
    // The file run.txt records (an experiment run from a file has no name simevo knows; a
    // sweep member's variation is in the overrides, --vary KEY=VALUE); without one, the
    // name (a sweep member is NAME.KEY-VALUE: names have no dots).
    std::string what = opt.experiment_file;
    if (what.empty()) {
        what = spec.name.substr(0, spec.name.find('.'));
    } else if (what.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_./+-") !=
               std::string::npos) {
        std::string q = "'";
        for (char c : what) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
        what = q + "'";
    }
    o << "Regenerate: `simevo run " << what << " --preset " << opt.preset << opt.overrides
      << "` (with the same `--out`)\n";
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

/* Everything after the runs but summary.md: curves, quality map, summary.json, episode
 * traces and the plots (STATUS says when plots are missing). Throws UserError. */
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

} // namespace

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
        // a transfer's source policy does not exist yet: name the task that will make it
        const std::string source = t.source_task >= 0
                                       ? "best policy of " + tasks[static_cast<std::size_t>(t.source_task)].dir.substr(exp_dir.size() + 1)
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
