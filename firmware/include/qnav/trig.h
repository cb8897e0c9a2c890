/*
 * Integer trigonometry (CORDIC, 16 iterations, no tables in RAM, no floats): the board's
 * pose and the map's geometry (qnav/map.h) share it.
 */
#ifndef QNAV_TRIG_H
#define QNAV_TRIG_H

#include <stdint.h>

#include "qnav/fixed.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * qnav_cos_sin_q14: cos and sin of a (0.01 deg, any value) in Q2.14 (16384 = 1),
 * error <= 2/16384. qnav_atan2_cdeg: direction of (x, y) in 0.01 deg, -18000..17999
 * (0 for the origin), error <= 1 cdeg for |x|, |y| up to 2^21; *dist (may be NULL) its
 * length, same unit as x and y, error <= 0.1 % + 2.
 * @par Scaling and overflow: inputs are clamped to +-2^21.
 */
void qnav_cos_sin_q14(int32_t a_cdeg, int16_t *cos_q14, int16_t *sin_q14);
/* An angle in 0.01 deg wrapped into -18000..17999. */
qnav_cdeg_t qnav_wrap_cdeg(int32_t a_cdeg);
qnav_cdeg_t qnav_atan2_cdeg(int32_t y, int32_t x, uint32_t *dist);

#ifdef __cplusplus
}
#endif

#endif
