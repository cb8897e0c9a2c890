/* What the ATmega128 benchmarks share (avr_clock.h). */
#include "avr_clock.h"

#include <avr/interrupt.h>
#include <avr/io.h>

#include "target_io.h"

void qnav_avr_put_flash(const char *s)
{
    char c[2];
    c[1] = '\0';
    while ((c[0] = (char)pgm_read_byte(s++)) != '\0') {
        qnav_target_put(c);
    }
}

void qnav_avr_put_cycles(uint32_t cycles)
{
    uint32_t us = (cycles + F_CPU / 2000000ul) / (F_CPU / 1000000ul);
    uint32_t frac = us % 1000u;
    qnav_target_put_u32(cycles);
    PUT(" cycles (");
    qnav_target_put_u32(us / 1000u);
    if (frac < 10u) {
        PUT(".00");
    } else if (frac < 100u) {
        PUT(".0");
    } else {
        PUT(".");
    }
    qnav_target_put_u32(frac);
    PUT(" ms at 16 MHz)");
}

static volatile uint16_t overflows;

ISR(TIMER1_OVF_vect)
{
    ++overflows;
}

void qnav_avr_timer_start(void)
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
uint32_t qnav_avr_timer_stop(void)
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

extern uint8_t __heap_start;
extern const uint8_t __ctors_start[];
#define PAINT 0xA5u

uint16_t qnav_avr_paint(void)
{
    uint8_t *p = &__heap_start;
    const uint16_t sp = SP;
    uint8_t *stop = (uint8_t *)(sp - 16u);
    while (p < stop) {
        *(volatile uint8_t *)p = PAINT;
        ++p;
    }
    return sp;
}

uint16_t qnav_avr_stack_used(uint16_t sp)
{
    uint8_t *p = &__heap_start;
    uint8_t *stop = (uint8_t *)(sp - 16u);
    while (p < stop && *(volatile uint8_t *)p == PAINT) {
        ++p;
    }
    return (uint16_t)(sp - (uint16_t)p + 1u);
}

int qnav_avr_flash_data_too_far(void)
{
    if (pgm_get_far_address(__ctors_start) > 0x10000ul) {
        /* .progmem ends where the constructors begin */
        PUT("program-memory data end past 64 KB (at ");
        qnav_target_put_u32(pgm_get_far_address(__ctors_start));
        PUT("): fewer fixtures per image\n");
        return 1;
    }
    return 0;
}
