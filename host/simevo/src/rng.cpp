/*
 * simevo's seed derivation (mix_seed) and byte hash (fnv1a64), on the shared splitmix64
 * and FNV-1a (qnav/rng.h).
 */
#include "rng.h"

namespace qnav {

uint64_t mix_seed(uint64_t a, uint64_t b)
{
    uint64_t x = a ^ qnav_rotl64(b, 29) ^ 0x5851f42d4c957f2dull;
    qnav_splitmix64(&x);
    x ^= b;
    return qnav_splitmix64(&x);
}

uint64_t fnv1a64(const void *data, std::size_t len, uint64_t h)
{
    return qnav_fnv1a64(data, len, h);
}

} // namespace qnav
