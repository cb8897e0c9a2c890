/*
 * The summary as text: curves.csv, summary.json (the numbers, for tools and the plots)
 * and summary.md (the tables a reader sees, with the command that regenerates them).
 */
#include "experiment_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "qnav/sim.h"

namespace qnav {

namespace {

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

namespace {

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
          << ", \"validation_clean\": " << json_num(r.validation_clean)
          << ", \"validation_arrival\": " << json_num(r.validation_arrival)
          << ", \"validation_R\": " << json_num(r.validation_R)
          << ", \"validation_tau_c\": " << json_num(r.validation_tau_c)
          << ", \"validation_episodes\": " << r.validation_episodes;
        if (r.has_other) {
            o << ", \"other\": {\"condition\": " << json_str(r.other_condition) << ", \"run\": " << r.other_run
              << ", \"validation_clean\": " << json_num(r.other_clean)
              << ", \"validation_arrival\": " << json_num(r.other_arrival)
              << ", \"validation_R\": " << json_num(r.other_R)
              << ", \"validation_tau_c\": " << json_num(r.other_tau_c) << "}";
        }
        o << ", \"test\": [";
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

} // namespace

std::string summary_json(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt,
                         const std::string &env_file, double robot_radius_m, const HeldOut &H)
{
    std::ostringstream o;
    o << "{\n  \"name\": " << json_str(spec.name) << ",\n  \"title\": " << json_str(spec.title)
      << ",\n  \"figure\": " << json_str(spec.figure) << ",\n  \"preset\": " << json_str(opt.preset)
      << ",\n  \"runs\": " << spec.runs << ",\n  \"episodes\": " << spec.target_episodes
      << ",\n  \"eval_episodes\": " << spec.eval_episodes << ",\n  \"curve_bin\": " << spec.curve_bin
      << ",\n  \"episodes_per_candidate\": " << S.k
      << ",\n  \"algorithm\": " << json_str(algorithm_name(spec.evolution.algorithm)) << ",\n  \"fitness\": "
      << json_str(qnav_sim_fitness_rule_name(spec.target.fitness))
      << ",\n  \"controller\": " << json_str(controller_reading_name(spec.target.controller))
      << ",\n  \"arrival_threshold\": " << json_num(S.arrival_threshold)
      << ",\n  \"checkpoint_episodes\": " << S.checkpoint_episodes
      << ",\n  \"environment_file\": " << json_str(env_file) << ",\n  \"robot_radius_m\": " << json_num(robot_radius_m)
      << ",\n  \"target\": " << json_str(spec.target.describe()) << ",\n  \"sources\": [";
    for (std::size_t i = 0; i < spec.sources.size(); ++i) {
        const SourceSpec &s = spec.sources[i];
        o << (i ? ", " : "") << "{\"label\": " << json_str(s.label) << ", \"scenario\": "
          << json_str(s.describe()) << ", \"episodes\": " << (s.evolved() ? s.episodes : 0) << "}";
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

namespace {

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
         "(new start points), with the target's "
      << (spec.target.held_out_robot.empty() ? "robot" : "held-out robot " + spec.target.held_out_robot)
      << ", sectors and noise; the same episodes in every experiment. "
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
        o << "## Recommended policy\n\n`recommended.policy` = "
          << (r.reference() ? "the " + r.condition + " policy" : r.condition + " run " + std::to_string(r.run))
          << ": of every run's best policy of every evolved condition and the robot's probabilistic policy, the "
             "one that arrived without touching anything in the most of the "
          << r.validation_episodes << " validation episodes (worlds seeded from " << kValidationSeedBase
          << ", disjoint from training and test; never training scores; ties by arrival, then by fewer "
             "recovery ticks; the probabilistic policy kept unless an evolved run is ahead by these, and "
             "evolved runs level by them ranked by R): "
          << fmt(100.0 * r.validation_clean, 1) << "% (arrival " << fmt(100.0 * r.validation_arrival, 1)
          << "%, recovery ticks " << fmt(r.validation_tau_c) << " an episode), R " << fmt(r.validation_R);
        if (r.has_other) {
            o << " (" << (r.other_run == 0 ? "the " + r.other_condition + " policy"
                                           : "the best evolved, " + r.other_condition + " run " + std::to_string(r.other_run))
              << ": " << fmt(100.0 * r.other_clean, 1) << "% (arrival " << fmt(100.0 * r.other_arrival, 1)
              << "%, recovery ticks " << fmt(r.other_tau_c) << " an episode), R " << fmt(r.other_R) << ")";
        }
        o << ". Its test figures (95% CI over its episodes):\n\n"
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

} // namespace

namespace {
/* The search and its settings, as the summary's first paragraph names them. */
std::string search_md(const EvolutionParams &e)
{
    if (e.algorithm == EvolutionParams::Algorithm::Es) {
        return "evolution strategy (" + std::to_string(e.es_pairs) + " antithetic pairs an iteration, sigma " +
               fmt(e.es_sigma, 3) + ", Adam step " + fmt(e.es_step, 3) + ")";
    }
    return "epsilon-greedy evolution (population " + std::to_string(e.population) + ", epsilon " + fmt(e.epsilon, 2) + ")";
}
} // namespace

std::string summary_md(const ExperimentSpec &spec, const ExperimentSummary &S, const RunOptions &opt, bool plots,
                       const HeldOut &H)
{
    std::ostringstream o;
    o << "# " << spec.name << (spec.figure.empty() ? "" : " (paper " + spec.figure + ")") << "\n\n"
      << spec.title << "\n\n"
      << "Preset `" << opt.preset << "`: " << spec.runs << " runs, " << spec.target_episodes
      << " target episodes per run (" << S.k << " per candidate), fitness rule `"
      << qnav_sim_fitness_rule_name(spec.target.fitness) << "`, controller `"
      << controller_reading_name(spec.target.controller) << "`, " << search_md(spec.evolution) << ", "
      << spec.evolution.hidden << " hidden units; final performance = each run's best policy over "
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
          << (s.evolved() ? s.describe() + ", " + std::to_string(s.episodes) + " episodes" : s.describe())
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
      << (spec.evolution.algorithm == EvolutionParams::Algorithm::Es
              ? "Best fitness = the evolution strategy's centre's R on its last iteration's k episodes (best.policy is that centre), mean over runs. "
              : "Best fitness = the population's best member's fitness (mean R of its episodes; biased upwards by selection), mean over runs. ")
      << "Online R = mean R of all candidates of a run (the area under its learning curve; higher = learns faster and better). "
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

} // namespace qnav
