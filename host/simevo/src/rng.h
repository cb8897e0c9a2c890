/*
 * simevo's own random numbers, so that an evolution run depends only on its seed and this
 * code, never on the C++ library's distributions: xoshiro256** seeded through splitmix64,
 * unbiased integers below n, uniform doubles, and the clipped Cauchy samples that
 * mutation adds to network weights (paper §3.3).
 */
#ifndef QNAV_SIMEVO_RNG_H
#define QNAV_SIMEVO_RNG_H

#include <array>
#include <cstdint>

namespace qnav {

/* splitmix64 finaliser of (a, b): derives independent stream seeds from a parent seed and
 * a label (run index, condition, episode number). */
uint64_t mix_seed(uint64_t a, uint64_t b);

/* 64-bit FNV-1a of a byte string (fingerprints, labels to seeds). */
uint64_t fnv1a64(const void *data, std::size_t len, uint64_t h = 1469598103934665603ull);

class Rng {
public:
    explicit Rng(uint64_t seed);

    uint64_t next_u64();
    /* Uniform in [0, 1), 53 random bits. */
    double uniform01();
    /* Uniform in (0, 1): never 0, never 1. */
    double uniform_open();
    /* Uniform integer in 0..n-1 (n >= 1), unbiased (rejection). */
    uint32_t below(uint32_t n);
    /* scale * tan(pi (u - 1/2)) for u uniform in (0, 1): a Cauchy sample with location 0
     * and scale `scale`, then clipped to [-clip, clip]. */
    double cauchy_clipped(double scale, double clip);

    std::array<uint64_t, 4> state() const { return s_; }

private:
    std::array<uint64_t, 4> s_;
};

} // namespace qnav

#endif
