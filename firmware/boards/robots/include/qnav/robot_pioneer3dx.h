/*
 * The pioneer3dx's board configuration, generated from its robot profile
 * (data/robots/pioneer3dx.toml) by
 *   qnav-sim robot-header --robot pioneer3dx firmware/boards/robots/include/qnav/robot_pioneer3dx.h
 * Do not edit: change the profile and run the command again. The test
 * board.robot_headers_match_profiles fails while this file differs from what the
 * command writes (docs/hil.md, "One robot description").
 */
#ifndef QNAV_ROBOT_PIONEER3DX_H
#define QNAV_ROBOT_PIONEER3DX_H

#define QNAV_ROBOT_PIONEER3DX_NAME "pioneer3dx"

/* Heading change per differential encoder count (right minus left), 1e-6 deg:
 * um_per_count / track_mm rad. */
#define QNAV_ROBOT_PIONEER3DX_UDEG_PER_COUNT 84207L

/* Where its mixer turns at full wheel speed (qnav_drive_mix), deg: 2 v_max /
 * (track x heading_gain_per_s) rad. */
#define QNAV_ROBOT_PIONEER3DX_TURN_FULL_DEG 116u

/* A qnav_board_config_t (qnav/board.h): the fields of QNAV_BOARD_ROBOT_FIELDS from the
 * profile, the rest qnav_board_config_default()'s. */
#define QNAV_ROBOT_PIONEER3DX_CONFIG \
    { \
        .ctrl.n_sectors = 16, \
        .ctrl.max_range_mm = 5000, \
        .ctrl.full_speed_quality = 29491, \
        .ctrl.body_radius_mm = 260, \
        .ctrl.safety_mm = 20, \
        .ctrl.sensor_offset_mm = 260, \
        .ctrl.v_max_mm_s = 1000, \
        .ctrl.decel_mm_s2 = 600, \
        .ctrl.rank = 1, \
        .ctrl.wedge_pct = 10, \
        .ctrl.wedge_near_mm = 0, \
        .ctrl.escape_stall_ticks = 40, \
        .ctrl.escape_follow_mm = 800, \
        .ctrl.escape_follow_s = 20, \
        .ctrl.keep_pct = 15, \
        .ctrl.range_min_mm = 100, \
        .ctrl.pass_mm = 20, \
        .ctrl.quality_full_speed = 26214, \
        .tick_ms = 100, \
        .track_mm = 330, \
        .um_per_count = 485, \
        .turn_full_deg = 116, \
        .link_timeout_ms = 300, \
        .nvm_offset = 0, \
        .controller = "body" \
    }

/* The profile's [map], on: the map the board places at each position goal
 * (qnav_board_place_maps), a qnav_map_config_t. */
#define QNAV_ROBOT_PIONEER3DX_MAP_CONFIG \
    { \
        .cell_mm = 500, .reach_mm = 3000, .look_mm = 1500, .jump_mm = 1000, \
        .plan_ticks = 10, .noise_pct = 1, .near_cost = 0, .near_mm = 200, \
        .arc_cdeg = 2250, .arc_width_mm = 0, .sight = 1, .escape_grow = 1, \
        .refuse_ticks = 10, .refuse_life_ticks = 200, .compact = 1, .grow_steps = 16, \
        .forget_reach_mm = 0, .opening_mm = 0, .unknown_cost = 0, .align_samples = 40, \
        .turn_back_ticks = 10 \
    }

/* The profile's [map] bytes: the board's memory for that map, the largest
 * square of its cells they hold placed at each goal (qnav_map_place). */
#define QNAV_ROBOT_PIONEER3DX_MAP_BYTES 512u

#endif /* QNAV_ROBOT_PIONEER3DX_H */
