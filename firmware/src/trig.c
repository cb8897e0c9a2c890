/*
 * Integer trigonometry (qnav/trig.h): CORDIC in 32-bit integers,
 * angles in 1/64 of 0.01 deg inside, 16 iterations. No floats, no tables in RAM (the 16
 * arctangents are constants in code), no file-scope state.
 */
#include "qnav/trig.h"

#include <stddef.h>

#define ITER 16u
#define UNIT INT32_C(64)                  /* internal angle units per 0.01 deg */
#define LIMIT INT32_C(2097152)            /* inputs clamped to +-2^21 */
#define K_Q14 INT32_C(9949)               /* CORDIC gain inverse, prod 1/sqrt(1 + 2^-2i), Q2.14 */

/* atan(2^-i) in 0.01 deg * 64 (python: round(degrees(atan(2**-i)) * 6400)). */
static int32_t atan_step(uint8_t i)
{
    switch (i) {
    case 0: return INT32_C(288000);
    case 1: return INT32_C(170016);
    case 2: return INT32_C(89832);
    case 3: return INT32_C(45600);
    case 4: return INT32_C(22889);
    case 5: return INT32_C(11455);
    case 6: return INT32_C(5729);
    case 7: return INT32_C(2865);
    case 8: return INT32_C(1432);
    case 9: return INT32_C(716);
    case 10: return INT32_C(358);
    case 11: return INT32_C(179);
    case 12: return INT32_C(90);
    case 13: return INT32_C(45);
    case 14: return INT32_C(22);
    default: return INT32_C(11);
    }
}

/* v / 2^s rounded toward zero, without shifting a negative number. */
static int32_t shr(int32_t v, uint8_t s)
{
    return v >= 0 ? (int32_t)((uint32_t)v >> s) : -(int32_t)((uint32_t)(-v) >> s);
}

static int32_t clamp(int32_t v)
{
    return v > LIMIT ? LIMIT : (v < -LIMIT ? -LIMIT : v);
}

qnav_cdeg_t qnav_wrap_cdeg(int32_t a)
{
    a %= INT32_C(36000);
    if (a < -INT32_C(18000)) {
        a += INT32_C(36000);
    } else if (a >= INT32_C(18000)) {
        a -= INT32_C(36000);
    }
    return (qnav_cdeg_t)a;
}

void qnav_cos_sin_q14(int32_t a_cdeg, int16_t *cos_q14, int16_t *sin_q14)
{
    int32_t a = qnav_wrap_cdeg(a_cdeg);
    int32_t x = K_Q14 * INT32_C(1024); /* 10 more bits inside, rounded off at the end */
    int32_t y = 0;
    int32_t z;
    int8_t flip = 1;
    uint8_t i;
    if (a > INT32_C(9000)) {
        a -= INT32_C(18000);
        flip = -1;
    } else if (a < -INT32_C(9000)) {
        a += INT32_C(18000);
        flip = -1;
    }
    z = a * UNIT;
    for (i = 0; i < ITER; ++i) {
        int32_t dx = shr(y, i);
        int32_t dy = shr(x, i);
        if (z >= 0) {
            x -= dx;
            y += dy;
            z -= atan_step(i);
        } else {
            x += dx;
            y -= dy;
            z += atan_step(i);
        }
    }
    x = (x + (x >= 0 ? 512 : -512)) / 1024;
    y = (y + (y >= 0 ? 512 : -512)) / 1024;
    x = x > INT32_C(16384) ? INT32_C(16384) : (x < -INT32_C(16384) ? -INT32_C(16384) : x);
    y = y > INT32_C(16384) ? INT32_C(16384) : (y < -INT32_C(16384) ? -INT32_C(16384) : y);
    if (cos_q14 != NULL) {
        *cos_q14 = (int16_t)(flip * x);
    }
    if (sin_q14 != NULL) {
        *sin_q14 = (int16_t)(flip * y);
    }
}

qnav_cdeg_t qnav_atan2_cdeg(int32_t y, int32_t x, uint32_t *dist)
{
    int32_t z = 0;
    uint8_t i;
    uint8_t up = 0;
    x = clamp(x);
    y = clamp(y);
    if (x == 0 && y == 0) {
        if (dist != NULL) {
            *dist = 0;
        }
        return 0;
    }
    if (x < 0) { /* rotate by 180 deg into the right half-plane */
        x = -x;
        y = -y;
        z = INT32_C(18000) * UNIT;
    }
    /* full resolution whatever the length: the largest of |x|, |y| into [2^20, 2^21]
     * (2^21 * sqrt(2) * 1.65 < 2^31) */
    while (x < INT32_C(1048576) && y < INT32_C(1048576) && y > -INT32_C(1048576)) {
        x *= 2;
        y *= 2;
        up++;
    }
    for (i = 0; i < ITER; ++i) {
        int32_t dx = shr(y, i);
        int32_t dy = shr(x, i);
        if (y > 0) {
            x += dx;
            y -= dy;
            z += atan_step(i);
        } else {
            x -= dx;
            y += dy;
            z -= atan_step(i);
        }
    }
    if (dist != NULL) {
        /* x = length * 1.6468 * 2^up: divide by the gain, m < 2^21 * 1.42 * 1.65 */
        uint32_t m = (uint32_t)x;
        if (up > 0u) {
            m = (m + ((uint32_t)1 << (up - 1u))) >> up;
        }
        *dist = (m / 16u) * (uint32_t)K_Q14 / 1024u + ((m % 16u) * (uint32_t)K_Q14) / 16384u;
    }
    z = z >= 0 ? (z + UNIT / 2) / UNIT : -((-z + UNIT / 2) / UNIT);
    return qnav_wrap_cdeg(z);
}
