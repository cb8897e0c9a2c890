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
    qnav_tekbot_hal_avr_init(&hal);
    (void)qnav_board_init(&g_bot, &cfg, &hal); /* the drive stays at 0 if it fails */
    for (;;) {
        qnav_board_poll(&g_bot);
    }
}
