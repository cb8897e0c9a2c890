/*
 * simevo's seeds: how a run, a condition, an episode or a world gets its own seed from a
 * parent seed and a label, and the fingerprint hash. The generator itself is qnav::Rng
 * (common/include/qnav/rng.hpp), shared with the simulator.
 */
#ifndef QNAV_SIMEVO_RNG_H
#define QNAV_SIMEVO_RNG_H

#include <cstddef>
#include <cstdint>

#include "qnav/rng.hpp"

namespace qnav {

/* splitmix64 finaliser of (a, b): derives independent stream seeds from a parent seed and
 * a label (run index, condition, episode number). */
uint64_t mix_seed(uint64_t a, uint64_t b);

/* 64-bit FNV-1a of a byte string (fingerprints, labels to seeds). */
uint64_t fnv1a64(const void *data, std::size_t len, uint64_t h = QNAV_FNV1A64_BASIS);

} // namespace qnav

#endif
