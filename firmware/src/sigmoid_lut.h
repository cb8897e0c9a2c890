/*
 * The sigmoid lookup table shared by the network's hidden and output units (private).
 * 4096 entries of Q1.15, indexed by the top 12 bits of a Q4.12 input offset by 8.
 */
#ifndef QNAV_SIGMOID_LUT_H
#define QNAV_SIGMOID_LUT_H

#include <stdint.h>
#include "qnav/flash.h"

#define QNAV_SIGMOID_LUT_SIZE 4096

extern const uint16_t qnav_sigmoid_lut[QNAV_SIGMOID_LUT_SIZE] QNAV_FLASH;

/* sigmoid(z) for z in Q4.12 ([-8, 8)), result Q1.15 in [0, 32767].
 * @par Scaling and overflow: input covers the whole int16 range, no overflow. */
static inline int16_t qnav_sigmoid_q4_12(int16_t z)
{
    uint16_t index = (uint16_t)((uint16_t)((uint16_t)z ^ 0x8000u) >> 4);
    return (int16_t)QNAV_FLASH_READ_U16(&qnav_sigmoid_lut[index]);
}

#endif /* QNAV_SIGMOID_LUT_H */
