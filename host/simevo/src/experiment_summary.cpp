/*
 * The summary of a finished experiment, read from its task folders only (eval.csv,
 * checkpoints.csv, episodes.csv): per condition final performance, arrival and recovery
 * with 95% CIs, binned learning curves, episodes to 90% and to the arrival threshold; and
 * the comparisons between conditions with their tests.
 */
#include "experiment.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "files.h"
#include "stats.h"

namespace qnav {

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
    double arrived = 0, clean = 0, tau = 0;
    for (const auto &o : ev) {
        r.push_back(o.R);
        arrived += o.reached ? 1 : 0;
        clean += o.reached && o.tau_c == 0 ? 1 : 0;
        tau += o.tau_c;
    }
    reached += static_cast<uint64_t>(arrived);
    evals += ev.size();
    c.final_per_run.push_back(mean_of(r));
    const double n = ev.empty() ? 1.0 : static_cast<double>(ev.size());
    c.arrival_per_run.push_back(arrived / n);
    c.clean_per_run.push_back(clean / n);
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
            prob.clean_per_run.push_back(o.reached && o.tau_c == 0 ? 1.0 : 0.0);
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

} // namespace qnav
