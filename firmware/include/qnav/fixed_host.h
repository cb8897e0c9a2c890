/*
 * Fixed point from and to real numbers, for host programs and tests only (the
 * simulator, simevo, navbridge, the unit tests). libqnav itself has no floating point:
 * its sources write raw values, and this header refuses to compile for the MCU targets.
 */
#ifndef QNAV_FIXED_HOST_H
#define QNAV_FIXED_HOST_H

#include "qnav/fixed.h"

#if defined(__AVR__) || (defined(__arm__) && !defined(__linux__))
#error "qnav/fixed_host.h is for host programs: firmware writes raw fixed-point values"
#endif

/* Literal conversions from compile-time constants (x must be a constant expression).
 * Both round halves away from zero and saturate to the type's range. */
#define QNAV_Q1_15(x)                                                                    \
    ((qnav_q1_15_t)((x) >= 1.0 ? QNAV_Q1_15_MAX                                          \
                    : (x) <= -1.0 ? -QNAV_Q1_15_MAX - 1                                  \
                    : (x) < 0 ? (int32_t)((x) * (double)QNAV_Q1_15_ONE_RAW - 0.5)        \
                              : (int32_t)((x) * (double)QNAV_Q1_15_ONE_RAW + 0.5)))
#define QNAV_Q8_8(x) ((qnav_q8_8_t)((x) < 0 ? (int32_t)((x) * 256.0 - 0.5) : (int32_t)((x) * 256.0 + 0.5)))

/* Raw values back to real numbers, for host programs and tests only (the firmware has no
 * floating point): QNAV_Q1_15_TO_REAL(16384) is 0.5. */
#define QNAV_Q1_15_TO_REAL(q) ((double)(q) / (double)QNAV_Q1_15_ONE_RAW)
#define QNAV_Q8_8_TO_REAL(q) ((double)(q) / (double)QNAV_Q8_8_ONE)

#endif /* QNAV_FIXED_HOST_H */
