/*
 * The fixed inputs of the shared test vectors: a 32-bit integer PRNG (xorshift32, the same
 * sequence on every platform) and the network policies it draws. The table generator
 * (gen_vector_table.c) and the vector program (shared_vectors.c) both use these, so the
 * committed flash table and the network it was compiled from cannot drift apart.
 */
#ifndef QNAV_VECTOR_POLICY_H
#define QNAV_VECTOR_POLICY_H

#include <stdint.h>
#include "qnav/policy.h"

/* Seed of the H = 12 network whose quality table is committed in vector_table.h. */
#define QNAV_VECTORS_NET12_SEED 0x5EED0012ul
/* Seed of the H = 16 network (hidden weights over the whole Q8.8 range: saturation). */
#define QNAV_VECTORS_NET16_SEED 0x5EED0016ul
/* Seed of the H = 32 network (hidden weights over the whole Q8.8 range: saturation). */
#define QNAV_VECTORS_NET32_SEED 0x5EED0032ul

/* Next value of the xorshift32 sequence; *state must not be 0. */
uint32_t qnav_vectors_rand(uint32_t *state);

/* A value in lo..hi (inclusive, hi >= lo) from the sequence. */
int32_t qnav_vectors_rand_range(uint32_t *state, int32_t lo, int32_t hi);

/*
 * A network policy of `hidden` units drawn from `seed`. wide = 0 draws a plausible
 * navigator (goal weights mostly negative, distance weights mostly positive, |w| <= 6);
 * wide = 1 draws the hidden units' weights and biases over the whole Q8.8 range (saturating
 * them) and output weights and bias in [-2, 2] (so the output still varies).
 */
void qnav_vectors_net_policy(qnav_policy_t *policy, uint8_t hidden, uint32_t seed, uint8_t wide);

#endif /* QNAV_VECTOR_POLICY_H */
