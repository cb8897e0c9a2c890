/*
 * Types of the map's benchmark trace (bench_map_trace.h, written by bench/map_trace.c):
 * one tick is the robot's pose, its scan, and what the host's map made of them.
 */
#ifndef QNAV_BENCH_MAP_H
#define QNAV_BENCH_MAP_H

#include <stdint.h>

#include "qnav/flash.h"

#define QNAV_BENCH_MAP_MAX_SECTORS 16u

typedef struct {
    int16_t x_mm, y_mm;        /* the robot's centre in the world (the map's frame), mm */
    int16_t heading_cdeg;      /* its heading, 0.01 deg */
    uint16_t ranges_mm[QNAV_BENCH_MAP_MAX_SECTORS]; /* the sonar's scan */
    int16_t bearing_cdeg;      /* the host's qnav_map_guide(): the sub-goal's bearing, */
    uint16_t range_mm;         /* the planned distance, */
    uint8_t flags;             /* its return value */
} qnav_bench_map_tick_t;

typedef struct {
    const char *name;
    int32_t x0_mm, y0_mm;         /* the map's square, placed as the board places it */
    uint32_t side_mm;             /* (qnav_map_place: midway between start and goal) */
    int32_t goal_x_mm, goal_y_mm;
    const qnav_bench_map_tick_t *ticks; /* in flash */
    uint16_t n_ticks;
} qnav_bench_map_world_t;

/* The controller configuration of the trace's robot (bench_map_trace.h's QNAV_BENCH_MAP_*),
 * which the map takes its body and sonar from: cc a qnav_ctrl_config_t pointer. */
#define QNAV_BENCH_MAP_CTRL_CONFIG(cc)                       \
    do {                                                     \
        qnav_ctrl_config_default(cc);                        \
        (cc)->n_sectors = QNAV_BENCH_MAP_SECTORS;            \
        (cc)->max_range_mm = QNAV_BENCH_MAP_RANGE_MM;        \
        (cc)->sensor_offset_mm = QNAV_BENCH_MAP_OFFSET_MM;   \
        (cc)->body_radius_mm = QNAV_BENCH_MAP_RADIUS_MM;     \
        (cc)->safety_mm = QNAV_BENCH_MAP_SAFETY_MM;          \
    } while (0)

#endif
