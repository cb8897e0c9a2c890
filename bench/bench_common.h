/*
 * Inputs shared by the AVR and host benchmarks, so both time the same work: a 32-sector
 * scan drawn from the shared vectors' PRNG (about a fifth of the ranges above the 5 m
 * maximum, as a real sonar gives), a set of destination bearings, and the three
 * controller set-ups (network H = 12, probabilistic default, table mode from the
 * committed flash table of that same network).
 */
#ifndef QNAV_BENCH_COMMON_H
#define QNAV_BENCH_COMMON_H

#include <stdint.h>

#include "qnav/ctrl.h"
#include "vector_policy.h"
#include "vector_table.h"

#ifndef QNAV_BENCH_SECTORS
#define QNAV_BENCH_SECTORS 32u /* the benchmark; -D to study other N */
#endif
#define QNAV_BENCH_MAX_RANGE_MM 5000u
#define QNAV_BENCH_SCANS 8u

enum { QNAV_BENCH_NET = 0, QNAV_BENCH_PROB, QNAV_BENCH_TABLE, QNAV_BENCH_NET3, QNAV_BENCH_MODES };

static const char *const qnav_bench_mode_names[QNAV_BENCH_MODES] = {
    "network H=12", "probabilistic", "table", "network H=12, 3 inputs (every path)"};

/* The previous tick's heading the benchmark passes in (3-input network, VFH+). */
#define QNAV_BENCH_PREV_CDEG 2500

/* Scan k (0..QNAV_BENCH_SCANS-1) into ranges[QNAV_BENCH_SECTORS]; returns its bearing. */
static inline qnav_cdeg_t qnav_bench_scan(uint8_t k, qnav_mm_t *ranges)
{
    static const qnav_cdeg_t bearings[QNAV_BENCH_SCANS] = {0, 4500, -9000, 17999,
                                                            -13550, 2050, 12000, -600};
    uint32_t s = 0xBE7C0000ul + k;
    uint8_t i;
    for (i = 0; i < QNAV_BENCH_SECTORS; ++i) {
        ranges[i] = (qnav_mm_t)(qnav_vectors_rand(&s) %
                                (QNAV_BENCH_MAX_RANGE_MM + QNAV_BENCH_MAX_RANGE_MM / 4u + 1u));
    }
    return bearings[k % QNAV_BENCH_SCANS];
}

/* Initialise ctrl for a mode; returns the init status. */
static inline qnav_status_t qnav_bench_init(qnav_ctrl_t *ctrl, uint8_t mode)
{
    qnav_ctrl_config_t cfg;
    qnav_policy_t policy;
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = QNAV_BENCH_SECTORS;
    cfg.max_range_mm = QNAV_BENCH_MAX_RANGE_MM;
    switch (mode) {
    case QNAV_BENCH_NET:
        qnav_vectors_net_policy(&policy, 12u, QNAV_VECTORS_NET12_SEED, 0u);
        return qnav_ctrl_init(ctrl, &cfg, &policy);
    case QNAV_BENCH_PROB:
        qnav_policy_prob_default(&policy);
        return qnav_ctrl_init(ctrl, &cfg, &policy);
    case QNAV_BENCH_NET3:
        /* the same network with a third input whose weights mirror w_theta's */
        qnav_vectors_net_policy(&policy, 12u, QNAV_VECTORS_NET12_SEED, 0u);
        policy.u.net.inputs = QNAV_NET_INPUTS_PREV;
        for (uint8_t j = 0; j < 12u; ++j) {
            policy.u.net.w_prev[j] = (qnav_q8_8_t)(-policy.u.net.w_theta[j] / 2);
        }
        return qnav_ctrl_init(ctrl, &cfg, &policy);
    default:
        return qnav_ctrl_init_table(ctrl, &cfg, qnav_vectors_net12_table,
                                    QNAV_VECTORS_NET12_TABLE_RANK);
    }
}

#endif /* QNAV_BENCH_COMMON_H */
