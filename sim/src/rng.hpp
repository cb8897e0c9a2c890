// The simulator's random numbers: a small seeded generator (xoshiro256**, seeded through
// splitmix64) with our own uniform and normal draws, so that the same seed gives the same
// episode on every standard library (std::normal_distribution is implementation-defined).
// An episode uses independent streams for start, sensing and actuation, derived from
// (context seed, episode seed, stream), so a change of noise level on one side does not
// shift the random sequence of the other.
#pragma once

#include <cmath>
#include <cstdint>

namespace qnav {

inline std::uint64_t splitmix64(std::uint64_t &state) {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// Named apart from simevo's qnav::Rng (host/simevo/src/rng.h): both end up in one binary,
// and two classes of one name there would be one class to the linker.
class SimRng {
public:
    SimRng() { seed(0, 0, 0); }
    // Seed from the context seed, the episode seed and a stream number.
    void seed(std::uint64_t context, std::uint64_t episode, std::uint64_t stream) {
        std::uint64_t sm = context;
        std::uint64_t mix = splitmix64(sm) ^ (episode * 0xD1B54A32D192ED03ull);
        std::uint64_t sm2 = mix;
        std::uint64_t mix2 = splitmix64(sm2) ^ (stream * 0x8CB92BA72F3D8DD7ull);
        for (auto &w : s_) w = splitmix64(mix2);
        has_spare_ = false;
    }
    std::uint64_t next_u64() {
        const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
        const std::uint64_t t = s_[1] << 17;
        s_[2] ^= s_[0];
        s_[3] ^= s_[1];
        s_[1] ^= s_[2];
        s_[0] ^= s_[3];
        s_[2] ^= t;
        s_[3] = rotl(s_[3], 45);
        return result;
    }
    // Uniform in [0, 1), 53 random bits.
    double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
    // Uniform in [lo, hi).
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    // Standard normal N(0, 1), Marsaglia's polar method (two values per acceptance).
    double normal() {
        if (has_spare_) {
            has_spare_ = false;
            return spare_;
        }
        double u, v, s;
        do {
            u = 2.0 * uniform() - 1.0;
            v = 2.0 * uniform() - 1.0;
            s = u * u + v * v;
        } while (s >= 1.0 || s == 0.0);
        const double m = std::sqrt(-2.0 * std::log(s) / s);
        spare_ = v * m;
        has_spare_ = true;
        return u * m;
    }

private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t s_[4];
    double spare_ = 0.0;
    bool has_spare_ = false;
};

}  // namespace qnav
