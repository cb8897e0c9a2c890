/*
 * What the ATmega128 benchmarks share (avr_bench.c, avr_map_bench.c): Timer1 counting
 * every clock, extended to 32 bits by its overflow interrupt; the peak stack of a call,
 * found by painting free RAM before it; text from flash (4 KB of RAM has no room for the
 * programs' messages).
 */
#ifndef QNAV_BENCH_AVR_CLOCK_H
#define QNAV_BENCH_AVR_CLOCK_H

#include <avr/pgmspace.h>
#include <stdint.h>

void qnav_avr_put_flash(const char *s);
#define PUT(s) qnav_avr_put_flash(PSTR(s))
/* "<cycles> cycles (<ms> ms at 16 MHz)" */
void qnav_avr_put_cycles(uint32_t cycles);

void qnav_avr_timer_start(void);
/* The cycles since qnav_avr_timer_start(), the timer's own cost included. */
uint32_t qnav_avr_timer_stop(void);

/* Paint free RAM from the end of .bss to a little below the stack pointer; returns the
 * stack pointer to give qnav_avr_stack_used() after the call measured. */
uint16_t qnav_avr_paint(void);
/* Bytes below stack pointer sp that the call since qnav_avr_paint() wrote. */
uint16_t qnav_avr_stack_used(uint16_t sp);

/* 1 (and a line saying so) when the program's flash data reach past 64 KB, where LPM's
 * 16-bit addresses wrap. */
int qnav_avr_flash_data_too_far(void);

#endif
