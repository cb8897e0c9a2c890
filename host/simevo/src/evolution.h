/*
 * The ε-greedy steady-state neuro-evolution of paper Fig. 4, independent of any simulator:
 * a population of Q8.8 network policies; each episode picks a random member with
 * probability ε (else the best), adds a clipped Cauchy sample to every weight, runs one
 * episode through an EpisodeRunner, and the mutant replaces the worst member with its R
 * as fitness. Everything random comes from one seeded Rng, so the sequence of candidates
 * is a pure function of (parameters, seed, the R values returned): that is what lets a
 * run be resumed by replaying its episode log (docs/simevo.md, "Resuming").
 */
#ifndef QNAV_SIMEVO_EVOLUTION_H
#define QNAV_SIMEVO_EVOLUTION_H

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "qnav/policy.h"
#include "rng.h"

namespace qnav {

/* What one episode returned (paper Eq. 1-3). */
struct EpisodeOutcome {
    double R = 0.0;       /* fitness, Eq. 1 */
    double f1 = 0.0;      /* path-length feature, Eq. 2, (0, 1] */
    double f2 = 0.0;      /* time feature, Eq. 3, (0, 1] */
    uint32_t tau_c = 0;   /* ticks spent in collision recovery */
    bool reached = false; /* destination reached */
};

/* Runs one episode with a policy. Implementations: the Box2D simulator (SimRunner) and
 * fakes in tests. episode_seed alone fixes the episode's randomness. */
class EpisodeRunner {
public:
    virtual ~EpisodeRunner() = default;
    virtual EpisodeOutcome run(const qnav_policy_t &policy, uint64_t episode_seed) = 0;
    /* One episode driven by a policy-free controller of libqnav's table (qnav/nav.h),
     * e.g. "vfh" for the VFH+ reference. */
    virtual EpisodeOutcome run_controller(const char *controller, uint64_t episode_seed) = 0;
    /* The probabilistic policy to compare against: the one tuned for the runner's robot
     * (libqnav's defaults unless a runner knows better). */
    virtual qnav_policy_t probabilistic_policy() const
    {
        qnav_policy_t p;
        qnav_policy_prob_default(&p);
        return p;
    }
};

/* How the initial random population is drawn. */
enum class InitKind {
    Cauchy, /* every weight an independent clipped Cauchy sample (scale init_scale,
               clip mutation_clip): the mutation operator applied to the zero network */
    Uniform /* every weight uniform in [-init_scale, init_scale] */
};

struct EvolutionParams {
    uint32_t population = 40;      /* members, >= 2 */
    double epsilon = 0.1;          /* probability of mutating a random member, [0, 1] */
    uint32_t hidden = 12;          /* hidden units of new networks, 1..QNAV_MAX_HIDDEN */
    uint32_t inputs = 2;           /* network inputs: 2 (paper) or 3 (previous decision, §5) */
    double mutation_scale = 0.3;   /* Cauchy scale, weight units (assumed; paper: none) */
    double mutation_clip = 10.0;   /* Cauchy samples clipped to [-clip, clip] (paper) */
    uint32_t episodes_per_candidate = 1; /* episodes averaged into one fitness value (paper:
                                            1; assumed larger in docs/simevo.md) */
    bool reevaluate_parent = true;   /* each step also runs the parent for one episode and
                                        folds it into the parent's mean fitness (noisy
                                        fitness; docs/simevo.md, "Deviations") */
    InitKind init = InitKind::Cauchy;
    double init_scale = 1.0;       /* see InitKind, weight units */
    /* Which steps meet the same k episodes (worlds and start points): PerStep = each step
     * its own k, shared by the candidate and its re-evaluated parent (paired acceptance);
     * PerGeneration = every block of `population` steps the same k (one world set per
     * generation). docs/simevo.md, "Distributions of worlds". */
    enum class WorldSets { PerStep, PerGeneration } world_sets = WorldSets::PerStep;
    /* The search: the paper's ε-greedy evolution (the fields above), or an evolution
     * strategy (es.h; population, epsilon, the mutation and world_sets do not apply; every
     * iteration scores its 2 * es_pairs + 1 networks on one common set of k episodes).
     * docs/simevo.md, "Two searches". */
    enum class Algorithm { EpsilonGreedy, Es } algorithm = Algorithm::EpsilonGreedy;
    uint32_t es_pairs = 16; /* antithetic perturbation pairs per iteration */
    double es_sigma = 0.1;  /* perturbation SD, weight units */
    double es_step = 0.02;  /* Adam step, weight units */
};

/* "epsilon-greedy", "es" (experiment files and task settings spell them so). */
const char *algorithm_name(EvolutionParams::Algorithm a);

/* Steps of one round of the search that share their k episodes and whose results are used
 * together: 2 * es_pairs + 1 for the evolution strategy, 1 for ε-greedy evolution. */
uint64_t search_round_steps(const EvolutionParams &p);

/* "cauchy", "uniform" (experiment files and task settings spell them so). */
const char *init_kind_name(InitKind k);
/* "per-step", "per-generation". */
const char *world_sets_name(EvolutionParams::WorldSets w);

/* Returns "" when p is valid, else "FIELD: problem". */
const char *evolution_params_problem(const EvolutionParams &p);

/* Add a clipped Cauchy sample (scale, clip in weight units) to every weight of net, round
 * to the nearest Q8.8 step (half away from zero) and saturate to [-128, 128 - 1/256]. */
void mutate_network(qnav_net_t &net, Rng &rng, double scale, double clip);

/* One random network of params' shape, drawn as params.init says (an initial member). */
void random_network(qnav_policy_t &policy, const EvolutionParams &params, Rng &rng);

/* A weight in weight units rounded to the nearest Q8.8 step (half away from zero), saturated. */
qnav_q8_8_t weight_to_q8_8(double w);

/* 32-bit fingerprint of a network's shape and weights (journal check). */
uint32_t policy_fingerprint(const qnav_policy_t &policy);

struct Member {
    qnav_policy_t policy{};
    double fitness = 0.0;   /* mean R of the episodes it was scored on */
    uint32_t evaluations = 0; /* episodes behind fitness */
    bool evaluated = false; /* false until its first episode */
};

/* The candidate for one episode. */
struct Candidate {
    uint64_t episode = 0;   /* 0-based episode index in this evolution */
    qnav_policy_t policy{}; /* the network to run */
    int32_t parent = -1;    /* member mutated to make it; -1 in the initial evaluation */
    bool explored = false;  /* the parent was the random pick (probability ε) */
    int32_t slot = -1;      /* member the result is stored in */
};

/* A search over network policies: proposes a candidate, is told its outcome, and knows the
 * policy it would hand out now. Everything random comes from its seed, so a run resumes
 * by replaying the journal's outcomes through propose()/accept(). */
class Search {
public:
    virtual ~Search() = default;
    virtual Candidate propose() = 0;
    /* Record the candidate's outcome (must follow the matching propose()). parent_out,
     * when not null, is the re-evaluation of candidate's parent member. */
    virtual void accept(const Candidate &c, const EpisodeOutcome &out, const EpisodeOutcome *parent_out) = 0;
    /* Steps (candidates scored) so far. */
    virtual uint64_t episodes_done() const = 0;
    /* The policy this search recommends now (best.policy, checkpoints) and its fitness. */
    virtual const qnav_policy_t &best_policy() const = 0;
    virtual double best_fitness() const = 0;
    /* The fitness reported in the journal's best_fitness column (-inf before any). */
    virtual double best_so_far() const = 0;
    /* The policy of member i (a parent to re-evaluate). */
    virtual const qnav_policy_t &member_policy(int32_t i) const = 0;
};

/* The search that params.algorithm names, from a random start or from source (transfer). */
std::unique_ptr<Search> make_search(const EvolutionParams &params, uint64_t seed,
                                    const qnav_policy_t *source);

class Evolution : public Search {
public:
    /* Random initial population (see InitKind). */
    Evolution(const EvolutionParams &params, uint64_t seed);
    /* Transfer (paper §4): member 0 is `source`, the others mutants of it. */
    Evolution(const EvolutionParams &params, uint64_t seed, const qnav_policy_t &source);

    /*
     * The next candidate. The first population-size episodes score the initial members
     * once each, in a random order (so the first episode runs a random member); after
     * that, Fig. 4: with probability ε a random member else the best, mutated; the
     * result replaces the worst member.
     */
    Candidate propose() override;
    /* parent_out: the re-evaluation of the parent (reevaluate_parent). */
    void accept(const Candidate &c, const EpisodeOutcome &out,
                const EpisodeOutcome *parent_out = nullptr) override;

    uint64_t episodes_done() const override { return episode_; }
    /* Before any evaluation: member 0. */
    const qnav_policy_t &best_policy() const override { return pop_[best_or_first()].policy; }
    double best_fitness() const override { return pop_[best_or_first()].fitness; }
    const qnav_policy_t &member_policy(int32_t i) const override { return pop_[static_cast<std::size_t>(i)].policy; }
    /* Index of the best evaluated member (ties: lowest index); -1 if none evaluated. */
    int32_t best_index() const;
    /* Index of the member to replace: an unevaluated one first, else the lowest fitness
     * (ties: lowest index). */
    int32_t worst_index() const;
    const std::vector<Member> &members() const { return pop_; }
    /* Fitness of the best member after the last accept() (-inf before any). */
    double best_so_far() const override { return best_so_far_; }
    const EvolutionParams &params() const { return params_; }

private:
    std::size_t best_or_first() const { return static_cast<std::size_t>(std::max<int32_t>(0, best_index())); }

    EvolutionParams params_;
    Rng rng_;
    std::vector<Member> pop_;
    std::vector<uint32_t> init_order_;
    uint64_t episode_ = 0;
    bool pending_ = false;
    double best_so_far_;
};

} // namespace qnav

#endif
