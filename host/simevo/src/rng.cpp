/*
 * xoshiro256** (Blackman & Vigna's published algorithm, written here from its
 * description) with splitmix64 seeding, and the samplers simevo needs on top of it.
 */
#include "rng.h"

#include <cmath>

namespace qnav {

namespace {
uint64_t splitmix64(uint64_t &x)
{
    x += 0x9e3779b97f4a7c15ull;
    uint64_t z = x;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}
uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
constexpr double kPi = 3.14159265358979323846;
} // namespace

uint64_t mix_seed(uint64_t a, uint64_t b)
{
    uint64_t x = a ^ rotl(b, 29) ^ 0x5851f42d4c957f2dull;
    splitmix64(x);
    x ^= b;
    return splitmix64(x);
}

uint64_t fnv1a64(const void *data, std::size_t len, uint64_t h)
{
    const unsigned char *p = static_cast<const unsigned char *>(data);
    for (std::size_t i = 0; i < len; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

Rng::Rng(uint64_t seed)
{
    uint64_t x = seed;
    for (auto &w : s_) {
        w = splitmix64(x);
    }
}

uint64_t Rng::next_u64()
{
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
}

double Rng::uniform01() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }

double Rng::uniform_open()
{
    // (k + 0.5) / 2^53 for k in 0..2^53-1: symmetric about 1/2, never 0 or 1.
    return (static_cast<double>(next_u64() >> 11) + 0.5) * 0x1.0p-53;
}

uint32_t Rng::below(uint32_t n)
{
    if (n <= 1) {
        return 0;
    }
    // Lemire-style rejection on the top 32 bits: unbiased.
    const uint32_t threshold = static_cast<uint32_t>(-n) % n;
    for (;;) {
        const uint64_t m = (next_u64() >> 32) * static_cast<uint64_t>(n);
        if (static_cast<uint32_t>(m) >= threshold) {
            return static_cast<uint32_t>(m >> 32);
        }
    }
}

double Rng::cauchy_clipped(double scale, double clip)
{
    const double u = uniform_open();
    double x = scale * std::tan(kPi * (u - 0.5));
    if (x > clip) {
        x = clip;
    } else if (x < -clip) {
        x = -clip;
    }
    return x;
}

} // namespace qnav
