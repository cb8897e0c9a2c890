/*
 * A decision as two wheel speeds (qnav/drive.h).
 */
#include "qnav/drive.h"

#include <stddef.h>

#include "qnav/trig.h"

/* Full wheel speed, Q1.15. */
#define FULL ((int32_t)32767)

/* The decision's forward part, Q1.15: speed * cos(heading), 0 at 90 deg and beyond. */
static int32_t forward_part(int32_t mag, qnav_q1_15_t speed)
{
    int16_t c;
    int16_t s;
    if (speed <= 0 || mag >= 90) {
        return 0;
    }
    qnav_cos_sin_q14(mag * 100, &c, &s);
    return ((int32_t)speed * c) / 16384;
}

static int32_t magnitude(qnav_deg_t heading_deg)
{
    const int32_t h = heading_deg;
    return h < 0 ? -h : h;
}

/* No forward part while the robot rolls forward at all: brake to a stop, then turn. */
static int brakes(int32_t fwd, qnav_q1_15_t rolling)
{
    return fwd == 0 && rolling > 0;
}

int qnav_drive_brakes_first(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling)
{
    return brakes(forward_part(magnitude(heading_deg), speed), rolling);
}

int qnav_drive_servo_brakes_first(qnav_deg_t heading_deg, qnav_q1_15_t rolling)
{
    return magnitude(heading_deg) >= 90 && rolling > QNAV_DRIVE_STOPPED;
}

void qnav_drive_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling,
                    uint16_t turn_full_deg, qnav_q1_15_t *left, qnav_q1_15_t *right)
{
    const int32_t mag = magnitude(heading_deg);
    const int32_t full_at = turn_full_deg == 0u ? 1 : (int32_t)turn_full_deg;
    int32_t fwd = forward_part(mag, speed);
    int32_t turn = mag >= full_at ? FULL : (FULL * mag) / full_at;
    if (left == NULL || right == NULL) {
        return;
    }
    if (brakes(fwd, rolling)) {
        *left = 0; /* docs/sim.md, "Brake, then turn" */
        *right = 0;
        return;
    }
    if (fwd + turn > FULL) { /* one factor for both: the same arc, slower */
        int32_t sum = fwd + turn;
        fwd = (fwd * FULL) / sum;
        turn = (turn * FULL) / sum;
    }
    if (heading_deg < 0) {
        turn = -turn;
    }
    *left = (qnav_q1_15_t)(fwd - turn);
    *right = (qnav_q1_15_t)(fwd + turn);
}

qnav_q1_15_t qnav_drive_rolling(int32_t travel_um, uint16_t tick_ms, uint16_t v_max_mm_s)
{
    /* mm/s * ms = um: full speed's travel in one tick */
    uint32_t full = (uint32_t)tick_ms * v_max_mm_s;
    uint32_t mag = travel_um < 0 ? 0u - (uint32_t)travel_um : (uint32_t)travel_um;
    int32_t r;
    if (full == 0u) {
        return 0;
    }
    if (mag >= full) {
        return (qnav_q1_15_t)(travel_um < 0 ? -FULL : FULL);
    }
    while (full > UINT32_C(65535)) { /* mag < full: mag * 32767 then fits 31 bits */
        full >>= 1;
        mag >>= 1;
    }
    r = (int32_t)((mag * (uint32_t)FULL) / full);
    return (qnav_q1_15_t)(travel_um < 0 ? -r : r);
}
