/*
 * Held-out worlds: evaluation of every best policy and reference in every world, their
 * figures per condition and world, and the recommended policy.
 */
#include "heldout.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include "files.h"
#include "rng.h"
#include "stats.h"
#include "task.h"

namespace qnav {

const uint64_t kHeldOutWorldsSeed = 0x6865'6c64'6f75'7421ull; /* "heldout!" */

namespace {

const char *kWorldsHeader = "condition,run,world,n,R,R_sd,arrived,tau_c,tau_c_sd\n";

/* What one row drives: a policy file, the probabilistic policy, or VFH+. */
struct Subject {
    std::string condition;
    uint32_t run = 0;
    ConditionKind kind = ConditionKind::Direct;
    std::string policy_file; /* evolved conditions */
};

std::vector<Subject> subjects(const ExperimentSummary &S, const std::string &exp_dir)
{
    std::vector<Subject> v;
    for (const ConditionSummary &c : S.conditions) {
        if (!condition_decl(c.kind).evolved) {
            v.push_back({c.label, 0, c.kind, ""});
            continue;
        }
        for (std::size_t r = 0; r < c.final_per_run.size(); ++r) {
            const std::string file =
                join_path(join_path(run_dir(exp_dir, static_cast<uint32_t>(r)), c.label), "best.policy");
            v.push_back({c.label, static_cast<uint32_t>(r + 1), c.kind, file});
        }
    }
    return v;
}

/* The runner of a held-out world (a family's test worlds run over a distribution). */
std::unique_ptr<EpisodeRunner> world_runner(const HeldOutWorld &w, uint64_t seed, const WorldRunnerFactory &make)
{
    if (w.scenario.distribution) {
        return std::make_unique<DistributionRunner>(w.scenario, seed, make);
    }
    return make(w.scenario, seed);
}

WorldRow evaluate_one(const Subject &s, const HeldOutWorld &w, uint32_t n, uint64_t context_seed,
                      const WorldRunnerFactory &make)
{
    std::unique_ptr<EpisodeRunner> runner = world_runner(w, context_seed, make);
    qnav_policy_t policy = runner->probabilistic_policy();
    if (!s.policy_file.empty()) {
        policy = read_policy_file(s.policy_file);
    }
    WorldRow row;
    row.condition = s.condition;
    row.run = s.run;
    row.world = w.label;
    row.n = n;
    std::vector<double> R, tau;
    for (uint32_t i = 0; i < n; ++i) {
        const uint64_t seed = mix_seed(kHeldOutWorldsSeed, i);
        const ReferenceDecl *ref = condition_decl(s.kind).reference;
        const EpisodeOutcome o = ref != nullptr ? run_reference(*runner, *ref, seed) : runner->run(policy, seed);
        R.push_back(o.R);
        tau.push_back(o.tau_c);
        row.arrived += o.reached ? 1 : 0;
        row.tau_c += o.tau_c;
    }
    row.R = mean_of(R);
    row.R_sd = sd_of(R);
    row.tau_c_sd = sd_of(tau);
    return row;
}

bool parse_row(const std::string &line, WorldRow &r)
{
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) {
        f.push_back(x);
    }
    if (f.size() != 9) {
        return false;
    }
    char *end = nullptr;
    r.condition = f[0];
    errno = 0;
    r.run = static_cast<uint32_t>(std::strtoul(f[1].c_str(), &end, 10));
    r.world = f[2];
    r.n = static_cast<uint32_t>(std::strtoul(f[3].c_str(), &end, 10));
    r.R = std::strtod(f[4].c_str(), &end);
    r.R_sd = std::strtod(f[5].c_str(), &end);
    r.arrived = static_cast<uint32_t>(std::strtoul(f[6].c_str(), &end, 10));
    r.tau_c = std::strtoull(f[7].c_str(), &end, 10);
    r.tau_c_sd = std::strtod(f[8].c_str(), &end);
    return errno == 0 && r.n > 0 && r.arrived <= r.n && !r.condition.empty() && !r.world.empty();
}

/* mean ± t(n - 1) sd / sqrt(n), clipped below at lo. */
Interval sd_interval(double mean, double sd, uint32_t n, double lo)
{
    const double h = n > 1 ? t_critical(n - 1, 0.05) * sd / std::sqrt(static_cast<double>(n)) : 0.0;
    return Interval{mean, std::max(lo, mean - h), mean + h};
}

/* A reference or one policy: CIs over its n episodes (arrival: Wilson). */
WorldCell single_cell(const WorldRow &r, bool family)
{
    WorldCell c;
    c.world = r.world;
    c.family = family;
    c.runs = 1;
    c.episodes = r.n;
    c.R = sd_interval(r.R, r.R_sd, r.n, -std::numeric_limits<double>::infinity());
    c.arrival = wilson_interval(r.arrived, r.n);
    c.tau_c = sd_interval(static_cast<double>(r.tau_c) / r.n, r.tau_c_sd, r.n, 0.0);
    return c;
}

} // namespace

std::vector<WorldRow> evaluate_held_out_worlds(const ExperimentSpec &spec, const ExperimentSummary &S,
                                               const std::string &exp_dir, const std::vector<HeldOutWorld> &worlds,
                                               const WorldRunnerFactory &make, unsigned jobs)
{
    const std::vector<Subject> subs = subjects(S, exp_dir);
    const std::size_t total = subs.size() * worlds.size();
    std::vector<WorldRow> rows(total);
    std::atomic<std::size_t> next{0};
    std::mutex mu;
    std::string first_error;
    auto worker = [&]() {
        for (std::size_t i = next++; i < total; i = next++) {
            try {
                rows[i] = evaluate_one(subs[i / worlds.size()], worlds[i % worlds.size()], spec.worlds_episodes,
                                       spec.seed, make);
            } catch (const std::exception &e) {
                std::lock_guard<std::mutex> l(mu);
                if (first_error.empty()) {
                    first_error = e.what();
                }
                next = total;
            }
        }
    };
    if (jobs == 0) {
        jobs = std::max(1u, std::thread::hardware_concurrency());
    }
    std::vector<std::thread> pool;
    for (unsigned j = 0; j < jobs; ++j) {
        pool.emplace_back(worker);
    }
    for (auto &t : pool) {
        t.join();
    }
    if (!first_error.empty()) {
        throw UserError("held-out worlds: " + first_error);
    }
    return rows;
}

std::string world_rows_csv(const std::vector<WorldRow> &rows)
{
    std::ostringstream o;
    o << kWorldsHeader;
    for (const WorldRow &r : rows) {
        char b[128];
        std::snprintf(b, sizeof b, ",%u,", r.run);
        o << r.condition << b << r.world;
        std::snprintf(b, sizeof b, ",%u,%.17g,%.17g,%u,%" PRIu64 ",%.17g\n", r.n, r.R, r.R_sd, r.arrived, r.tau_c,
                      r.tau_c_sd);
        o << b;
    }
    return o.str();
}

std::vector<WorldRow> read_world_rows(const std::string &csv_path)
{
    std::string text;
    if (!read_file(csv_path, text)) {
        throw UserError(csv_path + ": missing");
    }
    std::stringstream ss(text);
    std::string line;
    std::vector<WorldRow> rows;
    std::size_t n = 0;
    while (std::getline(ss, line)) {
        ++n;
        if (n == 1) {
            if (line + "\n" != kWorldsHeader) {
                throw UserError(csv_path + ":1: not a simevo held-out worlds file");
            }
            continue;
        }
        WorldRow r;
        if (!parse_row(line, r)) {
            throw UserError(csv_path + ":" + std::to_string(n) + ": malformed row");
        }
        rows.push_back(r);
    }
    return rows;
}

std::vector<ConditionWorlds> summarize_worlds(const ExperimentSummary &S, const std::vector<HeldOutWorld> &worlds,
                                              const std::vector<WorldRow> &rows)
{
    std::vector<ConditionWorlds> out;
    for (const ConditionSummary &c : S.conditions) {
        ConditionWorlds cw;
        cw.label = c.label;
        cw.evolved = condition_decl(c.kind).evolved;
        for (const HeldOutWorld &w : worlds) {
            std::vector<double> R, arrival, tau;
            const WorldRow *single = nullptr;
            uint32_t episodes = 0;
            for (const WorldRow &r : rows) {
                if (r.condition != c.label || r.world != w.label) {
                    continue;
                }
                single = &r;
                episodes = r.n;
                R.push_back(r.R);
                arrival.push_back(static_cast<double>(r.arrived) / r.n);
                tau.push_back(static_cast<double>(r.tau_c) / r.n);
            }
            if (single == nullptr) {
                throw UserError("held-out worlds: no row for " + c.label + " in " + w.label);
            }
            if (!cw.evolved) {
                cw.cells.push_back(single_cell(*single, w.family));
                continue;
            }
            WorldCell cell;
            cell.world = w.label;
            cell.family = w.family;
            cell.runs = static_cast<uint32_t>(R.size());
            cell.episodes = episodes;
            const double inf = std::numeric_limits<double>::infinity();
            cell.R = t_interval(R, -inf, inf);
            cell.arrival = t_interval(arrival, 0.0, 1.0);
            cell.tau_c = t_interval(tau, 0.0, inf);
            cw.cells.push_back(cell);
        }
        out.push_back(cw);
    }
    return out;
}

namespace {
/* One candidate for the recommendation: its validation figures. */
struct RecCandidate {
    std::string condition;
    uint32_t run = 0; /* 0: the reference */
    double clean = 0, arrival = 0, tau_c = 0, R = 0;
};

/* a against b in what a user flashing the policy needs: more validation episodes that
 * arrived without touching anything, then more that arrived, then fewer recovery ticks an
 * episode (touches in episodes that did not arrive too). +1 a ahead, -1 b ahead, 0 level
 * (fractions of whole episodes compared with a tolerance: they are summed differently). */
int safer(const RecCandidate &a, const RecCandidate &b)
{
    const double same = 1e-9;
    if (std::fabs(a.clean - b.clean) > same) {
        return a.clean > b.clean ? 1 : -1;
    }
    if (std::fabs(a.arrival - b.arrival) > same) {
        return a.arrival > b.arrival ? 1 : -1;
    }
    if (std::fabs(a.tau_c - b.tau_c) > same) {
        return a.tau_c < b.tau_c ? 1 : -1;
    }
    return 0;
}

/* Evolved run a ahead of evolved run b: safer, then a higher mean R. */
bool ahead(const RecCandidate &a, const RecCandidate &b)
{
    const int s = safer(a, b);
    return s != 0 ? s > 0 : a.R > b.R;
}
} // namespace

Recommendation recommend(const ExperimentSummary &S, const std::vector<HeldOutWorld> &worlds,
                         const std::vector<WorldRow> &rows, uint32_t validation_episodes)
{
    Recommendation best;
    RecCandidate pick;
    bool have = false;
    for (const ConditionSummary &c : S.conditions) {
        if (!condition_decl(c.kind).evolved) {
            continue;
        }
        for (std::size_t r = 0; r < c.arrival_per_run.size(); ++r) {
            const RecCandidate k{c.label, static_cast<uint32_t>(r + 1), c.clean_per_run.at(r), c.arrival_per_run[r],
                              c.tau_c_per_run.at(r), c.final_per_run[r]};
            if (!have || ahead(k, pick)) {
                pick = k;
                have = true;
            }
        }
    }
    if (!have) {
        return best;
    }
    RecCandidate other;
    for (const ConditionSummary &c : S.conditions) {
        if (c.kind != ConditionKind::Probabilistic || c.arrival_per_run.empty()) {
            continue;
        }
        /* a reference's per-run figures are its episodes' */
        const RecCandidate ref{c.label, 0, mean_of(c.clean_per_run), mean_of(c.arrival_per_run),
                               mean_of(c.tau_c_per_run), mean_of(c.final_per_run)};
        best.has_other = true;
        /* the hand-tuned policy stays unless an evolved run is safer on validation: a higher
         * R (a faster robot) does not make up for no evidence (docs/simevo.md) */
        if (safer(pick, ref) <= 0) {
            other = pick;
            pick = ref;
        } else {
            other = ref;
        }
    }
    best.valid = true;
    best.condition = pick.condition;
    best.run = pick.run;
    best.validation_clean = pick.clean;
    best.validation_arrival = pick.arrival;
    best.validation_R = pick.R;
    best.validation_tau_c = pick.tau_c;
    best.other_condition = other.condition;
    best.other_run = other.run;
    best.other_clean = other.clean;
    best.other_arrival = other.arrival;
    best.other_R = other.R;
    best.other_tau_c = other.tau_c;
    best.validation_episodes = validation_episodes;
    for (const HeldOutWorld &w : worlds) {
        for (const WorldRow &r : rows) {
            if (r.condition == best.condition && r.run == best.run && r.world == w.label) {
                best.test.push_back(single_cell(r, w.family));
            }
        }
    }
    return best;
}

std::string recommended_policy_path(const std::string &exp_dir) { return join_path(exp_dir, "recommended.policy"); }

std::vector<std::string> recommendation_lines(const std::string &name, const Recommendation &r,
                                              const std::string &exp_dir)
{
    std::vector<std::string> lines;
    if (!r.valid) {
        return lines;
    }
    char b[640];
    if (r.reference()) {
        std::snprintf(b, sizeof b,
                      "%s: recommended policy %s (the %s policy: no evolved run was ahead of it in the %u "
                      "validation episodes; it arrived in %.1f%%, %.1f%% without touching anything, R %.2f, "
                      "the best evolved, %s run %u, in %.1f%%, %.1f%%, R %.2f)",
                      name.c_str(), recommended_policy_path(exp_dir).c_str(), r.condition.c_str(),
                      r.validation_episodes, 100.0 * r.validation_arrival, 100.0 * r.validation_clean,
                      r.validation_R, r.other_condition.c_str(), r.other_run, 100.0 * r.other_arrival,
                      100.0 * r.other_clean, r.other_R);
    } else {
        char other[160] = "";
        if (r.has_other) {
            std::snprintf(other, sizeof other, "; the %s policy %.1f%%, %.1f%%, R %.2f", r.other_condition.c_str(),
                          100.0 * r.other_arrival, 100.0 * r.other_clean, r.other_R);
        }
        std::snprintf(b, sizeof b,
                      "%s: recommended policy %s (%s run %u, chosen on validation worlds: arrival %.1f%% of %u, "
                      "%.1f%% without touching anything, R %.2f%s)",
                      name.c_str(), recommended_policy_path(exp_dir).c_str(), r.condition.c_str(), r.run,
                      100.0 * r.validation_arrival, r.validation_episodes, 100.0 * r.validation_clean,
                      r.validation_R, other);
    }
    lines.push_back(b);
    for (const WorldCell &c : r.test) {
        std::snprintf(b, sizeof b,
                      "%s: test %s %s: arrival %.0f%% (95%% CI %.0f-%.0f%%) of %u, recovery ticks %.2f per episode, R %.2f",
                      name.c_str(), c.family ? "family" : "environment", c.world.c_str(), 100.0 * c.arrival.mean,
                      100.0 * c.arrival.lo, 100.0 * c.arrival.hi, c.episodes, c.tau_c.mean, c.R.mean);
        lines.push_back(b);
    }
    return lines;
}

} // namespace qnav
