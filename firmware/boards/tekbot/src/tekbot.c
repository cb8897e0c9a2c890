/*
 * The TekBot's board configuration (qnav/tekbot.h).
 */
#include "qnav/tekbot.h"

#include <stddef.h>

void qnav_tekbot_config_default(qnav_board_config_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    qnav_board_config_default(cfg);
    cfg->body_radius_mm = 120;
    cfg->safety_mm = 50;
    cfg->sonar_offset_mm = 120;
    cfg->v_max_mm_s = 500;
    cfg->decel_mm_s2 = 2000;
    cfg->um_per_count = 6872; /* pi * 70 mm / 32 */
}
