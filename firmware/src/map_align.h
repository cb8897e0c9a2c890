/*
 * The map's grid turned to the walls it sees (qnav/map.h, qnav_map_config_t.align_samples;
 * docs/architecture.md, "A grid turned to the walls"): the caller's poses and points into
 * the grid's frame, and the estimate of the walls' direction that turns it. map.c owns the
 * cells; this file owns the frame.
 */
#ifndef QNAV_MAP_ALIGN_H
#define QNAV_MAP_ALIGN_H

#include <stdint.h>

#include "qnav/map.h"

/* A new map about pose-frame centre (x, y): its grid in the pose's frame, nothing counted. */
void qnav_align_start(qnav_map_t *m, int32_t x_mm, int32_t y_mm);

/* Pose-frame point (*x, *y) into the grid's frame, in place. */
void qnav_align_point(const qnav_map_t *m, int32_t *x_mm, int32_t *y_mm);

/* A pose in the grid's frame. */
qnav_map_pose_t qnav_align_pose(const qnav_map_t *m, const qnav_map_pose_t *pose);

/* Counts the walls' nearest points in this scan from pose (pose frame); 1 when the grid
 * turned to them (the cells marked so far then lie in the old grid: the caller forgets
 * them). */
int qnav_align_observe(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *pose);

#endif
