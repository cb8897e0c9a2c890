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

/* The TekBot's configuration, generated from data/robots/tekbot.toml
 * (QNAV_ROBOT_TEKBOT_CONFIG of qnav/robot_tekbot.h: sonar, body, speed guard, tick, track,
 * encoders; docs/hil.md, "One robot description"). */
void qnav_tekbot_config_default(qnav_board_config_t *cfg);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_TEKBOT_H */
