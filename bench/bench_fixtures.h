/*
 * Shapes of the benchmark set (bench/fixtures/, made by bench/gen_fixtures.c): policies
 * with their names and sets, scans of every sector count with their type and goal
 * bearing, and the compiled tables of the AVR table images. The data lives in program
 * memory on AVR (QNAV_FLASH); the benchmark copies one policy or one scan into RAM before
 * a step, through qnav_bench_flash_copy().
 */
#ifndef QNAV_BENCH_FIXTURES_H
#define QNAV_BENCH_FIXTURES_H

#include <stdint.h>
#include <string.h>

#include "qnav/ctrl.h"
#include "qnav/flash.h"

#if QNAV_TABLES_IN_FLASH
#include <avr/pgmspace.h>
#define qnav_bench_flash_copy(dst, src, n) memcpy_P((dst), (src), (n))
#else
#define qnav_bench_flash_copy(dst, src, n) memcpy((dst), (src), (n))
#endif

/* Longest policy name, with its NUL. */
#define QNAV_BENCH_ID_LEN 24u

/* Which set a policy belongs to: the report keeps them apart. */
enum {
    QNAV_BENCH_SET_EVOLVED = 0,
    QNAV_BENCH_SET_RANDOM,
    QNAV_BENCH_SET_PROB,
    QNAV_BENCH_SET_ADVERSARY, /* found by the adversarial search (bench/adversary.c) */
    QNAV_BENCH_SETS
};
/* Their names in M lines and policy lists, in that order. */
#define QNAV_BENCH_SET_NAMES {"evolved", "random", "prob", "adversary"}

/* Scan types (the list). */
enum {
    QNAV_BENCH_SCAN_CLEAR = 0, /* every range at the maximum, several goal bearings */
    QNAV_BENCH_SCAN_BEHIND,    /* goal at 180 deg: clear, then with walls ahead */
    QNAV_BENCH_SCAN_OBSTACLE,  /* a 0.6 m wide wall 1.5 m straight at the goal */
    QNAV_BENCH_SCAN_CORRIDOR,  /* two walls 0.6 m either side, goal along the corridor */
    QNAV_BENCH_SCAN_DENSE,     /* qnav_sim's sonar in data/envs/dense.toml at fixed poses */
    QNAV_BENCH_SCAN_RANDOM,    /* i.i.d. ranges, about a fifth above the maximum */
    QNAV_BENCH_SCAN_ADVERSARY, /* found by the adversarial search with the policy of its k */
    QNAV_BENCH_SCAN_TYPES
};
/* Their names in M lines, in that order. */
#define QNAV_BENCH_SCAN_NAMES                                                              \
    {"clear", "behind", "obstacle", "corridor", "dense", "random", "adversary"}

/* One policy of the set. */
typedef struct {
    char id[QNAV_BENCH_ID_LEN]; /* as printed in M lines */
    uint8_t set;                /* QNAV_BENCH_SET_* */
    uint8_t table_group;        /* AVR table image holding its compiled table, 0 = none */
    qnav_policy_t policy;
} qnav_bench_policy_t;

/* One scan: n ranges at ranges[0..n-1] (one array per sector count: an AVR object is at
 * most 32 767 bytes). */
typedef struct {
    uint16_t n_sectors;
    uint8_t type;                 /* QNAV_BENCH_SCAN_* */
    uint8_t k;                    /* index within its type and sector count */
    qnav_cdeg_t goal_bearing_cdeg;
    const qnav_mm_t *ranges;
} qnav_bench_scan_t;

#endif /* QNAV_BENCH_FIXTURES_H */
