/*
 * ATmega128 firmware on an installed qnav: the controller in table mode with a rank-key
 * table compiled into flash by `qnav-policy header --mode table`, deciding on the fixed
 * scan of examples/host-app (the same output is expected, bit for bit). It prints the
 * decision on simavr's console and ends with "EXIT 0" (the installed run-simavr turns that
 * into its exit status).
 */
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr_mcu_section.h>
#include <stdio.h>

#include "qnav/ctrl.h"
#include "nav_table.h"

/* an address the ATmega128 leaves unused: writes reach only simavr's console */
#define CONSOLE_REG _SFR_MEM8(0x66)
AVR_MCU(F_CPU, "atmega128");
AVR_MCU_SIMAVR_CONSOLE(&CONSOLE_REG);

static void put(const char *s)
{
    for (; *s != '\0'; ++s) {
        CONSOLE_REG = (uint8_t)(*s == '\n' ? '\r' : *s); /* simavr flushes on '\r' */
    }
}

static qnav_ctrl_t nav;
static qnav_mm_t ranges[16];

int main(void)
{
    qnav_ctrl_config_t cfg;
    qnav_ctrl_input_t in = {0};
    qnav_ctrl_output_t out;
    char line[48];
    uint8_t k;
    for (k = 0; k < 16u; ++k) {
        ranges[k] = (qnav_mm_t)(k < 2u ? 400u : 3000u);
    }
    qnav_ctrl_config_default(&cfg);
    cfg.n_sectors = 16;
    cfg.max_range_mm = 3000;
    if (qnav_ctrl_init_table(&nav, &cfg, nav_table, nav_table_RANK) != QNAV_OK) {
        put("init failed\nEXIT 1\n");
    } else {
        in.ranges_mm = ranges;
        in.goal_bearing_cdeg = 3000;
        in.prev_heading_cdeg = 0; /* 2-input policies ignore it */
        qnav_ctrl_step(&nav, &in, &out, 0);
        snprintf(line, sizeof line, "fixed scan: heading %d speed %d\n", (int)out.heading_deg,
                 (int)out.speed);
        put(line);
        put("EXIT 0\n");
    }
    cli();
    for (;;) {
        sleep_mode(); /* with interrupts off, simavr ends the run here */
    }
}
