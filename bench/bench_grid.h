/*
 * The benchmark grid shared by the ATmega128, Cortex-M4 and host programs: every policy
 * of the set (bench/fixtures/bench_policies.h) in each mode it has, on every scan of every
 * sector count (bench_scans.h), through the public API only. Before each measured step the
 * same scan is stepped once by the library's plain reference step (qnav_ctrl_step_plain:
 * every path evaluated) on the same controller; a measured decision (heading, speed,
 * quality, flags) that differs is printed as a MISMATCH line. One line per measured step in the output protocol of
 * bench/README.md:
 *   M<TAB>target=T<TAB>mode=M<TAB>H=h<TAB>N=n<TAB>policy=ID<TAB>set=S<TAB>scan=TYPE:k<TAB>VALUE
 */
#ifndef QNAV_BENCH_GRID_H
#define QNAV_BENCH_GRID_H

#include <stdint.h>

#include "bench_fixtures.h"
#include "qnav/ctrl.h"

/* Modes, as named in M lines. */
enum {
    QNAV_BENCH_NETWORK = 0, /* 2-input network */
    QNAV_BENCH_PROB,        /* probabilistic policy */
    QNAV_BENCH_TABLE,       /* compiled table of a 2-input network */
    QNAV_BENCH_NETWORK3,    /* 3-input network (previous decision) */
    QNAV_BENCH_MODES
};
#define QNAV_BENCH_MODE_BIT(m) ((uint8_t)(1u << (m)))

/* A mode's name as M lines print it. */
const char *qnav_bench_mode_name(uint8_t mode);

/* The previous tick's heading passed in (read by 3-input networks only), 0.01 deg. */
#define QNAV_BENCH_PREV_CDEG 2500

/* What a platform supplies. */
typedef struct {
    const char *target; /* "avr", "cm4", "host" */
    char sep;           /* field separator printed in M lines: TAB, or a stand-in where the
                           console drops control characters (simavr) */
    uint8_t modes;      /* QNAV_BENCH_MODE_BIT()s to run */
    /* One measured step of ctrl on in (out receives the decision). Returns the value of
     * the M line; has_value 0 prints '-' instead (the Cortex-M4 counts instructions
     * between its marker functions outside the program). */
    uint32_t (*measure)(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                        qnav_ctrl_output_t *out, uint8_t mode);
    uint8_t has_value;
    /* The compiled table of policy `index` (its copy in RAM is *policy), or null when this
     * image has none; *rank receives the table's qnav_rank_t. */
    const qnav_qkey_t *(*table)(uint8_t index, const qnav_policy_t *policy, uint8_t *rank);
} qnav_bench_hooks_t;

/* Run the grid; returns the number of mismatches (0: every heading agreed). */
uint16_t qnav_bench_grid(const qnav_bench_hooks_t *hooks);

/* Copy scan `index` of the fixtures into ranges (RAM, at least its n_sectors entries);
 * returns its sector count and sets *bearing. */
uint16_t qnav_bench_load_scan(uint16_t index, qnav_mm_t *ranges, qnav_cdeg_t *bearing,
                              uint8_t *type, uint8_t *k);

/* Copy policy `index` into RAM; returns its set. */
uint8_t qnav_bench_load_policy(uint8_t index, qnav_policy_t *policy, char *id);

/* Number of scans and policies in the fixtures, and the sonar range of the scans (mm). */
uint16_t qnav_bench_scan_count(void);
uint8_t qnav_bench_policy_count(void);
qnav_mm_t qnav_bench_max_range_mm(void);

/* The benchmark's controller configuration for n sectors: qnav_ctrl_config_default()
 * (TekBot body) with the TekBot's sonar range. */
void qnav_bench_config(qnav_ctrl_config_t *cfg, uint16_t n_sectors);

/* The grid's scratch (one scan's ranges, QNAV_MAX_SECTORS entries; one controller; one
 * policy), for a program's own measurements outside the grid: 4 KB of RAM has room for
 * one set only. */
qnav_mm_t *qnav_bench_scratch_ranges(void);
qnav_ctrl_t *qnav_bench_scratch_ctrl(void);
qnav_policy_t *qnav_bench_scratch_policy(void);

/* Non-AVR targets: compile the policy's table into a static RAM buffer (null for a policy
 * without one). */
const qnav_qkey_t *qnav_bench_ram_table(uint8_t index, const qnav_policy_t *policy,
                                        uint8_t *rank);

#endif /* QNAV_BENCH_GRID_H */
