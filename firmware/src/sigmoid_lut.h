/*
 * The sigmoid lookup table shared by the network's hidden and output units (private):
 * 4097 Q1.15 entries on a 1/128 grid over [-16, 16], read with linear interpolation.
 */
#ifndef QNAV_SIGMOID_LUT_H
#define QNAV_SIGMOID_LUT_H

#include <stdint.h>
#include "qnav/flash.h"

#define QNAV_SIGMOID_LUT_SIZE 4097

extern const uint16_t qnav_sigmoid_lut[QNAV_SIGMOID_LUT_SIZE] QNAV_FLASH;

/* The table's flat ends in Q5.11: sigmoid is 0 at and below QNAV_SIGMOID_LAST_ZERO and
 * 32767 at and above QNAV_SIGMOID_FIRST_TOP (checked against the table by test_ctrl). */
#define QNAV_SIGMOID_LAST_ZERO (-22713)
#define QNAV_SIGMOID_FIRST_TOP 20456

/*
 * sigmoid(z) for z in Q5.11 ([-16, 16)), result Q1.15 in [0, 32767].
 * @par Scaling and overflow: u = z + 16 in units of 2^-11 is a uint16; its top 12 bits
 * pick the grid point below z (at most 4095, so entry + 1 exists), its low 4 bits the
 * fraction. Neighbouring entries differ by at most 64, so diff * frac < 2^10.
 * Error: interpolation below 1e-6, rounding at most 2^-15.
 */
static inline int16_t qnav_sigmoid_q5_11(int16_t z)
{
    uint16_t u = (uint16_t)((uint16_t)z ^ 0x8000u);
    uint16_t i = (uint16_t)(u >> 4);
    uint16_t lo = QNAV_FLASH_READ_U16(&qnav_sigmoid_lut[i]);
    uint16_t hi = QNAV_FLASH_READ_U16(&qnav_sigmoid_lut[i + 1u]);
    uint8_t frac = (uint8_t)(u & 15u);
    /* hi - lo <= 64 and frac <= 15: an 8 x 8 bit product (one MUL on AVR) */
    return (int16_t)(lo + (uint16_t)(((uint16_t)((uint8_t)(hi - lo) * frac) + 8u) >> 4));
}

#endif /* QNAV_SIGMOID_LUT_H */
