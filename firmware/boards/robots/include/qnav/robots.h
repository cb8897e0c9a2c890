/*
 * The robot a board image is built for: its configuration generated from its profile
 * (qnav/robot_<name>.h, written by qnav-sim robot-header). -DQNAV_BOARD_ROBOT_PIONEER3DX
 * builds for the Pioneer 3-DX; the default is the TekBot. Gives QNAV_BOARD_ROBOT_NAME,
 * QNAV_BOARD_ROBOT_CONFIG (a qnav_board_config_t initialiser) and
 * QNAV_BOARD_ROBOT_UDEG_PER_COUNT (heading per differential encoder count, 1e-6 deg),
 * QNAV_BOARD_ROBOT_TURN_FULL_DEG (where its mixer turns at full wheel speed, qnav_drive_mix), and
 * QNAV_BOARD_ROBOT_MAP_CONFIG (a qnav_map_config_t initialiser) and
 * QNAV_BOARD_ROBOT_MAP_BYTES (the memory the board places it in) when its profile's [map]
 * is on.
 */
#ifndef QNAV_ROBOTS_H
#define QNAV_ROBOTS_H

#include "qnav/robot_pioneer3dx.h"
#include "qnav/robot_tekbot.h"

#if defined(QNAV_BOARD_ROBOT_PIONEER3DX)
#define QNAV_BOARD_ROBOT_NAME QNAV_ROBOT_PIONEER3DX_NAME
#define QNAV_BOARD_ROBOT_CONFIG QNAV_ROBOT_PIONEER3DX_CONFIG
#define QNAV_BOARD_ROBOT_UDEG_PER_COUNT QNAV_ROBOT_PIONEER3DX_UDEG_PER_COUNT
#define QNAV_BOARD_ROBOT_TURN_FULL_DEG QNAV_ROBOT_PIONEER3DX_TURN_FULL_DEG
#ifdef QNAV_ROBOT_PIONEER3DX_MAP_CONFIG
#define QNAV_BOARD_ROBOT_MAP_CONFIG QNAV_ROBOT_PIONEER3DX_MAP_CONFIG
#endif
#ifdef QNAV_ROBOT_PIONEER3DX_MAP_BYTES
#define QNAV_BOARD_ROBOT_MAP_BYTES QNAV_ROBOT_PIONEER3DX_MAP_BYTES
#endif
#else
#define QNAV_BOARD_ROBOT_NAME QNAV_ROBOT_TEKBOT_NAME
#define QNAV_BOARD_ROBOT_CONFIG QNAV_ROBOT_TEKBOT_CONFIG
#define QNAV_BOARD_ROBOT_UDEG_PER_COUNT QNAV_ROBOT_TEKBOT_UDEG_PER_COUNT
#define QNAV_BOARD_ROBOT_TURN_FULL_DEG QNAV_ROBOT_TEKBOT_TURN_FULL_DEG
#ifdef QNAV_ROBOT_TEKBOT_MAP_CONFIG
#define QNAV_BOARD_ROBOT_MAP_CONFIG QNAV_ROBOT_TEKBOT_MAP_CONFIG
#endif
#ifdef QNAV_ROBOT_TEKBOT_MAP_BYTES
#define QNAV_BOARD_ROBOT_MAP_BYTES QNAV_ROBOT_TEKBOT_MAP_BYTES
#endif
#endif

#endif /* QNAV_ROBOTS_H */
