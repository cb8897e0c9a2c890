/*
 * The region markers of the Cortex-M4 benchmarks (tools/cm4-icount counts the instructions
 * between a call of qnav_bench_begin() and the next call of qnav_bench_end()): defined in
 * cm4_markers.c, not inlined, not merged, kept by --gc-sections.
 */
#ifndef QNAV_CM4_MARKERS_H
#define QNAV_CM4_MARKERS_H

__attribute__((noinline, used)) void qnav_bench_begin(void);
__attribute__((noinline, used)) void qnav_bench_end(void);

#endif
