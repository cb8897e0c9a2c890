/*
 * The sigmoid lookup table shared by the network's hidden and output units and by the
 * pre-activation keys of compiled tables (private): Q1.15 values on a 1/128 grid over
 * [-16, 16], read with linear interpolation. Only the grid points between the flat ends
 * are stored (2 700 of 4 097): the ends are returned without reading the table.
 */
#ifndef QNAV_SIGMOID_LUT_H
#define QNAV_SIGMOID_LUT_H

#include <stdint.h>
#include "qnav/flash.h"

/* The flat ends in Q5.11: sigmoid is 0 at and below QNAV_SIGMOID_LAST_ZERO and 32767 at
 * and above QNAV_SIGMOID_FIRST_TOP (tools/gen_sigmoid_lut.py checks them against the
 * grid; sigmoid_lut.c stops with #error if they differ). */
#define QNAV_SIGMOID_LAST_ZERO (-22713)
#define QNAV_SIGMOID_FIRST_TOP 20456

/* The grid points stored: from the one below QNAV_SIGMOID_LAST_ZERO + 1 (value 0) to the
 * one above QNAV_SIGMOID_FIRST_TOP - 1 (value 32767); entry k is grid point k + FIRST. */
#define QNAV_SIGMOID_LUT_FIRST 628
#define QNAV_SIGMOID_LUT_SIZE 2700

extern const uint16_t qnav_sigmoid_lut[QNAV_SIGMOID_LUT_SIZE] QNAV_FLASH;

/*
 * sigmoid(z) for z in Q5.11 strictly between the flat ends (QNAV_SIGMOID_LAST_ZERO <
 * z < QNAV_SIGMOID_FIRST_TOP), result Q1.15 in [1, 32766]: for callers that have already
 * taken the ends (the network's hidden units).
 * @par Scaling and overflow: u = z + 16 in units of 2^-11 is a uint16; its top 12 bits
 * pick the grid point below z (628..3326 here, so entry and entry + 1 are stored), its low
 * 4 bits the fraction. Neighbouring entries differ by at most 64, so diff * frac < 2^10.
 * Error: interpolation below 1e-6, rounding at most 2^-15.
 */
static inline int16_t qnav_sigmoid_q5_11_between(int16_t z)
{
    uint16_t u = (uint16_t)((uint16_t)z ^ 0x8000u);
    uint16_t i = (uint16_t)((u >> 4) - QNAV_SIGMOID_LUT_FIRST);
    uint16_t lo = QNAV_FLASH_READ_U16(&qnav_sigmoid_lut[i]);
    uint16_t hi = QNAV_FLASH_READ_U16(&qnav_sigmoid_lut[i + 1u]);
    uint8_t frac = (uint8_t)(u & 15u);
    /* hi - lo <= 64 and frac <= 15: an 8 x 8 bit product (one MUL on AVR) */
    return (int16_t)(lo + (uint16_t)(((uint16_t)((uint8_t)(hi - lo) * frac) + 8u) >> 4));
}

/*
 * sigmoid(z) for any z in Q5.11 ([-16, 16)), result Q1.15 in [0, 32767]: the flat ends
 * without the table, the rest through qnav_sigmoid_q5_11_between(). The same values as an
 * interpolation over the whole grid: tools/gen_sigmoid_lut.py finds the flat ends on the
 * whole grid and stores every point read between them; test_ctrl checks every z for the
 * ends and monotony, and the shared vectors the outputs on every target.
 */
static inline int16_t qnav_sigmoid_q5_11(int16_t z)
{
    if (z <= QNAV_SIGMOID_LAST_ZERO) {
        return 0;
    }
    if (z >= QNAV_SIGMOID_FIRST_TOP) {
        return 32767;
    }
    return qnav_sigmoid_q5_11_between(z);
}

#endif /* QNAV_SIGMOID_LUT_H */
