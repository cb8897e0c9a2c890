/*
 * Leaving dead ends (private to libqnav): a Bug-family boundary follower in front of every
 * path controller (docs/architecture.md, "Leaving dead ends"). A memoryless map of
 * (range, bearing) to quality has local minima: a U-pocket facing the destination, a wall
 * whose gap lies off the straight line. While the robot makes progress toward the
 * destination nothing changes. When it has made none for escape_stall_ticks, it follows
 * the boundary in front of it on one side: the policy is given, instead of the
 * destination's bearing, the bearing of the free path that skirts the obstacle (from the
 * nearest reading on that side, turning away from it, the first free path; a stall far
 * nearer than where the last follow ended is at another obstacle and chooses its side
 * afresh; one no nearer than where the last follow began means that follow led back
 * here, and it goes the other way round). A follow that comes back to a place it marked
 * (the destination's range and bearing as they were there) has gone round an island; it
 * leaves where it is again as near the destination as it came on the way round (Bug1).
 * It goes back to the
 * destination once the clear way toward it, read from the sonar sector that looks that
 * way, ends a step nearer to it than at the hit point (DistBug's leave rule); a follow that
 * lasts too long without getting nearer, or that leads far from the destination with open
 * space on its other hand, is given up for the other side, each try twice as long or far. While following, a step whose policy would stand still crawls along the
 * boundary or turns in place, so no policy freezes.
 *
 * The memory (qnav_escape_t, 24 bytes) is the caller's: it comes in with the step's input
 * and goes out with its output; the step itself keeps nothing.
 */
#ifndef QNAV_ESCAPE_H
#define QNAV_ESCAPE_H

#include "qnav/ctrl.h"

/* Check and derive the escape's parameters into c (init time). Returns QNAV_OK. */
QNAV_CHECK_RESULT qnav_status_t qnav_escape_setup(qnav_clearance_t *c,
                                                  const qnav_ctrl_config_t *cfg);

/*
 * Update the memory e (from in->escape) with this tick's distance to the destination and
 * return the bearing, in whole degrees 0..359 (path index), that the controller should
 * steer for: the destination's while going to it, the boundary's while following one.
 * Without an escape (configured off, or in->goal_range_mm 0) e is cleared and the
 * destination's bearing is returned. lvl: the 360 path levels of this tick.
 */
uint16_t qnav_escape_goal(const qnav_clearance_t *c, const uint8_t *lvl,
                          const qnav_ctrl_input_t *in, qnav_escape_t *e);

/* Zero the memory (going to the destination, nothing seen yet). */
void qnav_escape_clear(qnav_escape_t *e);

/* While following a boundary, a decision that moves goes at least at the speed guard's cap
 * for the lowest clearance of its path, straight ahead and the boundary's half (the
 * policy's speed is its confidence in a way toward the destination, which a follow is not),
 * and one that stands still becomes a crawl along the boundary path goal (or a turn in
 * place toward it when that path is not free). */
void qnav_escape_keep_moving(const qnav_clearance_t *c, const uint8_t *lvl,
                             const qnav_escape_t *e, uint16_t goal, qnav_ctrl_output_t *out);

/*
 * A turn keeps its way round. When this decision lies more than 90 degrees off straight
 * ahead and the last one (prev, whole degrees 0..359, in this tick's frame) on the other
 * side, and the shorter way from one to the other passes behind the robot, the decision
 * becomes a turn the same way round as the last one (179 or -179 degrees). Without it a
 * robot turning in place toward a path behind it, whose scan changes with every degree it
 * turns, can be sent left and right on alternate ticks and stand where it is.
 */
void qnav_escape_hold_turn(uint16_t prev, qnav_ctrl_output_t *out);

/*
 * A robot that stands does not stand for ever. A decision whose speed is 0 counts a tick in
 * out->escape.stood; a moving one halves it, so that a robot that drives clears it within
 * a few ticks and one that twitches now and then does not. Past twice escape_stall_ticks
 * the decision becomes the middle of a free window: the path nearest the last decision
 * (prev, whole degrees 0..359 in this tick's frame, so that the robot turns on toward one
 * way) with every path within 5 degrees either side free; at a crawl once the robot faces
 * it and straight ahead is clear, turning in place until then. Without such a window the
 * robot turns in place as decided. The escape's own stall acts after one stall time; a
 * robot stands past two when a map's plans keep clearing the memory (a new plan does not
 * move it) or a follow turns in place. qnav_escape_unstand is called after every other rule
 * of the decision but the turn's way round (qnav_escape_hold_turn); qnav_escape_stood is
 * its out-of-line part, for a decision that stands.
 */
void qnav_escape_stood(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t prev,
                       qnav_ctrl_output_t *out);
static inline void qnav_escape_unstand(const qnav_clearance_t *c, const uint8_t *lvl,
                                       uint16_t prev, qnav_ctrl_output_t *out)
{
    if (out->speed != 0) {
        out->escape.stood = (uint8_t)(out->escape.stood >> 1); /* a twitch is no drive */
    } else {
        qnav_escape_stood(c, lvl, prev, out); /* the rare case, out of line */
    }
}

#endif /* QNAV_ESCAPE_H */
