/*
 * libFuzzer target: the EEPROM policy store's load path (firmware/boards/core,
 * board_store.c) at start-up. The input is the EEPROM's first bytes (the rest erased);
 * qnav_board_init must come up whatever they hold (a slot that is not whole, or whose
 * policy the controller refuses, is skipped; none left: the built-in policy) and run a
 * tick.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/board.h"
#include "qnav/tekbot.h"
#include "sim_hal.h"

static sim_hal_t g_sim;
static qnav_board_t g_bot;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    qnav_board_config_t cfg;
    qnav_board_hal_t hal;
    memset(&g_sim, 0, sizeof g_sim);
    sim_hal_init(&g_sim, &hal);
    memcpy(g_sim.nvm, data, size < SIM_HAL_NVM ? size : SIM_HAL_NVM);
    g_sim.n_ranges = 8;
    qnav_tekbot_config_default(&cfg);
    cfg.ctrl.n_sectors = 8;
    if (qnav_board_init(&g_bot, &cfg, &hal) != QNAV_BOARD_OK) {
        abort(); /* a board that does not start because of its EEPROM */
    }
    g_sim.now_ms += 200;
    qnav_board_poll(&g_bot);
    return 0;
}
