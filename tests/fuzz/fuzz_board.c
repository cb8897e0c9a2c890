/*
 * libFuzzer target: the board core's frame handling (firmware/boards/core) through the
 * scripted HAL of the board tests (tests/board/sim_hal.c). The input is what arrives on
 * the board's UART, in slices of 24 bytes with 10 ms of clock and a qnav_board_poll()
 * after each (so ticks, goals, commands, uploads and EEPROM commits interleave with it).
 * Property beyond "no crash, no sanitizer report": whatever arrived, one second with no
 * bytes leaves the drive stopped (the link-quiet stop of docs/hil.md).
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
    size_t off = 0;
    int k;
    memset(&g_sim, 0, sizeof g_sim);
    sim_hal_init(&g_sim, &hal);
    g_sim.n_ranges = 8;
    for (k = 0; k < 8; ++k) {
        g_sim.ranges_mm[k] = (qnav_mm_t)(600 + 300 * k);
    }
    qnav_tekbot_config_default(&cfg);
    cfg.ctrl.n_sectors = 8;
    if (qnav_board_init(&g_bot, &cfg, &hal) != QNAV_BOARD_OK) {
        abort();
    }
    while (off < size && off < SIM_HAL_QUEUE / 2) {
        size_t n = size - off < 24 ? size - off : 24;
        sim_hal_to_board(&g_sim, data + off, (uint32_t)n);
        off += n;
        g_sim.now_ms += 10;
        g_sim.from_board_n = 0; /* what the board says is not looked at */
        qnav_board_poll(&g_bot);
    }
    for (k = 0; k < 100; ++k) {
        g_sim.now_ms += 10;
        g_sim.from_board_n = 0;
        qnav_board_poll(&g_bot);
    }
    if (g_sim.drive_speed != 0) {
        abort(); /* a second of silence and the robot still drives */
    }
    return 0;
}
