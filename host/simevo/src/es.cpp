/*
 * The evolution strategy of es.h, and make_search().
 */
#include "es.h"

#include <cmath>
#include <limits>

namespace qnav {

namespace {
constexpr double kAdamBeta1 = 0.9;
constexpr double kAdamBeta2 = 0.999;
constexpr double kAdamEps = 1e-8;
} // namespace

EvolutionStrategy::EvolutionStrategy(const EvolutionParams &params, uint64_t seed)
    : params_(params), rng_(seed), R_(search_round_steps(params)),
      centre_R_(-std::numeric_limits<double>::infinity())
{
    qnav_policy_t start;
    random_network(start, params_, rng_);
    start_at(start);
}

EvolutionStrategy::EvolutionStrategy(const EvolutionParams &params, uint64_t seed, const qnav_policy_t &source)
    : EvolutionStrategy(params, seed)
{
    start_at(source); // the random draw above is discarded, as Evolution's transfer does
}

void EvolutionStrategy::start_at(const qnav_policy_t &start)
{
    centre_ = start;
    const uint16_t n = qnav_net_weight_count(&centre_.u.net);
    theta_.resize(n);
    for (uint16_t k = 0; k < n; ++k) {
        theta_[k] = static_cast<double>(*qnav_net_weight(&centre_.u.net, k)) / QNAV_Q8_8_ONE;
    }
    adam_m_.assign(n, 0.0);
    adam_v_.assign(n, 0.0);
}

void EvolutionStrategy::round_into(qnav_policy_t &p, const std::vector<double> &w) const
{
    p = centre_;
    for (uint16_t k = 0; k < w.size(); ++k) {
        *qnav_net_weight(&p.u.net, k) = weight_to_q8_8(w[k]);
    }
}

Candidate EvolutionStrategy::propose()
{
    const uint64_t round = search_round_steps(params_);
    const uint64_t i = step_ % round;
    const std::size_t n = theta_.size();
    if (i == 0 && !pending_) {
        eps_.resize(params_.es_pairs * n);
        for (double &e : eps_) {
            e = rng_.normal();
        }
    }
    Candidate c;
    c.episode = step_;
    if (i == 0) {
        c.policy = centre_;
    } else {
        const std::size_t pair = static_cast<std::size_t>((i - 1) / 2);
        const double sign = (i - 1) % 2 == 0 ? 1.0 : -1.0;
        std::vector<double> w(theta_);
        for (std::size_t k = 0; k < n; ++k) {
            w[k] += sign * params_.es_sigma * eps_[pair * n + k];
        }
        round_into(c.policy, w);
    }
    pending_ = true;
    return c;
}

void EvolutionStrategy::accept(const Candidate &c, const EpisodeOutcome &out, const EpisodeOutcome *)
{
    if (!pending_ || c.episode != step_) {
        return;
    }
    pending_ = false;
    const uint64_t i = step_ % search_round_steps(params_);
    R_[static_cast<std::size_t>(i)] = out.R;
    if (i == 0) {
        centre_R_ = out.R;
    }
    ++step_;
    if (i + 1 == search_round_steps(params_)) {
        update();
    }
}

void EvolutionStrategy::update()
{
    const std::size_t n = theta_.size();
    const uint32_t P = params_.es_pairs;
    ++iteration_;
    const double b1t = 1.0 - std::pow(kAdamBeta1, static_cast<double>(iteration_));
    const double b2t = 1.0 - std::pow(kAdamBeta2, static_cast<double>(iteration_));
    for (std::size_t k = 0; k < n; ++k) {
        double g = 0.0;
        for (uint32_t j = 0; j < P; ++j) {
            g += (R_[1 + 2 * j] - R_[2 + 2 * j]) * eps_[j * n + k];
        }
        g /= 2.0 * P * params_.es_sigma;
        adam_m_[k] = kAdamBeta1 * adam_m_[k] + (1.0 - kAdamBeta1) * g;
        adam_v_[k] = kAdamBeta2 * adam_v_[k] + (1.0 - kAdamBeta2) * g * g;
        theta_[k] += params_.es_step * (adam_m_[k] / b1t) / (std::sqrt(adam_v_[k] / b2t) + kAdamEps);
    }
    round_into(centre_, theta_);
}

std::unique_ptr<Search> make_search(const EvolutionParams &params, uint64_t seed, const qnav_policy_t *source)
{
    switch (params.algorithm) {
    case EvolutionParams::Algorithm::Es:
        return source != nullptr ? std::make_unique<EvolutionStrategy>(params, seed, *source)
                                 : std::make_unique<EvolutionStrategy>(params, seed);
    case EvolutionParams::Algorithm::EpsilonGreedy:
        break;
    }
    return source != nullptr ? std::make_unique<Evolution>(params, seed, *source)
                             : std::make_unique<Evolution>(params, seed);
}

} // namespace qnav
