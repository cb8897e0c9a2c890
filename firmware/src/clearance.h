/*
 * Body-aware clearance (private to libqnav): which distance level each of the 360 paths
 * sees, and how fast the robot may drive along it. A sector's reading blocks its own
 * wedge and, enlarged as in VFH+ (Ulrich & Borenstein 1998), every path within
 * gamma = asin((r_robot + d_safe) / D) of it, D the obstacle's distance from the robot's
 * centre (range + sensor offset); a path's level is the nearest reading whose enlarged arc covers it. With
 * r_robot = d_safe = 0 every gamma is 0 and a path sees exactly its own sector (the
 * paper's literal mapping). The speed guard caps the speed at what the path's clearance
 * can stop in. Everything per level is computed at init; the step only paints bytes and
 * lowers each reading's gamma from its level's (the level's smallest range) to the
 * reading's own distance.
 */
#ifndef QNAV_CLEARANCE_H
#define QNAV_CLEARANCE_H

#include "qnav/ctrl.h"

/* On x86 hosts (SSE2) the level walks take 16 path levels at a time (clearance.c's
 * painting, escape.c's nearest reading); the other targets keep their byte loops. */
#if !defined(__AVR__) && defined(__SSE2__)
#define QNAV_LEVELS_SSE2 1
#include <emmintrin.h>

/* The 16 path levels from q on, any alignment. */
static inline __m128i qnav_levels16(const uint8_t *q)
{
    return _mm_loadu_si128((const __m128i *)(const void *)q);
}
#endif

/* Check cfg's sensor fields and derive everything in c (init time; integer only).
 * Returns QNAV_OK, QNAV_E_SECTORS or QNAV_E_RANGE (c is then unusable). */
QNAV_CHECK_RESULT qnav_status_t qnav_clearance_setup(qnav_clearance_t *c,
                                                     const qnav_ctrl_config_t *cfg);

/* Fill c->enlarge_deg[] and the speed guard's parameters and levels from cfg (init time;
 * integer only). */
void qnav_clearance_init(qnav_clearance_t *c, const qnav_ctrl_config_t *cfg);

/* The speed guard's cap for a path at level: the largest speed (Q1.15 of v_max) that stops
 * within the level's clearance after one reaction tick (QNAV_Q1_15_MAX without a guard or
 * at the farthest level; a level that holds the sonar's minimum range counts as an
 * obstacle at the transducers, since the sonar reads that range for anything nearer), the same as computing it for every step. @par Cost: two
 * compares for levels whose cap is 0 or full speed; for the levels between them (found at
 * init: one on the TekBot's profile, five on the Pioneer's) a binary search over ranges, a
 * square root and two divisions, about 2 000 cycles on the ATmega128. */
qnav_q1_15_t qnav_clearance_speed_cap(const qnav_clearance_t *c, uint8_t level);

/* The speed guard while turning to path (0..359): the robot still moves along its present
 * heading (path 0) until it has turned, so the cap is that of the nearer of the two. */
qnav_q1_15_t qnav_clearance_turn_cap(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t path);

/*
 * The destination in reach (docs/architecture.md, "The destination in reach"): the sector
 * under the destination's bearing when its reading lies beyond the destination by at least
 * the body's margin (range + sensor offset >= goal range + margin_mm), so that what it saw
 * cannot stop the robot before it arrives; c->n_sectors when there is none (the goal range
 * unknown, 0, or the sector clear anyway).
 */
uint16_t qnav_clearance_reach_sector(const qnav_clearance_t *c, const qnav_ctrl_input_t *in);

/*
 * The distance level of every path (lvl[i] for path i, i = 0..359) from the n_sectors
 * ranges: the minimum over the sectors whose enlarged arc covers the path, sector skip
 * (< n_sectors; n_sectors for none) counted as clear.
 * Returns QNAV_FLAG_RANGE_CLIPPED when a range above max_range_mm was clipped, else 0.
 * @par Cost: 360 byte writes plus count + 2 * gamma per sector nearer than the maximum.
 */
uint8_t qnav_clearance_levels(const qnav_clearance_t *c, const qnav_mm_t *ranges, uint16_t skip,
                              uint8_t *lvl);

/* Every path's level as a step sees it: from the input's ranges, with the destination in
 * reach counted clear. What every controller's step calls. */
static inline uint8_t qnav_clearance_input_levels(const qnav_clearance_t *c,
                                                  const qnav_ctrl_input_t *in, uint8_t *lvl)
{
    return qnav_clearance_levels(c, in->ranges_mm, qnav_clearance_reach_sector(c, in), lvl);
}

/* The distance level of a range, mm (docs/qformats.md; at or beyond max_range_mm:
 * QNAV_DIST_LEVELS - 1). */
uint8_t qnav_clearance_level_of(const qnav_clearance_t *c, qnav_mm_t range_mm);

#endif /* QNAV_CLEARANCE_H */
