/*
 * A decision (heading, speed) as a differential drive's two wheel speeds: what a board
 * that drives its own motors does each tick (the TekBot's), and what the simulator does
 * with a profile whose [drive] model is "mix" (docs/sim.md, "Drive model"), so the robot
 * evolution scored turns and brakes as the board's.
 */
#ifndef QNAV_DRIVE_H
#define QNAV_DRIVE_H

#include <stdint.h>

#include "qnav/fixed.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A servo drive rolling forward slower than this (Q1.15 of full wheel speed: 1/8) counts as
 * stopped: a turn back may begin (qnav_drive_servo_brakes_first). The wheel mixer waits for
 * a stop (qnav_drive_brakes_first). */
#define QNAV_DRIVE_STOPPED ((qnav_q1_15_t)4096)

/*
 * The forward part is speed * cos(heading), none at 90 deg and beyond or at speed 0; the
 * turn part is proportional to the heading, full wheel speed at turn_full_deg and beyond,
 * whatever the speed. turn_full_deg is the robot's (its profile's 2 v_max / (track x
 * heading_gain_per_s) radians, so that a degree of heading asks the same turn rate of a
 * slow and a fast robot: docs/sim.md, "A turn in the robot's own units"); the TekBot's is 90;
 * 0 is taken as 1. When the two together would run a wheel past full speed both
 * shrink by one factor, so the robot drives the arc the decision asked for, slower. A
 * decision without a forward part (a turn in place) while the robot still rolls forward
 * at all (rolling > 0) brakes both wheels to 0 first: spinning one wheel forward would
 * keep the robot rolling toward what made it stop. Not just slower than a threshold: with
 * wheels that slew at equal rates a turn in place keeps the forward speed it starts from,
 * and a robot that brakes slowly crept on into what it turned from (until 0.20.1 the
 * threshold was QNAV_DRIVE_STOPPED; docs/sim.md, "A robot that brakes slowly"). rolling is the forward
 * speed the wheels have now (the mean of the two, Q1.15 of full wheel speed; a board's
 * from its encoders over the last tick, qnav_drive_rolling(); 0 when unknown). left and
 * right are Q1.15 fractions of full wheel speed, signed, forward positive; a
 * counter-clockwise (positive) heading runs the right wheel faster. Heading 0 and speed 0
 * stop.
 */
void qnav_drive_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling,
                    uint16_t turn_full_deg, qnav_q1_15_t *left, qnav_q1_15_t *right);

/*
 * 1 when a drive must brake before it carries out this decision: the decision has no
 * forward part (a turn in place: |heading| >= 90 deg, or speed 0, or a forward part that
 * rounds to nothing) while the robot still rolls forward (rolling > 0).
 * The drive then holds its heading and brakes to a stop, and turns on a later tick: a
 * robot that turned while it rolled on would carry its momentum toward the side it turns
 * to (docs/sim.md, "Brake, then turn"). qnav_drive_mix() applies it (a drive that servoes
 * its speed and turn apart asks qnav_drive_servo_brakes_first()).
 */
int qnav_drive_brakes_first(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling);

/*
 * The same question for a drive that servoes its forward speed and its turn on separate
 * profiles (the simulator's model "heading", as a Pioneer's ARCOS drives): it can brake and
 * turn at once, so only a decision 90 deg or more off (a turn back) waits until the robot
 * rolls slower than QNAV_DRIVE_STOPPED; a decision at speed 0 nearer ahead (the speed
 * guard's stop) brakes while it turns toward it. A turn back while rolling would carry the
 * robot's momentum toward the side it turns to; a small turn while braking leads it away
 * from what made it stop (docs/sim.md, "Brake, then turn"). The wheel mixer cannot brake
 * and turn at once and keeps qnav_drive_brakes_first().
 */
int qnav_drive_servo_brakes_first(qnav_deg_t heading_deg, qnav_q1_15_t rolling);

/* The forward speed of travel_um (the mean of the two wheels' travel, micrometres) over
 * one tick of tick_ms, as a Q1.15 fraction of v_max_mm_s, saturated to +-32767 (0 when
 * tick_ms or v_max_mm_s is 0). */
qnav_q1_15_t qnav_drive_rolling(int32_t travel_um, uint16_t tick_ms, uint16_t v_max_mm_s);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_DRIVE_H */
