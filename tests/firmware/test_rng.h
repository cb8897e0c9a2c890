/*
 * The firmware tests' random numbers: qnav/rng.h's splitmix64 from a fixed seed, one stream
 * per test file (each file that includes this has its own state), so every run draws the
 * same scans, networks and rows.
 */
#ifndef QNAV_TEST_RNG_H
#define QNAV_TEST_RNG_H

#include <stdint.h>

#include "qnav/rng.h"

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static uint32_t rng_u32(void)
{
    return (uint32_t)(qnav_splitmix64(&rng_state) >> 32);
}

static int32_t rng_range(int32_t lo, int32_t hi) /* inclusive */
{
    return lo + (int32_t)(rng_u32() % (uint32_t)(hi - lo + 1));
}

#endif /* QNAV_TEST_RNG_H */
