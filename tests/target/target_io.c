/*
 * target_io.h for the three platforms: stdio on the host and on the Cortex-M4 (newlib with
 * semihosting), simavr's console register on AVR.
 */
#include "target_io.h"

#if defined(__AVR__)
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr_mcu_section.h>

#ifndef QNAV_MCU_NAME
#define QNAV_MCU_NAME "atmega128"
#endif

/* An address the ATmega128 leaves unused (0x66 in data space): writes to it reach only
 * simavr's console, never a peripheral model. */
#define QNAV_CONSOLE_REG _SFR_MEM8(0x66)

AVR_MCU(F_CPU, QNAV_MCU_NAME);
AVR_MCU_SIMAVR_CONSOLE(&QNAV_CONSOLE_REG);

static void put_char(char c)
{
    /* simavr 1.6 flushes a console line on '\r' and ignores '\n'. */
    QNAV_CONSOLE_REG = (uint8_t)(c == '\n' ? '\r' : c);
}

void qnav_target_exit(uint8_t code)
{
    qnav_target_put("EXIT ");
    qnav_target_put_u32(code);
    qnav_target_put("\n");
    cli();
    for (;;) {
        sleep_mode(); /* with interrupts off, simavr ends the run here */
    }
}

#else
#include <stdio.h>
#include <stdlib.h>

static void put_char(char c)
{
    (void)putchar(c);
}

void qnav_target_exit(uint8_t code)
{
    (void)fflush(stdout);
    exit(code);
}
#endif

void qnav_target_put(const char *s)
{
    while (*s != '\0') {
        put_char(*s++);
    }
}

void qnav_target_put_u32(uint32_t v)
{
    char buf[11];
    uint8_t n = 0;
    do {
        buf[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n > 0u) {
        put_char(buf[--n]);
    }
}

void qnav_target_put_i32(int32_t v)
{
    if (v < 0) {
        put_char('-');
        qnav_target_put_u32((uint32_t)0 - (uint32_t)v);
    } else {
        qnav_target_put_u32((uint32_t)v);
    }
}

void qnav_target_put_hex(uint32_t v, uint8_t digits)
{
    static const char hex[] = "0123456789abcdef";
    if (digits < 1u || digits > 8u) {
        digits = 8u;
    }
    put_char('0');
    put_char('x');
    while (digits > 0u) {
        --digits;
        put_char(hex[(v >> (4u * digits)) & 0xfu]);
    }
}
