/*
 * Cycle benchmark of qnav_ctrl_step() on an ATmega128 at 16 MHz, run under simavr
 * (cycle-accurate). Timer1 counts every clock (clk/1) and its overflow interrupt extends
 * it to 32 bits; the fixed cost of starting and stopping the timer is measured and
 * subtracted, and a delay loop of known length checks the method. Each mode (network
 * H = 12, probabilistic, table from flash) is timed on 8 scans of 32 sectors; the peak
 * stack of a step is found by painting free RAM and looking for the high-water mark.
 * A naive float network (float weights, avr-libc expf, 360 paths x 12 hidden, the
 * straightforward way) is timed the same way for comparison. Every figure printed is
 * measured here; targets are printed next to them for reading, not used to pass or fail.
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <math.h>
#include <stdint.h>
#include <util/delay_basic.h>

#include "bench_common.h"
#include "qnav/vfh.h"
#include "target_io.h"

static volatile uint16_t overflows;

ISR(TIMER1_OVF_vect)
{
    ++overflows;
}

static void timer_start(void)
{
    TCCR1B = 0;
    TCCR1A = 0;
    TCNT1 = 0;
    overflows = 0;
    TIFR = _BV(TOV1);
    TIMSK |= _BV(TOIE1);
    sei();
    TCCR1B = _BV(CS10); /* clk/1 */
}

/* Read the count while the timer still runs (simavr only updates TCNT1 from the cycle
 * counter while it is clocked), then stop it. An overflow flagged but not yet serviced
 * belongs before the count read when the count is small. */
static uint32_t timer_stop(void)
{
    uint16_t c;
    cli();
    c = TCNT1;
    TCCR1B = 0;
    if ((TIFR & _BV(TOV1)) && c < 0x8000u) {
        TIFR = _BV(TOV1);
        ++overflows;
    }
    return ((uint32_t)overflows << 16) + c;
}

static qnav_ctrl_t ctrl;
static qnav_mm_t ranges[QNAV_BENCH_SECTORS];
static uint32_t overhead;

/* Cycles of one step (timer overhead removed). */
static uint32_t time_step(const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    uint32_t c;
    timer_start();
    qnav_ctrl_step(&ctrl, in, out, 0);
    c = timer_stop();
    return c - overhead;
}

/* "<cycles> cycles (<ms> ms at 16 MHz)" */
static void put_cycles(uint32_t cycles)
{
    uint32_t us = (cycles + F_CPU / 2000000ul) / (F_CPU / 1000000ul);
    uint32_t frac = us % 1000u;
    qnav_target_put_u32(cycles);
    qnav_target_put(" cycles (");
    qnav_target_put_u32(us / 1000u);
    qnav_target_put(frac < 100u ? (frac < 10u ? ".00" : ".0") : ".");
    qnav_target_put_u32(frac);
    qnav_target_put(" ms at 16 MHz)");
}

/* ---- stack high-water mark ---------------------------------------------------------- */

extern uint8_t __heap_start;
#define PAINT 0xA5u

/* Paint from the end of .bss to a little below the current stack pointer, run one step,
 * and return how many bytes below the caller's stack pointer it wrote. Inlined so the
 * painting runs in main's frame and the step is called from a known stack pointer. */
static inline __attribute__((always_inline)) uint16_t step_stack_bytes(
    const qnav_ctrl_input_t *in, qnav_ctrl_output_t *out)
{
    uint8_t *p = &__heap_start;
    uint16_t sp = SP;
    uint8_t *stop = (uint8_t *)(sp - 16u);
    while (p < stop) {
        *(volatile uint8_t *)p = PAINT;
        ++p;
    }
    qnav_ctrl_step(&ctrl, in, out, 0);
    p = &__heap_start;
    while (p < stop && *(volatile uint8_t *)p == PAINT) {
        ++p;
    }
    return (uint16_t)(sp - (uint16_t)p + 1u);
}

/* ---- naive float network, for the ratio ---------------------------------------------- */

static float w_theta_f[12], w_dist_f[12], b_hidden_f[12], w_out_f[12], b_out_f;

static void naive_load(void)
{
    qnav_policy_t policy;
    uint8_t j;
    qnav_vectors_net_policy(&policy, 12u, QNAV_VECTORS_NET12_SEED, 0u);
    for (j = 0; j < 12u; ++j) {
        w_theta_f[j] = (float)policy.u.net.w_theta[j] / 256.0f;
        w_dist_f[j] = (float)policy.u.net.w_dist[j] / 256.0f;
        b_hidden_f[j] = (float)policy.u.net.b_hidden[j] / 256.0f;
        w_out_f[j] = (float)policy.u.net.w_out[j] / 256.0f;
    }
    b_out_f = (float)policy.u.net.b_out / 256.0f;
}

/* The straightforward float controller: for every path, its sector's range, the angular
 * distance to the goal, two sigmoid layers with expf; keep the best. Returns the heading. */
__attribute__((noinline)) static int16_t naive_float_step(const qnav_mm_t *r, uint16_t n,
                                                         float goal_deg, float max_mm)
{
    float best_q = -1.0f;
    int16_t best = 0;
    int16_t i;
    uint8_t j;
    for (i = 0; i < 360; ++i) {
        uint16_t sector = (uint16_t)(((float)i * (float)n / 360.0f) + 0.5f) % n;
        float d = (float)r[sector];
        float dtheta = fabsf((float)i - goal_deg);
        float acc = b_out_f;
        float q;
        if (d > max_mm) {
            d = max_mm;
        }
        if (dtheta > 180.0f) {
            dtheta = 360.0f - dtheta;
        }
        for (j = 0; j < 12u; ++j) {
            float z = w_theta_f[j] * (dtheta / 180.0f) + w_dist_f[j] * (d / max_mm) + b_hidden_f[j];
            acc += w_out_f[j] / (1.0f + expf(-z));
        }
        q = 1.0f / (1.0f + expf(-acc));
        if (q > best_q) {
            best_q = q;
            best = i;
        }
    }
    return (int16_t)(best > 180 ? best - 360 : best);
}

int main(void)
{
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    uint32_t c;
    uint8_t mode;
    uint8_t k;
    uint32_t net_mean = 0;
    uint16_t peak_stack = 0;
    uint8_t ok = 1;
    int16_t naive_heading;

    in.ranges_mm = ranges;
    timer_start();
    overhead = timer_stop();

    qnav_target_put("qnav AVR benchmark: ATmega128, 16 MHz, simavr; 32 sectors, 360 paths\n");
    qnav_target_put("timer overhead subtracted: ");
    qnav_target_put_u32(overhead);
    qnav_target_put(" cycles\n");
    timer_start();
    _delay_loop_2(50000u); /* 4 cycles per count: 200000 */
    c = timer_stop() - overhead;
    qnav_target_put("check: _delay_loop_2(50000), 200000 cycles by the datasheet, measured ");
    qnav_target_put_u32(c);
    qnav_target_put("\n");

    for (mode = 0; mode < QNAV_BENCH_MODES; ++mode) {
        uint32_t lo = 0xfffffffful;
        uint32_t hi = 0;
        uint32_t sum = 0;
        uint16_t stack;
        qnav_status_t st = qnav_bench_init(&ctrl, mode);
        if (st != QNAV_OK) {
            qnav_target_put("init failed: ");
            qnav_target_put_i32(st);
            qnav_target_put("\n");
            ok = 0;
            continue;
        }
        for (k = 0; k < QNAV_BENCH_SCANS; ++k) {
            in.goal_bearing_cdeg = qnav_bench_scan(k, ranges);
            in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
            c = time_step(&in, &out);
            sum += c;
            lo = c < lo ? c : lo;
            hi = c > hi ? c : hi;
        }
        in.goal_bearing_cdeg = qnav_bench_scan(0, ranges);
        stack = step_stack_bytes(&in, &out);
        peak_stack = stack > peak_stack ? stack : peak_stack;
        qnav_target_put(qnav_bench_mode_names[mode]);
        qnav_target_put(": mean ");
        put_cycles(sum / QNAV_BENCH_SCANS);
        qnav_target_put(", min ");
        qnav_target_put_u32(lo);
        qnav_target_put(", max ");
        qnav_target_put_u32(hi);
        qnav_target_put("; step stack ");
        qnav_target_put_u32(stack);
        qnav_target_put(" bytes\n");
        if (mode == QNAV_BENCH_NET) {
            net_mean = sum / QNAV_BENCH_SCANS;
        }
        if (mode != QNAV_BENCH_PROB) {
            /* Cost of one path's quality through the public function: how many path
             * evaluations a step's cycles amount to. */
            volatile qnav_q1_15_t q;
            uint8_t lv;
            timer_start();
            for (lv = 0; lv < 16u; ++lv) {
                q = qnav_ctrl_quality(&ctrl, (uint8_t)(lv * 2u), (uint8_t)(lv * 11u));
            }
            c = timer_stop() - overhead;
            (void)q;
            qnav_target_put("  one qnav_ctrl_quality() call: ");
            qnav_target_put_u32((c + 8u) / 16u);
            qnav_target_put(" cycles (mean of 16); step = ");
            qnav_target_put_u32((sum / QNAV_BENCH_SCANS + (c + 8u) / 32u) / ((c + 8u) / 16u));
            qnav_target_put(" such calls\n");
        }
    }

    {
        /* VFH+ (qnav/vfh.h) on the same scans, through its own step */
        static qnav_vfh_t vfh;
        static qnav_vfh_state_t vstate;
        qnav_vfh_config_t vcfg;
        uint32_t lo = 0xfffffffful;
        uint32_t hi = 0;
        uint32_t sum = 0;
        qnav_vfh_config_default(&vcfg);
        vcfg.body.n_sectors = QNAV_BENCH_SECTORS;
        vcfg.body.max_range_mm = QNAV_BENCH_MAX_RANGE_MM;
        if (qnav_vfh_init(&vfh, &vcfg) != QNAV_OK) {
            qnav_target_put("VFH+ init failed\n");
            ok = 0;
        }
        qnav_vfh_state_reset(&vstate);
        for (k = 0; k < QNAV_BENCH_SCANS; ++k) {
            in.goal_bearing_cdeg = qnav_bench_scan(k, ranges);
            in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
            timer_start();
            qnav_vfh_step(&vfh, &vstate, &in, &out);
            c = timer_stop() - overhead;
            sum += c;
            lo = c < lo ? c : lo;
            hi = c > hi ? c : hi;
        }
        qnav_target_put("VFH+ (alpha 5 deg, 72 sectors): mean ");
        put_cycles(sum / QNAV_BENCH_SCANS);
        qnav_target_put(", min ");
        qnav_target_put_u32(lo);
        qnav_target_put(", max ");
        qnav_target_put_u32(hi);
        qnav_target_put("; sizeof(qnav_vfh_t) + state ");
        qnav_target_put_u32(sizeof(qnav_vfh_t) + sizeof(qnav_vfh_state_t));
        qnav_target_put(" bytes\n");
    }

    qnav_target_put("sizeof(qnav_ctrl_t) ");
    qnav_target_put_u32(sizeof(qnav_ctrl_t));
    qnav_target_put(" bytes; controller RAM = sizeof + peak step stack + table RAM (0, table in flash) = ");
    qnav_target_put_u32(sizeof(qnav_ctrl_t) + peak_stack);
    qnav_target_put(" bytes (target <= 1024)\n");

    naive_load();
    in.goal_bearing_cdeg = qnav_bench_scan(0, ranges);
    timer_start();
    naive_heading = naive_float_step(ranges, QNAV_BENCH_SECTORS, 0.0f, (float)QNAV_BENCH_MAX_RANGE_MM);
    c = timer_stop() - overhead;
    qnav_target_put("naive float network (expf, 360 x 12): ");
    put_cycles(c);
    qnav_target_put(", heading ");
    qnav_target_put_i32(naive_heading);
    qnav_target_put("\n");
    if (net_mean != 0u) {
        qnav_target_put("ratio naive float / fixed-point network: ");
        qnav_target_put_u32((c + net_mean / 2u) / net_mean);
        qnav_target_put(".");
        qnav_target_put_u32(((c * 10u + net_mean / 2u) / net_mean) % 10u);
        qnav_target_put("\n");
    }
    qnav_target_put("targets: network <= 100000 cycles, table <= 8000 cycles, RAM <= 1024 bytes\n");
    qnav_target_exit(ok ? 0u : 1u);
    return 0;
}
