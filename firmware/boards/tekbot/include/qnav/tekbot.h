/*
 * The TekBot-class robot as a qnav board: its configuration for the board core
 * (qnav/board.h). The firmware image is the core + hal_avr.c + main_avr.c.
 */
#ifndef QNAV_TEKBOT_H
#define QNAV_TEKBOT_H

#include "qnav/board.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The core's defaults with the body of data/robots/tekbot.toml (radius 120 mm with the
 * sonar on its rim, safety 50 mm, 500 mm/s, braking 2000 mm/s^2) and its encoders (70 mm
 * wheels, 32 counts per turn: 6872 um per count). */
void qnav_tekbot_config_default(qnav_board_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_TEKBOT_H */
