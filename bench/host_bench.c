/*
 * Host benchmark of qnav_ctrl_step() over the benchmark set (bench_grid.h): the value of
 * each M line is picoseconds per step (ns x 1000, an integer), the median of 5
 * repetitions, each running the same step enough times to last at least 50 us
 * (CLOCK_MONOTONIC). Tables are compiled into RAM for every 2-input network. Meaningful
 * only in an optimised build without sanitizers (preset host-release); the build flags
 * are printed. Exit status 1 on a heading mismatch.
 *
 * Built against libqnav with QNAV_BENCH_COUNT = 1 (qnav_bench_count over the fixtures,
 * qnav_bench_count_adversary over the adversarial set, bench/adversary/) it measures no
 * time: the value is the number of hidden-unit evaluations of the step
 * (qnav_ctrl_count_evals), target "count", network mode only; tools/bench-proxy sets these
 * counts beside the same steps' simavr cycles. Exit status 1 too when a step makes more
 * evaluations than QNAV_NET_STEP_EVALS_MAX (qnav/ctrl.h), the bound by construction.
 */
#define _POSIX_C_SOURCE 199309L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_grid.h"
#include "qnav/clock.h"

#ifndef QNAV_BENCH_BUILD
#define QNAV_BENCH_BUILD "unknown"
#endif

#define REPS 5
#define MIN_BATCH_NS 50000.0

#if QNAV_BENCH_COUNT
#define TARGET "count"
#define MODES QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK)

/* Steps that made more evaluations than the bound by construction (qnav/ctrl.h). */
static unsigned over_bound;

static uint32_t measure(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                        qnav_ctrl_output_t *out, uint8_t mode)
{
    /* the grid's controller is its own scratch: counting through it changes no decision */
    qnav_ctrl_t *c = (qnav_ctrl_t *)ctrl;
    uint32_t evals = 0;
    (void)mode;
    qnav_ctrl_count_evals(c, &evals);
    qnav_ctrl_step(c, in, out, 0);
    qnav_ctrl_count_evals(c, 0);
    if (evals > QNAV_NET_STEP_EVALS_MAX(ctrl->hidden)) {
        printf("BOUND %lu evaluations, more than QNAV_NET_STEP_EVALS_MAX(%u) = %lu\n",
               (unsigned long)evals, (unsigned)ctrl->hidden,
               (unsigned long)QNAV_NET_STEP_EVALS_MAX(ctrl->hidden));
        ++over_bound;
    }
    return evals;
}

static void put_header(void)
{
    printf("qnav evaluation counts: values are hidden-unit evaluations per step\n");
}

#else
#define TARGET "host"
#define MODES                                                                              \
    (uint8_t)(QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK) | QNAV_BENCH_MODE_BIT(QNAV_BENCH_PROB) | \
              QNAV_BENCH_MODE_BIT(QNAV_BENCH_TABLE) | QNAV_BENCH_MODE_BIT(QNAV_BENCH_NETWORK3))

static volatile int32_t sink;

static double now_ns(void)
{
    return (double)qnav_mono_ns();
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a;
    double y = *(const double *)b;
    return (x > y) - (x < y);
}

/* ns per step over `iters` steps. */
static double batch(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, uint32_t iters)
{
    int32_t acc = 0;
    uint32_t i;
    double t0 = now_ns();
    for (i = 0; i < iters; ++i) {
        qnav_ctrl_step(ctrl, in, out, 0);
        acc += out->heading_deg;
    }
    sink = acc;
    return (now_ns() - t0) / (double)iters;
}

static uint32_t measure(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                        qnav_ctrl_output_t *out, uint8_t mode)
{
    double per[REPS];
    uint32_t iters = 1;
    int r;
    (void)mode;
    while (batch(ctrl, in, out, iters) * (double)iters < MIN_BATCH_NS && iters < (1u << 24)) {
        iters *= 2u;
    }
    for (r = 0; r < REPS; ++r) {
        per[r] = batch(ctrl, in, out, iters);
    }
    qsort(per, REPS, sizeof per[0], cmp_double);
    return (uint32_t)(per[REPS / 2] * 1000.0 + 0.5);
}

static void put_header(void)
{
    printf("qnav host benchmark: values are ps per step (ns x 1000), median of %d repetitions "
           "of >= %.0f us\nbuild: %s\n", REPS, MIN_BATCH_NS / 1000.0, QNAV_BENCH_BUILD);
    printf("sizeof(qnav_ctrl_t) %u bytes\n", (unsigned)sizeof(qnav_ctrl_t));
}
#endif

int main(void)
{
    qnav_bench_hooks_t hooks;
    uint16_t bad;
    put_header();
    hooks.target = TARGET;
    hooks.sep = '\t';
    hooks.modes = MODES;
    hooks.measure = measure;
    hooks.has_value = 1;
    hooks.table = qnav_bench_ram_table;
    fflush(stdout);
    bad = qnav_bench_grid(&hooks);
    fflush(stdout);
    if (bad != 0u) {
        printf("MISMATCH count %u\n", (unsigned)bad);
        return 1;
    }
#if QNAV_BENCH_COUNT
    if (over_bound != 0u) {
        printf("BOUND exceeded by %u steps\n", over_bound);
        return 1;
    }
#endif
    return 0;
}
