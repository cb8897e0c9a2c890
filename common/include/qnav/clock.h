/*
 * The clocks of qnav's host programs (navbridge, the SIL robot, the simavr board, the host
 * benchmark, the bridge's tests): the monotonic clock and the wall clock that LCM messages
 * are stamped with, one home instead of a copy in each. C99; the including file defines _POSIX_C_SOURCE
 * (199309L or later) before its first system header, as those programs do.
 */
#ifndef QNAV_CLOCK_H
#define QNAV_CLOCK_H

#include <stdint.h>
#include <time.h>

/* Nanoseconds on CLOCK_MONOTONIC. */
static inline int64_t qnav_mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* Microseconds on CLOCK_MONOTONIC. */
static inline int64_t qnav_mono_us(void)
{
    return qnav_mono_ns() / 1000;
}

/* Milliseconds on CLOCK_MONOTONIC. */
static inline int64_t qnav_mono_ms(void)
{
    return qnav_mono_us() / 1000;
}

/* Microseconds since 1970 on CLOCK_REALTIME: the `utime` of LCM messages. */
static inline int64_t qnav_wall_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

#endif /* QNAV_CLOCK_H */
