/*
 * Output and exit for programs that run unchanged on the host, on an ATmega128 under
 * simavr and on a Cortex-M4 under qemu-system-arm (the shared test vectors and the
 * benchmarks). On the host and the Cortex-M4 (semihosting) text goes to stdout and the
 * exit status is the process's. On AVR text goes through simavr's console register and the
 * program ends by printing "EXIT <n>" and sleeping with interrupts off; cmake/run-simavr
 * turns that back into an exit status. Only integers are formatted, identically everywhere.
 */
#ifndef QNAV_TARGET_IO_H
#define QNAV_TARGET_IO_H

#include <stdint.h>

/* Write a string as is (no newline added). Lines must not be empty or hold tabs: simavr's
 * console drops control characters and empty lines. */
void qnav_target_put(const char *s);

/* Unsigned decimal. */
void qnav_target_put_u32(uint32_t v);

/* Signed decimal. */
void qnav_target_put_i32(int32_t v);

/* "0x" and exactly `digits` hexadecimal digits (1..8), lower case. */
void qnav_target_put_hex(uint32_t v, uint8_t digits);

/* End the program with status code (0..255). Does not return. */
void qnav_target_exit(uint8_t code);

#endif /* QNAV_TARGET_IO_H */
