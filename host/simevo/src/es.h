/*
 * An evolution strategy over network policies (docs/simevo.md, "Two searches"): a centre
 * θ of real-valued weights; each iteration draws es_pairs Gaussian directions ε, scores
 * the networks θ + σε and θ − σε and θ itself on the same k episodes (the task runs every
 * step of an iteration on one episode set), and moves θ along Σ (R⁺ − R⁻) ε / (2 P σ)
 * with Adam. Candidates are θ ± σε rounded to Q8.8 as a board runs them; θ stays real
 * so that steps smaller than a Q8.8 unit accumulate. Deterministic given the seed and the
 * outcomes, like Evolution, so a journal replays.
 */
#ifndef QNAV_SIMEVO_ES_H
#define QNAV_SIMEVO_ES_H

#include <vector>

#include "evolution.h"

namespace qnav {

class EvolutionStrategy : public Search {
public:
    /* From one random network drawn as Evolution draws its initial members. */
    EvolutionStrategy(const EvolutionParams &params, uint64_t seed);
    /* Transfer: θ starts at source's weights. */
    EvolutionStrategy(const EvolutionParams &params, uint64_t seed, const qnav_policy_t &source);

    /* Step i of an iteration: i = 0 the centre, then θ + σε_j and θ − σε_j in turn. */
    Candidate propose() override;
    void accept(const Candidate &c, const EpisodeOutcome &out, const EpisodeOutcome *parent_out) override;
    uint64_t episodes_done() const override { return step_; }
    /* The current centre, rounded. */
    const qnav_policy_t &best_policy() const override { return centre_; }
    /* The centre's R in its latest iteration (its own k episodes; -inf before). */
    double best_fitness() const override { return centre_R_; }
    double best_so_far() const override { return centre_R_; }
    const qnav_policy_t &member_policy(int32_t) const override { return centre_; }

private:
    void start_at(const qnav_policy_t &start);
    void round_into(qnav_policy_t &p, const std::vector<double> &w) const;
    void update();

    EvolutionParams params_;
    Rng rng_;
    qnav_policy_t centre_{};     /* shape, and θ rounded */
    std::vector<double> theta_;  /* weight units */
    std::vector<double> eps_;    /* es_pairs × n directions of the current iteration */
    std::vector<double> R_;      /* outcomes of the iteration's steps */
    std::vector<double> adam_m_, adam_v_;
    uint64_t step_ = 0;
    uint64_t iteration_ = 0;
    bool pending_ = false;
    double centre_R_;
};

} // namespace qnav

#endif
