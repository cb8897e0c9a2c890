/*
 * The ε-greedy evolutionary algorithm of paper Fig. 4 and its mutation operator.
 */
#include "evolution.h"

#include <cmath>
#include <limits>

/* The value of a macro as a string literal (QNAV_MAX_HIDDEN can be set with -D). */
#define QNAV_SIMEVO_STR_(x) #x
#define QNAV_SIMEVO_STR(x) QNAV_SIMEVO_STR_(x)

namespace qnav {

const char *evolution_params_problem(const EvolutionParams &p)
{
    if (p.population < 2 || p.population > 100000) {
        return "population: must be 2..100000";
    }
    if (!(p.epsilon >= 0.0 && p.epsilon <= 1.0)) {
        return "epsilon: must be in [0, 1]";
    }
    if (p.hidden < 1 || p.hidden > QNAV_MAX_HIDDEN) {
        return "hidden: must be 1.." QNAV_SIMEVO_STR(QNAV_MAX_HIDDEN) " (QNAV_MAX_HIDDEN)";
    }
    if (p.inputs != QNAV_NET_INPUTS_PAPER && p.inputs != QNAV_NET_INPUTS_PREV) {
        return "inputs: must be 2 or 3";
    }
    if (!(p.mutation_scale > 0.0 && p.mutation_scale <= 128.0)) {
        return "mutation_scale: must be in (0, 128]";
    }
    if (!(p.mutation_clip > 0.0 && p.mutation_clip <= 256.0)) {
        return "mutation_clip: must be in (0, 256]";
    }
    if (p.episodes_per_candidate < 1 || p.episodes_per_candidate > 1000) {
        return "episodes_per_candidate: must be 1..1000";
    }
    if (!(p.init_scale > 0.0 && p.init_scale <= 128.0)) {
        return "init_scale: must be in (0, 128]";
    }
    if (p.es_pairs < 1 || p.es_pairs > 10000) {
        return "es_pairs: must be 1..10000";
    }
    if (!(p.es_sigma > 0.0 && p.es_sigma <= 16.0)) {
        return "es_sigma: must be in (0, 16]";
    }
    if (!(p.es_step > 0.0 && p.es_step <= 16.0)) {
        return "es_step: must be in (0, 16]";
    }
    return "";
}

const char *init_kind_name(InitKind k)
{
    switch (k) {
    case InitKind::Cauchy:
        return "cauchy";
    case InitKind::Uniform:
        return "uniform";
    }
    return "cauchy";
}

const char *algorithm_name(EvolutionParams::Algorithm a)
{
    switch (a) {
    case EvolutionParams::Algorithm::EpsilonGreedy:
        return "epsilon-greedy";
    case EvolutionParams::Algorithm::Es:
        return "es";
    }
    return "epsilon-greedy";
}

uint64_t search_round_steps(const EvolutionParams &p)
{
    return p.algorithm == EvolutionParams::Algorithm::Es ? 2ull * p.es_pairs + 1 : 1;
}

const char *world_sets_name(EvolutionParams::WorldSets w)
{
    switch (w) {
    case EvolutionParams::WorldSets::PerStep:
        return "per-step";
    case EvolutionParams::WorldSets::PerGeneration:
        return "per-generation";
    }
    return "per-step";
}

namespace {
qnav_q8_8_t to_q8_8_saturated(double raw)
{
    const double r = std::round(raw); // half away from zero
    if (r >= static_cast<double>(QNAV_Q8_8_MAX)) {
        return QNAV_Q8_8_MAX;
    }
    if (r <= static_cast<double>(QNAV_Q8_8_MIN)) {
        return QNAV_Q8_8_MIN;
    }
    return static_cast<qnav_q8_8_t>(r);
}

uint16_t weight_count(const qnav_net_t &net) { return qnav_net_weight_count(&net); }
} // namespace

void mutate_network(qnav_net_t &net, Rng &rng, double scale, double clip)
{
    const uint16_t n = weight_count(net);
    for (uint16_t k = 0; k < n; ++k) {
        qnav_q8_8_t *w = qnav_net_weight(&net, k);
        const double delta = rng.cauchy_clipped(scale, clip);
        *w = to_q8_8_saturated(static_cast<double>(*w) + delta * QNAV_Q8_8_ONE);
    }
}

uint32_t policy_fingerprint(const qnav_policy_t &policy)
{
    uint64_t h = fnv1a64(&policy.kind, 1);
    switch (static_cast<qnav_policy_kind_t>(policy.kind)) {
    case QNAV_POLICY_NET: {
        qnav_net_t net = policy.u.net;
        h = fnv1a64(&net.hidden, 1, h);
        if (net.inputs != QNAV_NET_INPUTS_PAPER) {
            h = fnv1a64(&net.inputs, 1, h); /* 2-input fingerprints stay as they were */
        }
        const uint16_t n = weight_count(net);
        for (uint16_t k = 0; k < n; ++k) {
            const int16_t w = *qnav_net_weight(&net, k);
            const unsigned char b[2] = {static_cast<unsigned char>(w & 0xff),
                                        static_cast<unsigned char>((w >> 8) & 0xff)};
            h = fnv1a64(b, 2, h);
        }
        break;
    }
    case QNAV_POLICY_PROB: {
        const int16_t p[2] = {policy.u.prob.k_goal, policy.u.prob.k_safe};
        h = fnv1a64(p, sizeof p, h);
        break;
    }
    }
    return static_cast<uint32_t>(h ^ (h >> 32));
}

void random_network(qnav_policy_t &policy, const EvolutionParams &params, Rng &rng)
{
    qnav_policy_net_zero_inputs(&policy, static_cast<uint8_t>(params.hidden), static_cast<uint8_t>(params.inputs));
    qnav_net_t &net = policy.u.net;
    const uint16_t n = weight_count(net);
    for (uint16_t k = 0; k < n; ++k) {
        double x = 0.0;
        switch (params.init) {
        case InitKind::Cauchy:
            x = rng.cauchy_clipped(params.init_scale, params.mutation_clip);
            break;
        case InitKind::Uniform:
            x = (2.0 * rng.uniform01() - 1.0) * params.init_scale;
            break;
        }
        *qnav_net_weight(&net, k) = to_q8_8_saturated(x * QNAV_Q8_8_ONE);
    }
}

qnav_q8_8_t weight_to_q8_8(double w) { return to_q8_8_saturated(w * QNAV_Q8_8_ONE); }

Evolution::Evolution(const EvolutionParams &params, uint64_t seed)
    : params_(params), rng_(seed), pop_(params.population),
      best_so_far_(-std::numeric_limits<double>::infinity())
{
    for (Member &m : pop_) {
        random_network(m.policy, params_, rng_);
    }
    init_order_.resize(pop_.size());
    for (uint32_t i = 0; i < init_order_.size(); ++i) {
        init_order_[i] = i;
    }
    for (uint32_t i = static_cast<uint32_t>(init_order_.size()); i > 1; --i) {
        const uint32_t j = rng_.below(i);
        std::swap(init_order_[i - 1], init_order_[j]);
    }
}

Evolution::Evolution(const EvolutionParams &params, uint64_t seed, const qnav_policy_t &source)
    : Evolution(params, seed)
{
    // The random members drawn above are discarded; the draws keep transfer and direct
    // runs on the same generator positions, which is harmless and keeps one code path.
    for (uint32_t i = 0; i < pop_.size(); ++i) {
        pop_[i].policy = source;
        if (i > 0) {
            mutate_network(pop_[i].policy.u.net, rng_, params_.mutation_scale,
                           params_.mutation_clip);
        }
    }
}

int32_t Evolution::best_index() const
{
    int32_t best = -1;
    for (uint32_t i = 0; i < pop_.size(); ++i) {
        if (pop_[i].evaluated && (best < 0 || pop_[i].fitness > pop_[static_cast<std::size_t>(best)].fitness)) {
            best = static_cast<int32_t>(i);
        }
    }
    return best;
}

int32_t Evolution::worst_index() const
{
    int32_t worst = -1;
    for (uint32_t i = 0; i < pop_.size(); ++i) {
        if (!pop_[i].evaluated) {
            return static_cast<int32_t>(i);
        }
        if (worst < 0 || pop_[i].fitness < pop_[static_cast<std::size_t>(worst)].fitness) {
            worst = static_cast<int32_t>(i);
        }
    }
    return worst;
}

Candidate Evolution::propose()
{
    Candidate c;
    c.episode = episode_;
    if (episode_ < init_order_.size()) {
        c.slot = static_cast<int32_t>(init_order_[episode_]);
        c.policy = pop_[init_order_[episode_]].policy;
    } else {
        // Fig. 4 step 1: both draws every time, so the stream does not depend on ε.
        const double u = rng_.uniform01();
        const uint32_t pick = rng_.below(static_cast<uint32_t>(pop_.size()));
        c.explored = u < params_.epsilon;
        c.parent = c.explored ? static_cast<int32_t>(pick) : best_index();
        c.policy = pop_[static_cast<std::size_t>(c.parent)].policy;
        mutate_network(c.policy.u.net, rng_, params_.mutation_scale, params_.mutation_clip);
        c.slot = -1; // decided in accept(): the worst member at that time
    }
    pending_ = true;
    return c;
}

void Evolution::accept(const Candidate &c, const EpisodeOutcome &out, const EpisodeOutcome *parent_out)
{
    if (!pending_ || c.episode != episode_) {
        return;
    }
    pending_ = false;
    if (parent_out != nullptr && c.parent >= 0) {
        Member &p = pop_[static_cast<std::size_t>(c.parent)];
        p.fitness = (p.fitness * p.evaluations + parent_out->R) / (p.evaluations + 1);
        ++p.evaluations;
    }
    Member &m = pop_[static_cast<std::size_t>(c.slot >= 0 ? c.slot : worst_index())];
    m.policy = c.policy;
    m.fitness = out.R;
    m.evaluations = 1;
    m.evaluated = true;
    best_so_far_ = pop_[static_cast<std::size_t>(best_index())].fitness;
    ++episode_;
}

} // namespace qnav
