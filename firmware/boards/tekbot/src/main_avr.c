/*
 * Firmware entry point of an ATmega128 board: hardware layer, board core, loop. The
 * robot's configuration is the one generated from its profile (qnav/robots.h: the TekBot
 * by default, -DQNAV_BOARD_ROBOT_PIONEER3DX for the Pioneer 3-DX). The board and its
 * controller live in one static (no heap).
 */
#include "hal_avr.h"
#include "qnav/board.h"
#include "qnav/robots.h"

static qnav_board_t g_bot;

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
    /* QNAV_BOARD_E_CTRL: no controller (a stored policy it refuses), but the link runs:
     * the heartbeat's state lacks QNAV_LINK_STATE_POLICY, the drive stays at 0, and an
     * upload installs a policy */
    for (;;) {
        qnav_board_poll(&g_bot);
    }
}
