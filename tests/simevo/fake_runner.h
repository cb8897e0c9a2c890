/*
 * A fake episode runner for simevo's tests: R rises as a network's weights approach a
 * fixed target vector, plus a small deterministic "episode noise" from the episode seed.
 * Cheap and deterministic, so evolution logic is tested without the simulator.
 */
#ifndef QNAV_TEST_FAKE_RUNNER_H
#define QNAV_TEST_FAKE_RUNNER_H

#include <atomic>
#include <cmath>

#include "evolution.h"
#include "rng.h"

namespace qnav {

class FakeRunner : public EpisodeRunner {
public:
    explicit FakeRunner(double noise = 0.01) : noise_(noise) {}
    EpisodeOutcome run(const qnav_policy_t &policy, uint64_t episode_seed) override
    {
        ++calls;
        switch (static_cast<qnav_policy_kind_t>(policy.kind)) {
        case QNAV_POLICY_PROB: { // the probabilistic policy: a fixed score
            Rng r(episode_seed);
            EpisodeOutcome o;
            o.R = -20.0 + (r.uniform01() - 0.5);
            return o;
        }
        case QNAV_POLICY_NET:
            break;
        }
        qnav_net_t net = policy.u.net;
        double d2 = 0.0;
        for (uint16_t k = 0; k < QNAV_NET_WEIGHTS(net.hidden); ++k) {
            const double w = *qnav_net_weight(&net, k) / 256.0;
            const double target = (k % 3 == 0) ? 2.0 : -1.0;
            d2 += (w - target) * (w - target);
        }
        Rng r(episode_seed);
        EpisodeOutcome o;
        o.R = -std::sqrt(d2) + noise_ * (r.uniform01() - 0.5);
        o.f1 = 1.0 / (1.0 + d2);
        o.f2 = 0.5;
        o.tau_c = static_cast<uint32_t>(d2) % 7u;
        o.reached = d2 < 4.0;
        return o;
    }
    EpisodeOutcome run_controller(const char *, uint64_t episode_seed) override
    {
        ++calls; // a policy-free reference (VFH+): a fixed score, like the probabilistic one
        Rng r(episode_seed ^ 0x5646u);
        EpisodeOutcome o;
        o.R = -25.0 + (r.uniform01() - 0.5);
        o.reached = r.uniform01() < 0.5;
        return o;
    }
    std::atomic<long> calls{0};

private:
    double noise_;
};

} // namespace qnav

#endif
