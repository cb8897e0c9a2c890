/*
 * A decision (heading, speed) as a differential drive's two wheel speeds: what a board
 * that drives its own motors does each tick (the TekBot's), and what the simulator does
 * with a profile whose [drive] model is "mix" (docs/sim.md, "Drive model"), so the robot
 * evolution scored turns and brakes as the board's.
 */
#ifndef QNAV_DRIVE_H
#define QNAV_DRIVE_H

#include "qnav/fixed.h"

#ifdef __cplusplus
extern "C" {
#endif

/* At or beyond this |heading| a decision is a turn in place (the TekBot's board). */
#define QNAV_DRIVE_SPIN_DEG 60

/* The forward part falls linearly from speed at heading 0 to 0 at spin_deg (none at speed
 * 0); the turn part is proportional to the heading, full wheel speed at 90 deg and beyond
 * (each wheel saturates at full speed), whatever the speed: speed 0 with a heading turns in place, heading 0 and speed 0
 * stop. left and right are Q1.15 fractions of full wheel speed, signed, forward positive;
 * a counter-clockwise (positive) heading runs the right wheel faster. spin_deg < 1 counts
 * as 1. */
void qnav_drive_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_deg_t spin_deg,
                    qnav_q1_15_t *left, qnav_q1_15_t *right);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_DRIVE_H */
