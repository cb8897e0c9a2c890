/*
 * The tekbot's board configuration, generated from its robot profile
 * (data/robots/tekbot.toml) by
 *   qnav-sim robot-header --robot tekbot firmware/boards/robots/include/qnav/robot_tekbot.h
 * Do not edit: change the profile and run the command again. The test
 * board.robot_headers_match_profiles fails while this file differs from what the
 * command writes (docs/hil.md, "One robot description").
 */
#ifndef QNAV_ROBOT_TEKBOT_H
#define QNAV_ROBOT_TEKBOT_H

#define QNAV_ROBOT_TEKBOT_NAME "tekbot"

/* Heading change per differential encoder count (right minus left), 1e-6 deg:
 * um_per_count / track_mm rad. */
#define QNAV_ROBOT_TEKBOT_UDEG_PER_COUNT 2187426L

/* Where its mixer turns at full wheel speed (qnav_drive_mix), deg: 2 v_max /
 * (track x heading_gain_per_s) rad. */
#define QNAV_ROBOT_TEKBOT_TURN_FULL_DEG 90u

/* A qnav_board_config_t (qnav/board.h): the fields of QNAV_BOARD_ROBOT_FIELDS from the
 * profile, the rest qnav_board_config_default()'s. */
#define QNAV_ROBOT_TEKBOT_CONFIG \
    { \
        .ctrl.n_sectors = 16, \
        .ctrl.max_range_mm = 2500, \
        .ctrl.full_speed_quality = 29491, \
        .ctrl.body_radius_mm = 120, \
        .ctrl.safety_mm = 50, \
        .ctrl.sensor_offset_mm = 120, \
        .ctrl.v_max_mm_s = 500, \
        .ctrl.decel_mm_s2 = 2000, \
        .ctrl.rank = 1, \
        .ctrl.wedge_pct = 25, \
        .ctrl.wedge_near_mm = 113, \
        .ctrl.escape_stall_ticks = 20, \
        .ctrl.escape_follow_mm = 500, \
        .ctrl.escape_follow_s = 20, \
        .ctrl.keep_pct = 15, \
        .ctrl.range_min_mm = 30, \
        .ctrl.pass_mm = 10, \
        .ctrl.quality_full_speed = 22938, \
        .tick_ms = 100, \
        .track_mm = 180, \
        .um_per_count = 6872, \
        .turn_full_deg = 90, \
        .link_timeout_ms = 300, \
        .nvm_offset = 0, \
        .controller = "body" \
    }

/* The profile's [map], on: the map the board places at each position goal
 * (qnav_board_place_maps), a qnav_map_config_t. */
#define QNAV_ROBOT_TEKBOT_MAP_CONFIG \
    { \
        .cell_mm = 300, .reach_mm = 2000, .look_mm = 1000, .jump_mm = 1000, \
        .plan_ticks = 5, .noise_pct = 10, .near_cost = 0, .near_mm = 200, \
        .arc_cdeg = 1800, .arc_width_mm = 0, .sight = 1, .escape_grow = 1, \
        .refuse_ticks = 30, .refuse_life_ticks = 200, .compact = 1, .grow_steps = 10, \
        .forget_reach_mm = 1000, .opening_mm = 270, .unknown_cost = 0, \
        .align_samples = 40, .turn_back_ticks = 10 \
    }

/* The profile's [map] bytes: the board's memory for that map, the largest
 * square of its cells they hold placed at each goal (qnav_map_place). */
#define QNAV_ROBOT_TEKBOT_MAP_BYTES 768u

#endif /* QNAV_ROBOT_TEKBOT_H */
