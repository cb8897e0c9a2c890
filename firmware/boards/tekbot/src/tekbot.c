/*
 * The TekBot's board configuration (qnav/tekbot.h): the one generated from its robot
 * profile (qnav/robot_tekbot.h).
 */
#include "qnav/tekbot.h"

#include <stddef.h>

#include "qnav/robot_tekbot.h"

void qnav_tekbot_config_default(qnav_board_config_t *cfg)
{
    static const qnav_board_config_t tekbot = QNAV_ROBOT_TEKBOT_CONFIG;
    if (cfg == NULL) {
        return;
    }
    *cfg = tekbot;
}
