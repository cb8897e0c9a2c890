/*
 * Benchmark regions of known instruction counts for tools/cm4-icount (Cortex-M4 only).
 * Each region is hand-written Thumb-2 between `bl qnav_bench_begin` and
 * `bl qnav_bench_end`, so its count follows from the assembly: the counter counts every
 * instruction executed after begin returns up to and including the `bl` into end. Each
 * region prints `M<TAB>name<TAB>expected<TAB>-`; the test (test_cm4_icount.py) checks that
 * cm4-icount replaces every `-` by the expected count. The regions cover no work, straight
 * code, loops of 1 to 150 000 iterations (taken branches: one translation block each), calls,
 * an IT block whose skipped instruction still counts, a block longer than QEMU's 512
 * instructions per translation block, and code in RAM rewritten between runs (retranslation).
 * QNAV_ICOUNT_VARIANT selects a faulty program for the error tests: 1 prints one `-` line
 * more than it has regions, 2 one fewer, 3 exits with status 3, 4 faults (QEMU locks up).
 */
#include <stdint.h>

#include "target_io.h"

#ifndef QNAV_ICOUNT_VARIANT
#define QNAV_ICOUNT_VARIANT 0
#endif

/* The markers, as a benchmark program defines them. */
void qnav_bench_begin(void);
void qnav_bench_end(void);
__attribute__((noinline, used)) void qnav_bench_begin(void) { __asm__ volatile(""); }
__attribute__((noinline, used)) void qnav_bench_end(void) { __asm__ volatile(""); }

/* The regions (assembly below). Arguments are kept in r4 across the markers. */
void region_empty(void);            /* 1: bl end */
void region_straight(void);         /* 10 + 1 */
void region_loop(uint32_t n);       /* 2n + 1, n >= 1: n × (subs, bne) + bl end */
void region_calls(void);            /* 1 + 12 + 1: bl outer; outer = push, bl, bl, pop + 2 × leaf (4) */
void region_it(uint32_t x);         /* 4 + 1: cmp, ite, moveq, movne whatever x is */
void region_long_block(void);       /* 1500 + 1 */
void region_call_ram(uint32_t fn);  /* 1 + body + 1: blx r4, the RAM function, bl end */

__asm__(
    "   .syntax unified\n"
    "   .thumb\n"
    "   .section .text.icount_regions,\"ax\",%progbits\n"
    "   .balign 4\n"

    "   .global region_empty\n"
    "   .type region_empty, %function\n"
    "   .thumb_func\n"
    "region_empty:\n"
    "   push {r4, lr}\n"
    "   bl qnav_bench_begin\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .global region_straight\n"
    "   .type region_straight, %function\n"
    "   .thumb_func\n"
    "region_straight:\n"
    "   push {r4, lr}\n"
    "   bl qnav_bench_begin\n"
    "   movs r0, #1\n"
    "   movs r1, #2\n"
    "   adds r0, r0, r1\n"
    "   lsls r0, r0, #3\n"
    "   movw r2, #0x1234\n"     /* 32-bit encodings count once like 16-bit ones */
    "   add.w r2, r2, r0\n"
    "   eors r1, r2\n"
    "   mul r0, r1, r2\n"
    "   nop\n"
    "   subs r0, r0, #1\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .global region_loop\n"
    "   .type region_loop, %function\n"
    "   .thumb_func\n"
    "region_loop:\n"
    "   push {r4, lr}\n"
    "   mov r4, r0\n"
    "   bl qnav_bench_begin\n"
    "1: subs r4, r4, #1\n"
    "   bne 1b\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .type region_leaf, %function\n"
    "   .thumb_func\n"
    "region_leaf:\n"              /* 4 instructions */
    "   movs r0, #1\n"
    "   adds r0, r0, #2\n"
    "   adds r0, r0, #3\n"
    "   bx lr\n"

    "   .type region_outer, %function\n"
    "   .thumb_func\n"
    "region_outer:\n"             /* 4 instructions + 2 × 4 in region_leaf */
    "   push {lr}\n"
    "   bl region_leaf\n"
    "   bl region_leaf\n"
    "   pop {pc}\n"

    "   .global region_calls\n"
    "   .type region_calls, %function\n"
    "   .thumb_func\n"
    "region_calls:\n"
    "   push {r4, lr}\n"
    "   bl qnav_bench_begin\n"
    "   bl region_outer\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .global region_it\n"
    "   .type region_it, %function\n"
    "   .thumb_func\n"
    "region_it:\n"
    "   push {r4, lr}\n"
    "   mov r4, r0\n"
    "   bl qnav_bench_begin\n"
    "   cmp r4, #0\n"
    "   ite eq\n"
    "   moveq r0, #1\n"
    "   movne r0, #2\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .global region_long_block\n"
    "   .type region_long_block, %function\n"
    "   .thumb_func\n"
    "region_long_block:\n"
    "   push {r4, lr}\n"
    "   bl qnav_bench_begin\n"
    "   .rept 1500\n"
    "   adds r0, r0, #1\n"
    "   .endr\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"

    "   .global region_call_ram\n"
    "   .type region_call_ram, %function\n"
    "   .thumb_func\n"
    "region_call_ram:\n"
    "   push {r4, lr}\n"
    "   mov r4, r0\n"
    "   bl qnav_bench_begin\n"
    "   blx r4\n"
    "   bl qnav_bench_end\n"
    "   pop {r4, pc}\n"
    "   .text\n");

/* A function in RAM, alone in its 1 KB page so that rewriting it invalidates only its own
 * translation: n × `adds r0, #1` then `bx lr`, n + 1 instructions. */
static uint16_t ram_code[512] __attribute__((aligned(1024)));

static uint32_t ram_function(uint32_t n)
{
    uint32_t i;
    for (i = 0; i < n; ++i) {
        ram_code[i] = 0x3001u; /* adds r0, #1 */
    }
    ram_code[n] = 0x4770u;     /* bx lr */
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    return (uint32_t)(uintptr_t)ram_code | 1u; /* Thumb */
}

static uint32_t reported;

static void report(const char *name, uint32_t expected)
{
    qnav_target_put("M\t");
    qnav_target_put(name);
    qnav_target_put("\t");
    qnav_target_put_u32(expected);
    qnav_target_put("\t-\n");
    ++reported;
}

int main(void)
{
    static const uint32_t loops[] = {1u, 10u, 2500u, 150000u};
    uint32_t i;

    qnav_target_put("icount_regions: regions of known instruction counts\n");
    qnav_target_put("M\tregion\texpected\tcount\n"); /* an M line that is not a result */

    region_empty();
    report("empty", 1u);
    region_straight();
    report("straight", 11u);
    for (i = 0; i < sizeof loops / sizeof loops[0]; ++i) {
        region_loop(loops[i]);
        report("loop", 2u * loops[i] + 1u);
    }
    region_calls();
    report("calls", 14u);
    region_it(0u);
    report("it_taken", 5u);
    region_it(1u);
    report("it_skipped", 5u);
    region_long_block();
    report("long_block", 1501u);
    region_call_ram(ram_function(4u));
    report("ram_4", 4u + 3u);
    region_call_ram(ram_function(40u));
    report("ram_40", 40u + 3u);
    region_call_ram(ram_function(4u));
    report("ram_4_again", 4u + 3u);

#if QNAV_ICOUNT_VARIANT == 1
    report("no_region", 0u);
#elif QNAV_ICOUNT_VARIANT == 2
    region_empty();
#elif QNAV_ICOUNT_VARIANT == 4
    __asm__ volatile("udf #0"); /* no fault handler: the core locks up */
#endif
    qnav_target_put("icount_regions: ");
    qnav_target_put_u32(reported);
    qnav_target_put(" results\n");
    qnav_target_exit(QNAV_ICOUNT_VARIANT == 3 ? 3u : 0u);
    return 0;
}
