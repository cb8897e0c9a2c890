/*
 * Host benchmark of qnav_ctrl_step(): nanoseconds per step in network (H = 12),
 * probabilistic and table mode on the same 32-sector scans as the AVR benchmark, through
 * the real library code path. Each repetition runs enough steps to last about 20 ms
 * (CLOCK_MONOTONIC); the median of 7 repetitions is printed. Meaningful only in an
 * optimised build without sanitizers (preset host-release); the build flags are printed.
 */
#define _POSIX_C_SOURCE 199309L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_common.h"

#ifndef QNAV_BENCH_BUILD
#define QNAV_BENCH_BUILD "unknown"
#endif

#define REPS 7

static double now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e9 + (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a;
    double y = *(const double *)b;
    return (x > y) - (x < y);
}

static qnav_mm_t ranges[QNAV_BENCH_SCANS][QNAV_BENCH_SECTORS];
static qnav_cdeg_t bearings[QNAV_BENCH_SCANS];
static volatile int32_t sink;

/* Time `iters` steps cycling over the scans; returns ns per step. */
static double run(const qnav_ctrl_t *ctrl, uint32_t iters)
{
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    int32_t acc = 0;
    uint32_t i;
    double t0 = now_ns();
    for (i = 0; i < iters; ++i) {
        uint32_t k = i % QNAV_BENCH_SCANS;
        in.ranges_mm = ranges[k];
        in.goal_bearing_cdeg = bearings[k];
        in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
        qnav_ctrl_step(ctrl, &in, &out, 0);
        acc += out.heading_deg + out.speed;
    }
    sink = acc;
    return (now_ns() - t0) / (double)iters;
}

int main(void)
{
    qnav_ctrl_t ctrl;
    uint8_t mode;
    uint8_t k;
    static const double target_ns[QNAV_BENCH_MODES] = {2000.0, 0.0, 500.0, 0.0};

    for (k = 0; k < QNAV_BENCH_SCANS; ++k) {
        bearings[k] = qnav_bench_scan(k, ranges[k]);
    }
    printf("qnav host benchmark: 32 sectors, 360 paths, median of %d repetitions of ~20 ms\n",
           REPS);
    printf("build: %s\n", QNAV_BENCH_BUILD);
    for (mode = 0; mode < QNAV_BENCH_MODES; ++mode) {
        double per[REPS];
        uint32_t iters = 16;
        int r;
        qnav_status_t st = qnav_bench_init(&ctrl, mode);
        if (st != QNAV_OK) {
            fprintf(stderr, "host_bench: init of mode %s failed with status %d\n",
                    qnav_bench_mode_names[mode], (int)st);
            return 1;
        }
        while (run(&ctrl, iters) * (double)iters < 20e6 && iters < (1u << 30)) {
            iters *= 2u;
        }
        for (r = 0; r < REPS; ++r) {
            per[r] = run(&ctrl, iters);
        }
        qsort(per, REPS, sizeof per[0], cmp_double);
        printf("%-14s %10.1f ns/step (min %.1f, max %.1f, %u steps per repetition)",
               qnav_bench_mode_names[mode], per[REPS / 2], per[0], per[REPS - 1],
               (unsigned)iters);
        if (target_ns[mode] > 0.0) {
            printf("  target <= %.0f ns", target_ns[mode]);
        }
        printf("\n");
    }
    return 0;
}
