/*
 * What an experiment runs: the conditions it compares (declared once, kConditions) and
 * its task plan (per run: source evolutions, the transfers seeded from them, direct
 * evolution; once: the reference task), every seed derived from the spec's by label.
 */
#include "experiment.h"

#include <cstdio>
#include <set>

#include "files.h"
#include "rng.h"

namespace qnav {

namespace {

uint64_t label_hash(const std::string &s) { return fnv1a64(s.data(), s.size()); }

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

std::string fitted_source_path(const std::string &exp_dir, const SourceSpec &s)
{
    return join_path(exp_dir, "source-" + s.label + ".policy");
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
            if (s.evolved()) {
                const std::string label = "source-" + s.label;
                tasks.push_back(evolve(label, s.scenario, s.episodes,
                                       mix_seed(run_seed, label_hash("episodes:" + label))));
                src_index = static_cast<int>(tasks.size() - 1);
            }
            TaskDef tr = evolve(condition_label(ConditionKind::Transfer, s.label), spec.target, spec.target_episodes, target_episodes_base);
            tr.source_task = src_index;
            tr.source_policy_file = s.fit.empty() ? s.policy_file : fitted_source_path(exp_dir, s);
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

constexpr ConditionDecl kConditions[kConditionCount] = {
    {ConditionKind::Transfer, "transfer-", true, nullptr},
    {ConditionKind::Direct, "direct", true, nullptr},
    {ConditionKind::Probabilistic, kReferences[0].label, false, &kReferences[0]},
    {ConditionKind::Vfh, kReferences[1].label, false, &kReferences[1]},
};

/* The reference conditions are kReferences, row for row and in its order, none evolved:
 * a row added to kReferences without its ConditionKind and its row above fails here. */
constexpr bool conditions_follow_the_reference_table()
{
    std::size_t next = 0;
    for (const ConditionDecl &d : kConditions) {
        if (d.reference == nullptr) {
            continue;
        }
        if (next >= kReferenceCount || d.reference != &kReferences[next] || d.evolved) {
            return false;
        }
        ++next;
    }
    return next == kReferenceCount;
}
static_assert(conditions_follow_the_reference_table(),
              "every row of kReferences (task.h) needs a ConditionKind (experiment.h) and a "
              "kConditions row pointing at it, in the same order");

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

} // namespace qnav
