/*
 * The one random-number generator of qnav's host code: xoshiro256** (Blackman & Vigna),
 * seeded through splitmix64 (Steele, Lea & Flood), both written from their published
 * descriptions. A seed gives the same sequence on every machine, compiler and standard
 * library, which the simulator's episodes and generated worlds, simevo's runs and
 * `qnav-policy new --seed` rely on: changing anything here changes every result. C99 and
 * header only, so C and C++ programs share it; qnav/rng.hpp adds the samplers for C++.
 * Host only: the firmware draws nothing at random.
 */
#ifndef QNAV_RNG_H
#define QNAV_RNG_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* splitmix64: advance *state by the golden-ratio increment and return the mixed state.
 * A whole sequence from any seed, 0 included; also a seed mixer. */
static inline uint64_t qnav_splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* 64-bit FNV-1a of len bytes at data, continuing from h (start: QNAV_FNV1A64_BASIS):
 * fingerprints, and labels turned into seeds. */
#define QNAV_FNV1A64_BASIS 1469598103934665603ull
static inline uint64_t qnav_fnv1a64(const void *data, size_t len, uint64_t h)
{
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < len; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* x rotated left by k bits, 0 < k < 64. */
static inline uint64_t qnav_rotl64(uint64_t x, unsigned k)
{
    return (x << k) | (x >> (64u - k));
}

/* xoshiro256** state: 256 bits, never all zero once seeded. */
typedef struct {
    uint64_t s[4];
} qnav_xoshiro256ss_t;

/* The state of `seed`: four successive splitmix64 outputs from it. */
static inline void qnav_xoshiro256ss_seed(qnav_xoshiro256ss_t *g, uint64_t seed)
{
    uint64_t x = seed;
    int i;
    for (i = 0; i < 4; ++i) {
        g->s[i] = qnav_splitmix64(&x);
    }
}

/* The next 64 random bits. */
static inline uint64_t qnav_xoshiro256ss_next(qnav_xoshiro256ss_t *g)
{
    uint64_t *s = g->s;
    const uint64_t result = qnav_rotl64(s[1] * 5u, 7u) * 9u;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = qnav_rotl64(s[3], 45u);
    return result;
}

#ifdef __cplusplus
}
#endif

#endif /* QNAV_RNG_H */
