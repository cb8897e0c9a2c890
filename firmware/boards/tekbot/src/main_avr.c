/*
 * Firmware entry point of an ATmega128 board: hardware layer, board core, loop. The
 * robot's configuration is the one generated from its profile (qnav/robots.h: the TekBot
 * by default, -DQNAV_BOARD_ROBOT_PIONEER3DX for the Pioneer 3-DX). The board and its
 * controller live in one static (no heap), and with the profile's map on, the map and its
 * memory in two more.
 */
#include "hal_avr.h"
#include "qnav/board.h"
#include "qnav/robots.h"

static qnav_board_t g_bot;

#ifdef QNAV_BOARD_ROBOT_MAP_CONFIG
/* The profile's map, placed by the core at each position goal in the profile's [map] bytes
 * (the TekBot's 512 hold 32 x 32 compact cells, 11.2 m at 0.35 m: docs/hil.md). */
#ifndef QNAV_BOARD_ROBOT_MAP_BYTES
#error "the robot's profile has its [map] on but gives it no bytes: the board's memory for it"
#endif
static qnav_map_t g_map;
static uint8_t g_map_mem[QNAV_BOARD_ROBOT_MAP_BYTES];
static const qnav_map_config_t g_map_cfg = QNAV_BOARD_ROBOT_MAP_CONFIG;
#endif

int main(void)
{
    static const qnav_board_config_t cfg = QNAV_BOARD_ROBOT_CONFIG;
    qnav_board_hal_t hal;
    qnav_board_status_t st;
    qnav_tekbot_hal_avr_init(&hal);
    st = qnav_board_init(&g_bot, &cfg, &hal);
    if (st != QNAV_BOARD_OK && st != QNAV_BOARD_E_CTRL) {
        /* a hardware layer or configuration the core refuses (a build error): nothing
         * may be polled, and the drive was never started */
        for (;;) {
        }
    }
#ifdef QNAV_BOARD_ROBOT_MAP_CONFIG
    (void)qnav_board_place_maps(&g_bot, &g_map, &g_map_cfg, g_map_mem, sizeof g_map_mem);
#endif
    /* QNAV_BOARD_E_CTRL: no controller (a stored policy it refuses), but the link runs:
     * the heartbeat's state lacks QNAV_LINK_STATE_POLICY, the drive stays at 0, and an
     * upload installs a policy */
    for (;;) {
        qnav_board_poll(&g_bot);
    }
}
