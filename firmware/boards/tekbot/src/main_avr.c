/*
 * Firmware entry point of the ATmega128 TekBot: hardware layer, application, loop. The
 * application and the controller live in one static each (no heap).
 */
#include "hal_avr.h"
#include "qnav/tekbot.h"

static qnav_tekbot_t g_bot;

int main(void)
{
    qnav_board_hal_t hal;
    qnav_tekbot_config_t cfg;
    qnav_tekbot_hal_avr_init(&hal);
    qnav_tekbot_config_default(&cfg);
    cfg.n_sectors = 8; /* ADC0..ADC7 */
    (void)qnav_tekbot_init(&g_bot, &cfg, &hal); /* motors stay at 0 if it fails */
    for (;;) {
        qnav_tekbot_poll(&g_bot);
    }
}
