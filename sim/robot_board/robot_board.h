/*
 * A robot profile as a board configuration (host only): the one mapping from
 * data/robots/NAME.toml to the board core's qnav_board_config_t, used by the header
 * generator (qnav-sim robot-header), the SIL robot, navbridge --robot and
 * qnav-simavr-board --robot, and the comparison of a board's CONFIG report with it (one
 * line naming the first field that differs). The controller part is
 * qnav_sim_robot_ctrl_config(): the simulator's controller and the board's are made by the
 * same function. Fields come from QNAV_BOARD_ROBOT_FIELDS (qnav/board.h).
 */
#ifndef QNAV_ROBOT_BOARD_H
#define QNAV_ROBOT_BOARD_H

#include <stddef.h>
#include <stdio.h>

#include "qnav/board.h"
#include "qnav/link.h"
#include "qnav/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The board configuration of robot: qnav_board_config_default() with ctrl =
 * qnav_sim_robot_ctrl_config(robot, 0), tick_ms = [control] tick_ms, track_mm = [body]
 * wheel_base_m, um_per_count = [odometry] um_per_count. */
void qnav_robot_board_config(const qnav_sim_robot_t *robot, qnav_board_config_t *cfg);

/* The map robot's board runs (its profile's [map] when on, in its [map] bytes), as the
 * board's CONFIG report gives it (qnav_board_map_info). */
void qnav_robot_board_map_info(const qnav_sim_robot_t *robot, qnav_board_map_info_t *info);

/* The same from a robot spec (a profile's path or name, as qnav_sim_robot_load takes it),
 * and its map when map is not NULL: QNAV_SIM_OK, or the loader's status with its message in
 * err. */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_robot_board_load(const char *spec,
                                                          qnav_board_config_t *cfg,
                                                          qnav_board_map_info_t *map, char *err,
                                                          size_t errlen);

/* The heading change per differential encoder count (right minus left), micro-degrees:
 * um_per_count / track_mm radians. What a board's HAL integrates for its heading. */
long qnav_robot_board_udeg_per_count(const qnav_board_config_t *cfg);

/* Write the generated C header for robot: QNAV_ROBOT_<NAME>_CONFIG (a complete
 * qnav_board_config_t initialiser), _NAME, _UDEG_PER_COUNT and _TURN_FULL_DEG. The text depends on the
 * profile only (its comment names the canonical command and committed path,
 * firmware/boards/robots/include/qnav/robot_<name>.h). Returns 0, or -1 when writing
 * failed. */
int qnav_robot_board_header(const qnav_sim_robot_t *robot, FILE *out);

/* Compare a board's CONFIG report with the configuration expected, and with the map
 * expected unless expected_map is NULL. Returns 0 when every QNAV_BOARD_ROBOT_FIELDS field
 * (then every QNAV_BOARD_MAP_FIELDS field) is reported with the expected value, else 1 with
 * "FIELD REPORTED != EXPECTED" (or "FIELD not reported") in line: the first field that
 * differs, in the lists' order. */
int qnav_robot_board_diff(const qnav_link_config_t *reported, const qnav_board_config_t *expected,
                          const qnav_board_map_info_t *expected_map, char *line, size_t len);

/* The same between two configurations (field by field, in the list's order). */
int qnav_robot_board_config_diff(const qnav_board_config_t *a, const qnav_board_config_t *b,
                                 char *line, size_t len);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_ROBOT_BOARD_H */
