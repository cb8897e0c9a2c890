/*
 * The monotonic clock of qnav's host programs (navbridge, the SIL robot, the simavr board):
 * one home instead of a copy in each. C99; the including file defines _POSIX_C_SOURCE
 * (199309L or later) before its first system header, as those programs do.
 */
#ifndef QNAV_CLOCK_H
#define QNAV_CLOCK_H

#include <stdint.h>
#include <time.h>

/* Microseconds on CLOCK_MONOTONIC. */
static inline int64_t qnav_mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* Milliseconds on CLOCK_MONOTONIC. */
static inline int64_t qnav_mono_ms(void)
{
    return qnav_mono_us() / 1000;
}

#endif /* QNAV_CLOCK_H */
