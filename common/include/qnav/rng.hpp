// qnav::Rng, the one random-number generator of the simulator and simevo: qnav/rng.h's
// xoshiro256** with our own samplers, so that a seed gives the same draws on every
// standard library (std::normal_distribution and the others are implementation-defined).
// The simulator draws uniforms and normals on independent streams (stream()); simevo
// draws uniforms, unbiased integers and clipped Cauchy mutations from one seed.
#pragma once

#include <cmath>
#include <cstdint>

#include "qnav/rng.h"

namespace qnav {

class Rng {
public:
    // The sequence of `seed` (the state is four splitmix64 outputs from it).
    explicit Rng(std::uint64_t seed = 0) { qnav_xoshiro256ss_seed(&g_, seed); }

    // Stream number `which` of episode `episode` under context seed `context`: the
    // simulator draws an episode's start, sensing and actuation from streams 1, 2 and 3, so
    // a change of noise on one side does not shift the draws of another.
    static Rng stream(std::uint64_t context, std::uint64_t episode, std::uint64_t which) {
        std::uint64_t sm = context;
        std::uint64_t mix = qnav_splitmix64(&sm) ^ (episode * 0xD1B54A32D192ED03ull);
        const std::uint64_t mix2 = qnav_splitmix64(&mix) ^ (which * 0x8CB92BA72F3D8DD7ull);
        return Rng(mix2);
    }

    std::uint64_t next_u64() { return qnav_xoshiro256ss_next(&g_); }

    // Uniform in [0, 1), 53 random bits.
    double uniform01() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }

    // Uniform in [lo, hi).
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(); }

    // Uniform in (0, 1), never 0 or 1: (k + 0.5) / 2^53 for k in 0..2^53-1, symmetric
    // about 1/2.
    double uniform_open() { return (static_cast<double>(next_u64() >> 11) + 0.5) * 0x1.0p-53; }

    // Uniform integer in 0..n-1 (n >= 1), unbiased: Lemire-style rejection on the top 32
    // bits.
    std::uint32_t below(std::uint32_t n) {
        if (n <= 1) return 0;
        const std::uint32_t threshold = static_cast<std::uint32_t>(-n) % n;
        for (;;) {
            const std::uint64_t m = (next_u64() >> 32) * static_cast<std::uint64_t>(n);
            if (static_cast<std::uint32_t>(m) >= threshold) return static_cast<std::uint32_t>(m >> 32);
        }
    }

    // Standard normal N(0, 1), Marsaglia's polar method (two values per acceptance).
    double normal() {
        if (has_spare_) {
            has_spare_ = false;
            return spare_;
        }
        double u, v, s;
        do {
            u = 2.0 * uniform01() - 1.0;
            v = 2.0 * uniform01() - 1.0;
            s = u * u + v * v;
        } while (s >= 1.0 || s == 0.0);
        const double m = std::sqrt(-2.0 * std::log(s) / s);
        spare_ = v * m;
        has_spare_ = true;
        return u * m;
    }

    // scale * tan(pi (u - 1/2)) for u uniform in (0, 1): a Cauchy sample with location 0
    // and scale `scale`, clipped to [-clip, clip] (simevo's mutations, paper §3.3).
    double cauchy_clipped(double scale, double clip) {
        const double x = scale * std::tan(kPi_ * (uniform_open() - 0.5));
        return x > clip ? clip : x < -clip ? -clip : x;
    }

private:
    static constexpr double kPi_ = 3.14159265358979323846;
    qnav_xoshiro256ss_t g_;
    double spare_ = 0.0;
    bool has_spare_ = false;
};

}  // namespace qnav
