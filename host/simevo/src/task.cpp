/*
 * Resumable tasks: journal replay, evolution loop, best policy and held-out evaluation.
 */
#include "task.h"

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <functional>
#include <sstream>
#include <unistd.h>

#include "files.h"
#include "qnav/policy_io.h"
#include "rng.h"
#include "worlds.h"

namespace qnav {

namespace {

const char *kJournalHeader = "step,R,f1,f2,tau_c,arrived,parent,explored,policy,parent_R,best_fitness\n";
const char *kEvalHeader = "eval_episode,R,f1,f2,tau_c,reached\n";
const char *kCheckpointHeader = "checkpoint,episodes,n,R,arrived,tau_c\n";

std::vector<std::string> split_csv(const std::string &line)
{
    std::vector<std::string> f;
    std::size_t start = 0;
    for (;;) {
        const std::size_t c = line.find(',', start);
        f.push_back(line.substr(start, c == std::string::npos ? std::string::npos : c - start));
        if (c == std::string::npos) {
            break;
        }
        start = c + 1;
    }
    return f;
}

bool parse_double(const std::string &s, double &v)
{
    if (s.empty()) {
        return false;
    }
    char *end = nullptr;
    errno = 0;
    v = std::strtod(s.c_str(), &end);
    return end == s.c_str() + s.size() && errno == 0;
}

bool parse_u64(const std::string &s, uint64_t &v)
{
    if (s.empty() || s[0] == '-') {
        return false;
    }
    char *end = nullptr;
    errno = 0;
    v = std::strtoull(s.c_str(), &end, 10);
    return end == s.c_str() + s.size() && errno == 0;
}

std::string fmt_outcome(const EpisodeOutcome &o)
{
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.17g,%.6f,%.6f,%" PRIu32 ",%d", o.R, o.f1, o.f2, o.tau_c,
                  o.reached ? 1 : 0);
    return buf;
}

/* Parses "R,f1,f2,tau_c,reached" starting at field k; reached counts arrivals, at most
 * max_reached (1 for one episode, k for a journal step); *arrived gets the count. */
bool parse_outcome(const std::vector<std::string> &f, std::size_t k, EpisodeOutcome &o,
                   uint32_t max_reached = 1, uint32_t *arrived = nullptr)
{
    uint64_t tau = 0;
    uint64_t reached = 0;
    if (!parse_double(f[k], o.R) || !parse_double(f[k + 1], o.f1) ||
        !parse_double(f[k + 2], o.f2) || !parse_u64(f[k + 3], tau) ||
        !parse_u64(f[k + 4], reached) || reached > max_reached || tau > UINT32_MAX) {
        return false;
    }
    o.tau_c = static_cast<uint32_t>(tau);
    o.reached = reached == max_reached;
    if (arrived != nullptr) {
        *arrived = static_cast<uint32_t>(reached);
    }
    return true;
}

/* Lines of a text, each with its end offset; a last line without '\n' is reported as
 * incomplete. */
struct Lines {
    std::vector<std::string> lines;
    std::vector<std::size_t> ends; /* offset just past each complete line's '\n' */
};
Lines split_lines(const std::string &text)
{
    Lines L;
    std::size_t start = 0;
    while (start < text.size()) {
        const std::size_t nl = text.find('\n', start);
        if (nl == std::string::npos) {
            break; // partial last line: the episode in flight when the run was killed
        }
        L.lines.push_back(text.substr(start, nl - start));
        L.ends.push_back(nl + 1);
        start = nl + 1;
    }
    return L;
}

// Closes a file descriptor when it goes out of scope.
struct FdGuard {
    int fd;
    ~FdGuard() { ::close(fd); }
};

// Open a journal for appending after its first `keep` bytes (the complete lines that
// survived an interrupted run), writing the header when nothing survived.
int open_journal_at(const std::string &path, std::size_t keep, const char *header)
{
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
        throw UserError(path + ": cannot open (" + std::strerror(errno) + ")");
    }
    FdGuard guard{fd};
    if (::ftruncate(fd, static_cast<off_t>(keep)) != 0 ||
        ::lseek(fd, static_cast<off_t>(keep), SEEK_SET) < 0) {
        throw UserError(path + ": cannot truncate (" + std::strerror(errno) + ")");
    }
    if (keep == 0) {
        write_all(fd, header, path);
    }
    guard.fd = -1; // handed to the caller
    return fd;
}

/* The rows of a resumable journal that survived an interrupted run: the header is checked
 * ("PATH:1: not a simevo KIND"), then row(fields, where) is called for each complete line
 * until it returns false (enough rows) or throws; where = "PATH:LINE: ". Returns the bytes
 * to keep: the header and the rows accepted (0 for a missing or empty file). */
std::size_t resume_rows(const std::string &path, const char *header, const char *kind,
                        const std::function<bool(const std::vector<std::string> &, const std::string &)> &row)
{
    std::string text;
    if (!read_file(path, text) || text.empty()) {
        return 0;
    }
    const Lines L = split_lines(text);
    if (L.lines.empty()) {
        return 0; // killed while writing the header
    }
    if (L.lines[0] + "\n" != header) {
        throw UserError(path + ":1: not a simevo " + kind);
    }
    std::size_t keep = L.ends[0];
    for (std::size_t i = 1; i < L.lines.size(); ++i) {
        if (!row(split_csv(L.lines[i]), path + ":" + std::to_string(i + 1) + ": ")) {
            break;
        }
        keep = L.ends[i];
    }
    return keep;
}

/* Held-out evaluation, journaled like the evolution (STEM.partial, one line per episode)
 * and renamed to STEM.csv when complete; episode(seed) runs one episode. Returns false
 * when stopped. */
bool run_eval_episodes(const std::function<EpisodeOutcome(uint64_t)> &episode, const char *stem,
                       const TaskDef &t, const TaskObserver &obs, const std::atomic<bool> &stop)
{
    const std::string partial = join_path(t.dir, std::string(stem) + ".partial");
    const std::string final_path = join_path(t.dir, std::string(stem) + ".csv");
    if (file_exists(final_path)) { // killed between the rename and "done"
        if (obs.episodes_done) {
            obs.episodes_done(static_cast<uint32_t>(read_eval(final_path).size()), true);
        }
        return true;
    }
    uint32_t have = 0;
    const std::size_t keep = resume_rows(partial, kEvalHeader, "evaluation file",
                                         [&](const std::vector<std::string> &f, const std::string &where) {
        if (have >= t.eval_episodes) {
            return false;
        }
        EpisodeOutcome o;
        uint64_t idx = 0;
        if (f.size() != 6 || !parse_u64(f[0], idx) || idx != have || !parse_outcome(f, 1, o)) {
            throw UserError(where + "malformed row");
        }
        ++have;
        return true;
    });
    if (obs.episodes_done && have > 0) {
        obs.episodes_done(have, true);
    }
    const int fd = open_journal_at(partial, keep, kEvalHeader);
    FdGuard guard{fd};
    for (uint32_t i = have; i < t.eval_episodes; ++i) {
        if (stop.load()) {
            return false;
        }
        const EpisodeOutcome o = episode(mix_seed(t.eval_seed_base, i));
        write_all(fd, std::to_string(i) + "," + fmt_outcome(o) + "\n", partial);
        if (obs.episodes_done) {
            obs.episodes_done(1, false);
        }
    }
    if (::rename(partial.c_str(), final_path.c_str()) != 0) {
        throw UserError(final_path + ": cannot write (" + std::strerror(errno) + ")");
    }
    return true;
}

/* The held-out evaluation of a policy: eval.csv. */
bool run_eval(EpisodeRunner &runner, const qnav_policy_t &policy, const TaskDef &t,
              const TaskObserver &obs, const std::atomic<bool> &stop)
{
    return run_eval_episodes([&](uint64_t seed) { return runner.run(policy, seed); }, "eval", t, obs, stop);
}

/* A policy's score over the k episodes of one step: mean R, f1, f2; tau_c summed;
 * reached = all arrived. */
struct StepOutcome {
    EpisodeOutcome o;
    uint32_t arrived = 0;
};

/* Episode j of step `step` runs with mix_seed(base, step * k + j): the candidate and the
 * parent it is compared with face the same k start points. */
StepOutcome run_k(EpisodeRunner &runner, const qnav_policy_t &policy, uint64_t base, uint64_t step, uint32_t k)
{
    StepOutcome sum;
    for (uint32_t j = 0; j < k; ++j) {
        const EpisodeOutcome o = runner.run(policy, mix_seed(base, step * k + j));
        sum.o.R += o.R;
        sum.o.f1 += o.f1;
        sum.o.f2 += o.f2;
        sum.o.tau_c += o.tau_c;
        sum.arrived += o.reached ? 1 : 0;
    }
    sum.o.R /= k;
    sum.o.f1 /= k;
    sum.o.f2 /= k;
    sum.o.reached = sum.arrived == k;
    return sum;
}

std::string fmt_step(const StepOutcome &s)
{
    char buf[160];
    std::snprintf(buf, sizeof buf, "%.17g,%.6f,%.6f,%" PRIu32 ",%" PRIu32, s.o.R, s.o.f1, s.o.f2, s.o.tau_c,
                  s.arrived);
    return buf;
}

/* The checkpoint journal of a target task: the rows already there are kept; reach()
 * evaluates the best member at every checkpoint passed and not yet recorded, so a resumed
 * task (which replays the evolution step by step) completes exactly the missing ones. */
class CheckpointLog {
public:
    CheckpointLog(const TaskDef &t, EpisodeRunner &runner, const TaskObserver &obs)
        : t_(t), runner_(runner), obs_(obs), path_(join_path(t.dir, "checkpoints.csv"))
    {
        if (t.checkpoints.empty()) {
            return;
        }
        const std::size_t keep = resume_rows(path_, kCheckpointHeader, "checkpoint file",
                                             [&](const std::vector<std::string> &f, const std::string &where) {
            if (done_ >= t.checkpoints.size()) {
                return false;
            }
            uint64_t c = 0;
            if (f.size() != 6 || !parse_u64(f[0], c) || c != t.checkpoints[done_]) {
                throw UserError(where + "malformed row");
            }
            ++done_;
            return true;
        });
        if (obs_.episodes_done && done_ > 0) {
            obs_.episodes_done(done_ * t.checkpoint_episodes, true);
        }
        fd_ = open_journal_at(path_, keep, kCheckpointHeader);
    }
    ~CheckpointLog()
    {
        if (fd_ >= 0) {
            ::close(fd_);
        }
    }
    CheckpointLog(const CheckpointLog &) = delete;
    CheckpointLog &operator=(const CheckpointLog &) = delete;

    void reach(const Search &evo, uint64_t episodes)
    {
        while (done_ < t_.checkpoints.size() && t_.checkpoints[done_] <= episodes) {
            const qnav_policy_t &best = evo.best_policy();
            CheckpointRow r;
            r.checkpoint = t_.checkpoints[done_];
            r.episodes = episodes;
            r.n = t_.checkpoint_episodes;
            for (uint32_t i = 0; i < r.n; ++i) {
                const EpisodeOutcome o = runner_.run(best, mix_seed(t_.eval_seed_base, i));
                r.R += o.R / r.n;
                r.arrived += o.reached ? 1 : 0;
                r.tau_c += o.tau_c;
            }
            char row[200];
            std::snprintf(row, sizeof row, "%" PRIu64 ",%" PRIu64 ",%" PRIu32 ",%.17g,%" PRIu32 ",%" PRIu64 "\n",
                          r.checkpoint, r.episodes, r.n, r.R, r.arrived, r.tau_c);
            write_all(fd_, row, path_);
            if (obs_.episodes_done) {
                obs_.episodes_done(r.n, false);
            }
            ++done_;
        }
    }

private:
    const TaskDef &t_;
    EpisodeRunner &runner_;
    const TaskObserver &obs_;
    std::string path_;
    std::size_t done_ = 0;
    int fd_ = -1;
};

} // namespace

qnav_policy_t read_policy_file(const std::string &path)
{
    if (!file_exists(path)) {
        throw UserError(path + ": policy file not found");
    }
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN] = {0};
    if (qnav_policy_read(path.c_str(), &p, err, sizeof err) != 0) {
        throw UserError(err);
    }
    return p;
}

qnav_policy_t load_source_policy(const std::string &path)
{
    const qnav_policy_t p = read_policy_file(path);
    switch (static_cast<qnav_policy_kind_t>(p.kind)) {
    case QNAV_POLICY_NET:
        break;
    case QNAV_POLICY_PROB:
        throw UserError(path + ": incompatible policy: kind is not 'net' (a transfer seeds a "
                               "population of networks)");
    }
    if (p.u.net.hidden < 1 || p.u.net.hidden > QNAV_MAX_HIDDEN) {
        throw UserError(path + ": incompatible policy: hidden units outside 1.." + std::to_string(QNAV_MAX_HIDDEN));
    }
    return p;
}

const char *task_kind_name(TaskKind k)
{
    switch (k) {
    case TaskKind::Evolve:
        return "evolve";
    case TaskKind::EvalProbabilistic:
        return "eval-probabilistic+vfh"; /* kept as written before the reference table */
    }
    return "evolve";
}

namespace {
/* The evolution strategy's settings; "" for ε-greedy, so fingerprints from before it match. */
std::string es_settings_text(const EvolutionParams &e)
{
    if (e.algorithm != EvolutionParams::Algorithm::Es) {
        return "";
    }
    std::ostringstream o;
    o.precision(17);
    o << " algorithm=" << algorithm_name(e.algorithm) << " es_pairs=" << e.es_pairs << " es_sigma=" << e.es_sigma
      << " es_step=" << e.es_step;
    return o.str();
}
} // namespace

std::string task_settings_text(const TaskDef &t, const std::string &source_fingerprint)
{
    std::ostringstream o;
    o.precision(17);
    const EvolutionParams &e = t.evolution;
    o << "# simevo task settings; a resumed task must match them exactly\n"
      << "kind=" << task_kind_name(t.kind) << "\n"
      << "label=" << t.label << "\nrun=" << t.run << "\n"
      << "scenario=" << t.scenario.describe() << "\n"
      << "context_seed=" << t.context_seed << "\n";
    if (t.kind == TaskKind::Evolve) {
        o << "episodes=" << t.episodes << "\n"
          << "population=" << e.population << " epsilon=" << e.epsilon
          << " hidden=" << e.hidden << " mutation_scale=" << e.mutation_scale
          << " mutation_clip=" << e.mutation_clip << " episodes_per_candidate=" << e.episodes_per_candidate
          << " reevaluate_parent=" << (e.reevaluate_parent ? 1 : 0)
          << " init=" << init_kind_name(e.init)
          << " init_scale=" << e.init_scale
          << (e.inputs != QNAV_NET_INPUTS_PAPER ? " inputs=" + std::to_string(e.inputs) : std::string())
          /* the default is left out, so fingerprints from before world sets still match */
          << (e.world_sets != EvolutionParams::WorldSets::PerStep ? std::string(" world_sets=") + world_sets_name(e.world_sets)
                                                                  : std::string())
          << es_settings_text(e)
          << "\n"
          << "evolution_seed=" << t.evolution_seed << "\n"
          << "episode_seed_base=" << t.episode_seed_base << "\n"
          << "source=" << (source_fingerprint.empty() ? "none (random population)" : source_fingerprint)
          << "\n";
    }
    o << "eval_episodes=" << t.eval_episodes << "\neval_seed_base=" << t.eval_seed_base << "\n";
    if (!t.checkpoints.empty()) {
        o << "checkpoints=";
        for (std::size_t i = 0; i < t.checkpoints.size(); ++i) {
            o << (i ? "," : "") << t.checkpoints[i];
        }
        o << " checkpoint_episodes=" << t.checkpoint_episodes << "\n";
    }
    return o.str();
}

uint64_t task_steps(const TaskDef &t)
{
    // Rounded up, so that every checkpoint within the budget is reached, and to whole
    // rounds of the search (an evolution strategy's iterations).
    const uint64_t k = std::max<uint32_t>(1, t.evolution.episodes_per_candidate);
    const uint64_t round = search_round_steps(t.evolution);
    const uint64_t steps = std::max<uint64_t>(1, (t.episodes + k - 1) / k);
    return (steps + round - 1) / round * round;
}

EpisodeOutcome run_reference(EpisodeRunner &runner, const ReferenceDecl &r, uint64_t episode_seed)
{
    if (r.controller != nullptr) {
        return runner.run_controller(r.controller, episode_seed);
    }
    return runner.run(runner.probabilistic_policy(), episode_seed);
}

uint64_t task_total_episodes(const TaskDef &t)
{
    if (t.kind != TaskKind::Evolve) {
        return kReferenceCount * static_cast<uint64_t>(t.eval_episodes); /* every reference */
    }
    return task_steps(t) * t.evolution.episodes_per_candidate +
           static_cast<uint64_t>(t.checkpoints.size()) * t.checkpoint_episodes + t.eval_episodes;
}

namespace {
/* The complete lines of a finished output file, its header checked; kind names the file
 * in the message. */
Lines read_with_header(const std::string &csv_path, const char *header, const char *kind)
{
    std::string text;
    if (!read_file(csv_path, text)) {
        throw UserError(csv_path + ": missing");
    }
    Lines L = split_lines(text);
    if (L.lines.empty() || L.lines[0] + "\n" != header) {
        throw UserError(csv_path + ":1: not a simevo " + kind);
    }
    return L;
}
} // namespace

JournalColumns read_journal(const std::string &csv_path)
{
    const Lines L = read_with_header(csv_path, kJournalHeader, "episode journal");
    JournalColumns c;
    for (std::size_t i = 1; i < L.lines.size(); ++i) {
        const auto f = split_csv(L.lines[i]);
        double best = 0.0;
        EpisodeOutcome o;
        uint32_t arrived = 0;
        if (f.size() != 11 || !parse_outcome(f, 1, o, UINT32_MAX, &arrived) || !parse_double(f[10], best)) {
            throw UserError(csv_path + ":" + std::to_string(i + 1) + ": malformed row");
        }
        c.R.push_back(o.R);
        c.arrived.push_back(arrived);
        c.best_fitness.push_back(best);
    }
    return c;
}

namespace {
/* The rows of a finished output file, each parsed by parse (false = malformed). */
template <typename T>
std::vector<T> read_rows(const std::string &csv_path, const char *header, const char *kind,
                         bool (*parse)(const std::vector<std::string> &, T &))
{
    const Lines L = read_with_header(csv_path, header, kind);
    std::vector<T> v;
    for (std::size_t i = 1; i < L.lines.size(); ++i) {
        T row;
        if (!parse(split_csv(L.lines[i]), row)) {
            throw UserError(csv_path + ":" + std::to_string(i + 1) + ": malformed row");
        }
        v.push_back(row);
    }
    return v;
}

bool parse_checkpoint(const std::vector<std::string> &f, CheckpointRow &r)
{
    uint64_t n = 0, arrived = 0;
    if (f.size() != 6 || !parse_u64(f[0], r.checkpoint) || !parse_u64(f[1], r.episodes) || !parse_u64(f[2], n) ||
        !parse_double(f[3], r.R) || !parse_u64(f[4], arrived) || !parse_u64(f[5], r.tau_c) || n == 0 ||
        n > UINT32_MAX || arrived > n) {
        return false;
    }
    r.n = static_cast<uint32_t>(n);
    r.arrived = static_cast<uint32_t>(arrived);
    return true;
}

bool parse_eval_row(const std::vector<std::string> &f, EpisodeOutcome &o)
{
    return f.size() == 6 && parse_outcome(f, 1, o);
}
} // namespace

std::vector<CheckpointRow> read_checkpoints(const std::string &csv_path)
{
    return read_rows(csv_path, kCheckpointHeader, "checkpoint file", parse_checkpoint);
}

std::vector<EpisodeOutcome> read_eval(const std::string &csv_path)
{
    return read_rows(csv_path, kEvalHeader, "evaluation file", parse_eval_row);
}

namespace {
/* Replay the journal (if any) through evo: same proposals, recorded outcomes, no
 * simulation except checkpoints missing from their file. Returns the bytes of the journal
 * to keep (complete, matching lines). */
std::size_t replay_journal(const TaskDef &t, const std::string &journal_path, Search &evo,
                           CheckpointLog &checkpoints, const TaskObserver &obs)
{
    const uint32_t k = t.evolution.episodes_per_candidate;
    return resume_rows(journal_path, kJournalHeader, "episode journal",
                       [&](const std::vector<std::string> &f, const std::string &where) {
        if (evo.episodes_done() >= task_steps(t)) {
            return false;
        }
        uint64_t step = 0;
        EpisodeOutcome o;
        if (f.size() != 11 || !parse_u64(f[0], step) || !parse_outcome(f, 1, o, k)) {
            throw UserError(where + "malformed journal row");
        }
        const Candidate c = evo.propose();
        EpisodeOutcome po;
        const bool has_parent = t.evolution.reevaluate_parent && c.parent >= 0;
        if (has_parent != !f[9].empty() || (has_parent && !parse_double(f[9], po.R))) {
            throw UserError(where + "parent re-evaluation missing or unexpected");
        }
        char fp[16];
        std::snprintf(fp, sizeof fp, "%08" PRIx32, policy_fingerprint(c.policy));
        if (step != c.episode || f[8] != fp) {
            throw UserError(where + "journal does not match this program and settings "
                                    "(step or policy differs); use another --out");
        }
        evo.accept(c, o, has_parent ? &po : nullptr);
        if (obs.episodes_done) {
            obs.episodes_done(k, true);
        }
        checkpoints.reach(evo, evo.episodes_done() * k);
        return true;
    });
}
/* Which k episodes step `step` runs: its own (paired with its parent), its generation's, or
 * its evolution-strategy iteration's. */
uint64_t step_episode_set(const EvolutionParams &e, uint64_t step)
{
    if (e.algorithm == EvolutionParams::Algorithm::Es) {
        return step / search_round_steps(e);
    }
    switch (e.world_sets) {
    case EvolutionParams::WorldSets::PerStep:
        return step;
    case EvolutionParams::WorldSets::PerGeneration:
        return step / e.population;
    }
    return step;
}

/* Resume (replay) and continue an evolution to its budget, journaling each step and
 * evaluating the checkpoints. Returns false when stopped. */
bool evolve(const TaskDef &t, Search &evo, EpisodeRunner &runner, EpisodeRunner &held_out_runner,
            const std::string &journal_path, const TaskObserver &obs, const std::atomic<bool> &stop)
{
    CheckpointLog checkpoints(t, held_out_runner, obs);
    const std::size_t keep = replay_journal(t, journal_path, evo, checkpoints, obs);
    const int fd = open_journal_at(journal_path, keep, kJournalHeader);
    FdGuard guard{fd};
    if (obs.best && evo.episodes_done() > 0) {
        obs.best(t.label, evo.best_so_far());
    }
    const uint32_t k = t.evolution.episodes_per_candidate;
    while (evo.episodes_done() < task_steps(t)) {
        if (stop.load()) {
            return false;
        }
        const Candidate c = evo.propose();
        const uint64_t episode_set = step_episode_set(t.evolution, c.episode);
        const StepOutcome o = run_k(runner, c.policy, t.episode_seed_base, episode_set, k);
        const bool has_parent = t.evolution.reevaluate_parent && c.parent >= 0;
        StepOutcome po;
        char parent_r[40] = "";
        if (has_parent) {
            po = run_k(runner, evo.member_policy(c.parent), t.episode_seed_base,
                       episode_set, k);
            std::snprintf(parent_r, sizeof parent_r, "%.17g", po.o.R);
        }
        evo.accept(c, o.o, has_parent ? &po.o : nullptr);
        char row[360];
        std::snprintf(row, sizeof row, "%" PRIu64 ",%s,%d,%d,%08" PRIx32 ",%s,%.17g\n", c.episode,
                      fmt_step(o).c_str(), static_cast<int>(c.parent), c.explored ? 1 : 0,
                      policy_fingerprint(c.policy), parent_r, evo.best_so_far());
        write_all(fd, row, journal_path);
        if (obs.episodes_done) {
            obs.episodes_done(k, false);
        }
        if (obs.best) {
            obs.best(t.label, evo.best_so_far());
        }
        checkpoints.reach(evo, evo.episodes_done() * k);
    }

    return true;
}
/* The population's best member written to best_path, its comment naming the task, run,
 * episodes and fitness. Returns that policy. Throws UserError. */
qnav_policy_t write_best_policy(const TaskDef &t, const Search &evo, const std::string &best_path)
{
    const qnav_policy_t best = evo.best_policy();
    char comment[200];
    std::snprintf(comment, sizeof comment, "simevo %s run %u: best after %" PRIu64 " episodes, R = %.6f",
                  t.label.c_str(), t.run + 1, t.episodes, evo.best_fitness());
    char err[QNAV_POLICY_IO_ERRLEN] = {0};
    if (qnav_policy_write(best_path.c_str(), &best, comment, err, sizeof err) != 0) {
        throw UserError(err);
    }
    return best;
}

/* The runner of a scenario: make's, or over a distribution's worlds. */
std::unique_ptr<EpisodeRunner> make_runner(const RunnerFactory &make, const Scenario &sc, uint64_t seed)
{
    if (sc.distribution) {
        return std::make_unique<DistributionRunner>(sc, seed, make);
    }
    return make(sc, seed);
}
} // namespace

bool run_task(const TaskDef &t, const std::string &source_policy_path, const RunnerFactory &make,
              const TaskObserver &obs, const std::atomic<bool> &stop)
{
    make_dirs(t.dir);
    const std::string settings_path = join_path(t.dir, "task.txt");
    const std::string journal_path = join_path(t.dir, "episodes.csv");
    const std::string best_path = join_path(t.dir, "best.policy");
    const std::string done_path = join_path(t.dir, "done");

    qnav_policy_t source{};
    std::string source_fp;
    if (t.kind == TaskKind::Evolve && !source_policy_path.empty()) {
        source = load_source_policy(source_policy_path);
        char buf[64];
        std::snprintf(buf, sizeof buf, "policy %08" PRIx32 " (hidden %u)",
                      policy_fingerprint(source), static_cast<unsigned>(source.u.net.hidden));
        source_fp = buf;
    }
    const std::string settings = task_settings_text(t, source_fp);
    std::string existing;
    if (read_file(settings_path, existing)) {
        if (existing != settings) {
            throw UserError(settings_path +
                            ": this output folder was made with different settings; use another "
                            "--out (or delete the folder to start over)");
        }
    } else {
        write_file_atomic(settings_path, settings);
    }
    if (file_exists(done_path)) {
        if (obs.episodes_done) {
            obs.episodes_done(task_total_episodes(t), true);
        }
        return true;
    }

    // Held-out episodes of a distribution run in its validation worlds; of one environment,
    // at new start points of it (the same runner, as before distributions existed).
    std::unique_ptr<EpisodeRunner> held_out_owner;
    std::unique_ptr<EpisodeRunner> runner;
    if (t.kind == TaskKind::EvalProbabilistic || !t.scenario.distribution) {
        runner = make_runner(make, validation_scenario(t.scenario), t.context_seed);
    } else {
        runner = make_runner(make, t.scenario, t.context_seed);
        held_out_owner = make_runner(make, validation_scenario(t.scenario), t.context_seed);
    }
    EpisodeRunner &held_out = held_out_owner ? *held_out_owner : *runner;

    if (t.kind == TaskKind::EvalProbabilistic) {
        // every reference on the same held-out episodes, one task so shares stay as they were
        for (const ReferenceDecl &r : kReferences) {
            if (!run_eval_episodes([&](uint64_t seed) { return run_reference(*runner, r, seed); }, r.eval_stem, t,
                                   obs, stop)) {
                return false;
            }
        }
        write_file_atomic(done_path, "complete\n");
        return true;
    }

    const std::unique_ptr<Search> evo =
        make_search(t.evolution, t.evolution_seed, source_policy_path.empty() ? nullptr : &source);
    if (!evolve(t, *evo, *runner, held_out, journal_path, obs, stop)) {
        return false;
    }
    const qnav_policy_t best = write_best_policy(t, *evo, best_path);
    if (t.eval_episodes > 0) {
        if (!run_eval(held_out, best, t, obs, stop)) {
            return false;
        }
    }
    write_file_atomic(done_path, "complete\n");
    return true;
}

} // namespace qnav
