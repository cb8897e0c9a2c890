/* The Cortex-M4 benchmarks' region markers (cm4_markers.h): empty, and so never folded. */
#include "cm4_markers.h"

__attribute__((noinline, used)) void qnav_bench_begin(void)
{
    __asm__ volatile("");
}

__attribute__((noinline, used)) void qnav_bench_end(void)
{
    __asm__ volatile("");
}
