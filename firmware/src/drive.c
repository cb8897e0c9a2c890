/*
 * A decision as two wheel speeds (qnav/drive.h).
 */
#include "qnav/drive.h"

#include <stddef.h>

/* Full wheel speed, Q1.15: the turn part at |heading| >= 90 deg (measured: docs/sim.md,
 * "One drive for the simulated and the real TekBot"). */
#define TURN_MAX ((int32_t)32767)

static qnav_q1_15_t sat_q15(int32_t v)
{
    if (v > INT32_C(32767)) {
        return 32767;
    }
    if (v < -INT32_C(32767)) {
        return -32767;
    }
    return (qnav_q1_15_t)v;
}

void qnav_drive_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_deg_t spin_deg,
                    qnav_q1_15_t *left, qnav_q1_15_t *right)
{
    int32_t h = heading_deg;
    int32_t mag = h < 0 ? -h : h;
    int32_t fwd;
    int32_t turn;
    if (left == NULL || right == NULL) {
        return;
    }
    if (spin_deg < 1) {
        spin_deg = 1;
    }
    fwd = speed <= 0 || mag >= spin_deg ? 0 : ((int32_t)speed * (spin_deg - mag)) / spin_deg;
    turn = (mag >= 90 ? TURN_MAX : (TURN_MAX * mag) / 90) * (h < 0 ? -1 : 1);
    *left = sat_q15(fwd - turn);
    *right = sat_q15(fwd + turn);
}
