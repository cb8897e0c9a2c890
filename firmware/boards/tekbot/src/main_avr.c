/*
 * Firmware entry point of the ATmega128 TekBot: hardware layer, board core, loop. The
 * board and its controller live in one static (no heap).
 */
#include "hal_avr.h"
#include "qnav/tekbot.h"

static qnav_board_t g_bot;

int main(void)
{
    qnav_board_hal_t hal;
    qnav_board_config_t cfg;
    qnav_tekbot_hal_avr_init(&hal);
    qnav_tekbot_config_default(&cfg);
    cfg.n_sectors = 8; /* ADC0..ADC7 */
    (void)qnav_board_init(&g_bot, &cfg, &hal); /* the drive stays at 0 if it fails */
    for (;;) {
        qnav_board_poll(&g_bot);
    }
}
