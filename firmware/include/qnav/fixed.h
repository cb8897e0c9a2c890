/*
 * Fixed-point and unit types shared by every libqnav module. Types are named by Q format
 * with the sign bit counted (qnav_q1_15_t is Q1.15 in int16_t: value = raw / 2^15) or by
 * unit (qnav_mm_t is millimetres). docs/qformats.md lists every quantity, its range and
 * resolution. No int, long or double here: int is 16 bits on AVR.
 */
#ifndef QNAV_FIXED_H
#define QNAV_FIXED_H

#include <stdint.h>

/* Q1.15 in int16_t: [-1, 1), resolution 2^-15. Qualities and speeds use [0, 1). */
typedef int16_t qnav_q1_15_t;
/* Q8.8 in int16_t: [-128, 128), resolution 1/256. Policy weights and parameters. */
typedef int16_t qnav_q8_8_t;
/* Distance in millimetres, 0..65535. */
typedef uint16_t qnav_mm_t;
/* Angle in hundredths of a degree, counter-clockwise positive. */
typedef int16_t qnav_cdeg_t;
/* Angle in whole degrees, counter-clockwise positive. */
typedef int16_t qnav_deg_t;

#define QNAV_Q1_15_ONE_RAW 32768L /* 1.0 in Q1.15 (itself out of range: use _MAX) */
#define QNAV_Q1_15_MAX 32767
#define QNAV_Q8_8_ONE 256
#define QNAV_Q8_8_MAX 32767
#define QNAV_Q8_8_MIN (-32767 - 1)

/* Conversions from and to real numbers, for host programs and tests, are in
 * qnav/fixed_host.h: the firmware has no floating point, not even in constant
 * expressions, so its sources write raw values. */

#endif /* QNAV_FIXED_H */
