/*
 * Deterministic PRNG and network policies for the shared test vectors (vector_policy.h).
 */
#include "vector_policy.h"

uint32_t qnav_vectors_rand(uint32_t *state)
{
    uint32_t x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    return x;
}

int32_t qnav_vectors_rand_range(uint32_t *state, int32_t lo, int32_t hi)
{
    uint32_t span = (uint32_t)(hi - lo) + 1u;
    return lo + (int32_t)(qnav_vectors_rand(state) % span);
}

void qnav_vectors_net_policy(qnav_policy_t *policy, uint8_t hidden, uint32_t seed, uint8_t wide)
{
    uint32_t s = seed;
    uint8_t j;
    qnav_policy_net_zero(policy, hidden);
    for (j = 0; j < policy->u.net.hidden; ++j) {
        if (wide) {
            policy->u.net.w_theta[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -32768, 32767);
            policy->u.net.w_dist[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -32768, 32767);
            policy->u.net.b_hidden[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -32768, 32767);
            policy->u.net.w_out[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -2 * 256, 2 * 256);
        } else {
            policy->u.net.w_theta[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -6 * 256, 1 * 256);
            policy->u.net.w_dist[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -1 * 256, 6 * 256);
            policy->u.net.b_hidden[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -3 * 256, 3 * 256);
            policy->u.net.w_out[j] = (qnav_q8_8_t)qnav_vectors_rand_range(&s, -1 * 256, 3 * 256);
        }
    }
    policy->u.net.b_out = (qnav_q8_8_t)(wide ? qnav_vectors_rand_range(&s, -2 * 256, 2 * 256)
                                             : qnav_vectors_rand_range(&s, -4 * 256, -1 * 256));
}
