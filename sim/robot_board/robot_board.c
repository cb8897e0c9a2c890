/*
 * A robot profile as a board configuration (robot_board.h): the mapping, the generated
 * header and the comparison, each walking QNAV_BOARD_ROBOT_FIELDS once.
 */
#include "robot_board.h"

#include <ctype.h>
#include <math.h>
#include <string.h>

void qnav_robot_board_config(const qnav_sim_robot_t *robot, qnav_board_config_t *cfg)
{
    qnav_sim_robot_info_t ri;
    qnav_board_config_default(cfg);
    qnav_sim_robot_ctrl_config(robot, 0, &cfg->ctrl);
    qnav_sim_robot_info(robot, &ri);
    cfg->tick_ms = (uint16_t)ri.tick_ms;
    cfg->track_mm = (uint16_t)lround(fmin(65535.0, ri.wheel_base_m * 1000.0));
    cfg->um_per_count = (uint16_t)ri.um_per_count;
    cfg->turn_full_deg = ri.turn_full_deg;
}

qnav_sim_status_t qnav_robot_board_load(const char *spec, qnav_board_config_t *cfg,
                                        qnav_board_map_info_t *map, char *err, size_t errlen)
{
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_status_t st = qnav_sim_robot_load(spec, &robot, err, errlen);
    if (st != QNAV_SIM_OK) {
        return st;
    }
    qnav_robot_board_config(robot, cfg);
    if (map != NULL) {
        qnav_robot_board_map_info(robot, map);
    }
    qnav_sim_robot_free(robot);
    return QNAV_SIM_OK;
}

void qnav_robot_board_map_info(const qnav_sim_robot_t *robot, qnav_board_map_info_t *info)
{
    qnav_map_config_t mc;
    const int on = qnav_sim_robot_map_config(robot, &mc);
    qnav_board_map_info(on ? &mc : NULL, (uint32_t)qnav_sim_robot_map_bytes(robot), info);
}

long qnav_robot_board_udeg_per_count(const qnav_board_config_t *cfg)
{
    if (cfg->track_mm == 0u) {
        return 0;
    }
    /* (um / 1000) / track_mm rad, in 1e-6 deg */
    return lround((double)cfg->um_per_count / (1000.0 * cfg->track_mm) * (180.0 / 3.14159265358979323846) * 1e6);
}

/* With the profile's [map] on: the map the board places at each position goal, as a
 * qnav_map_config_t initialiser (nothing when the map is off). */
static void put_map(FILE *out, const qnav_sim_robot_t *robot, const char *up)
{
    qnav_map_config_t mc;
    if (!qnav_sim_robot_map_config(robot, &mc)) {
        return;
    }
    {
#define MAP_FIELD_ENTRY(name, bits) {#name, (unsigned)mc.name},
        const struct {
            const char *name;
            unsigned value;
        } fields[] = {QNAV_MAP_CONFIG_FIELDS(MAP_FIELD_ENTRY)};
#undef MAP_FIELD_ENTRY
        size_t k, col = 0u;
        fprintf(out,
                "/* The profile's [map], on: the map the board places at each position goal\n"
                " * (qnav_board_place_maps), a qnav_map_config_t. */\n"
                "#define QNAV_ROBOT_%s_MAP_CONFIG \\\n"
                "    { \\\n",
                up);
        for (k = 0; k < sizeof fields / sizeof fields[0]; ++k) {
            char one[64];
            const int len = snprintf(one, sizeof one, ".%s = %u%s", fields[k].name, fields[k].value,
                                     k + 1u < sizeof fields / sizeof fields[0] ? "," : "");
            if (col != 0u && col + 1u + (size_t)len > 86u) { /* the line's end: a continuation */
                fputs(" \\\n", out);
                col = 0u;
            }
            col += (size_t)fprintf(out, "%s%s", col == 0u ? "        " : " ", one);
        }
        fputs(" \\\n    }\n\n", out);
    }
    if (qnav_sim_robot_map_bytes(robot) != 0u) {
        fprintf(out,
                "/* The profile's [map] bytes: the board's memory for that map, the largest\n"
                " * square of its cells they hold placed at each goal (qnav_map_place). */\n"
                "#define QNAV_ROBOT_%s_MAP_BYTES %luu\n\n",
                up, (unsigned long)qnav_sim_robot_map_bytes(robot));
    }
}

int qnav_robot_board_header(const qnav_sim_robot_t *robot, FILE *out)
{
    qnav_board_config_t cfg;
    qnav_sim_robot_info_t ri;
    char up[64];
    size_t k;
    qnav_sim_robot_info(robot, &ri);
    qnav_robot_board_config(robot, &cfg);
    for (k = 0; ri.name[k] != '\0' && k + 1 < sizeof up; ++k) {
        up[k] = isalnum((unsigned char)ri.name[k]) ? (char)toupper((unsigned char)ri.name[k]) : '_';
    }
    up[k] = '\0';
    fprintf(out,
            "/*\n"
            " * The %s's board configuration, generated from its robot profile\n"
            " * (data/robots/%s.toml) by\n"
            " *   qnav-sim robot-header --robot %s firmware/boards/robots/include/qnav/robot_%s.h\n"
            " * Do not edit: change the profile and run the command again. The test\n"
            " * board.robot_headers_match_profiles fails while this file differs from what the\n"
            " * command writes (docs/hil.md, \"One robot description\").\n"
            " */\n"
            "#ifndef QNAV_ROBOT_%s_H\n"
            "#define QNAV_ROBOT_%s_H\n\n"
            "#define QNAV_ROBOT_%s_NAME \"%s\"\n\n"
            "/* Heading change per differential encoder count (right minus left), 1e-6 deg:\n"
            " * um_per_count / track_mm rad. */\n"
            "#define QNAV_ROBOT_%s_UDEG_PER_COUNT %ldL\n\n"
            "/* Where its mixer turns at full wheel speed (qnav_drive_mix), deg: 2 v_max /\n"
            " * (track x heading_gain_per_s) rad. */\n"
            "#define QNAV_ROBOT_%s_TURN_FULL_DEG %uu\n\n"
            "/* A qnav_board_config_t (qnav/board.h): the fields of QNAV_BOARD_ROBOT_FIELDS from the\n"
            " * profile, the rest qnav_board_config_default()'s. */\n"
            "#define QNAV_ROBOT_%s_CONFIG \\\n"
            "    { \\\n",
            ri.name, ri.name, ri.name, ri.name, up, up, up, ri.name, up,
            qnav_robot_board_udeg_per_count(&cfg), up, (unsigned)cfg.turn_full_deg, up);
#define QNAV_ROBOT_BOARD_PRINT(id, name, member) \
    fprintf(out, "        .%s = %ld, \\\n", #member, (long)cfg.member);
    QNAV_BOARD_ROBOT_FIELDS(QNAV_ROBOT_BOARD_PRINT)
#undef QNAV_ROBOT_BOARD_PRINT
    fprintf(out,
            "        .link_timeout_ms = %u, \\\n"
            "        .nvm_offset = %u, \\\n"
            "        .controller = \"%s\" \\\n"
            "    }\n\n",
            (unsigned)cfg.link_timeout_ms, (unsigned)cfg.nvm_offset, cfg.controller);
    put_map(out, robot, up);
    fprintf(out, "#endif /* QNAV_ROBOT_%s_H */\n", up);
    return fflush(out) == 0 && !ferror(out) ? 0 : -1;
}

/* 1, with the line, when field id is missing from the report or differs from want. */
static int field_differs(const qnav_link_config_t *reported, uint8_t id, const char *name,
                         int32_t want, char *line, size_t len)
{
    uint8_t i;
    for (i = 0; i < reported->n && reported->key[i] != id; ++i) {
    }
    if (i == reported->n) {
        snprintf(line, len, "%s not reported", name);
        return 1;
    }
    if (reported->value[i] != want) {
        snprintf(line, len, "%s %ld != %ld", name, (long)reported->value[i], (long)want);
        return 1;
    }
    return 0;
}

int qnav_robot_board_diff(const qnav_link_config_t *reported, const qnav_board_config_t *expected,
                          const qnav_board_map_info_t *expected_map, char *line, size_t len)
{
#define QNAV_ROBOT_BOARD_CHECK(id, name, member)                                           \
    if (field_differs(reported, (uint8_t)(id), #name, (int32_t)expected->member, line, len)) { \
        return 1;                                                                           \
    }
    QNAV_BOARD_ROBOT_FIELDS(QNAV_ROBOT_BOARD_CHECK)
#undef QNAV_ROBOT_BOARD_CHECK
#define QNAV_ROBOT_BOARD_CHECK_MAP(id, name, member)                                       \
    if (field_differs(reported, (uint8_t)(id), #name, (int32_t)expected_map->member, line,  \
                      len)) {                                                               \
        return 1;                                                                           \
    }
    if (expected_map != NULL) {
        QNAV_BOARD_MAP_FIELDS(QNAV_ROBOT_BOARD_CHECK_MAP)
    }
#undef QNAV_ROBOT_BOARD_CHECK_MAP
    if (len > 0) {
        line[0] = '\0';
    }
    return 0;
}

int qnav_robot_board_config_diff(const qnav_board_config_t *a, const qnav_board_config_t *b,
                                 char *line, size_t len)
{
    qnav_link_config_t m;
    qnav_board_config_report(a, &m);
    return qnav_robot_board_diff(&m, b, NULL, line, len);
}
