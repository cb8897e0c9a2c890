/*
 * One robot description: for each robot, the controller configuration the simulator runs
 * (a context of its profile, qnav_sim_ctrl_config) and the one its board is built with
 * (the generated, committed header qnav/robot_<name>.h) are the same, field by field and
 * byte for byte; the board-only fields (tick, track, encoder scale) are the profile's; and a
 * configuration that differs is reported naming the field.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "qnav/robot_pioneer3dx.h"
#include "qnav/robot_tekbot.h"
#include "qnav/sim.h"
#include "robot_board.h"

static const qnav_board_config_t g_tekbot = QNAV_ROBOT_TEKBOT_CONFIG;
static const qnav_board_config_t g_pioneer3dx = QNAV_ROBOT_PIONEER3DX_CONFIG;

/* The simulator's controller configuration for robot at its default sectors, and the
 * profile's board configuration. */
static void from_profile(const char *robot, qnav_ctrl_config_t *sim_cc, qnav_board_config_t *bc)
{
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_robot_t *r = NULL;
    qnav_sim_env_t *e = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t sc;
    assert_int_equal(qnav_sim_robot_load(robot, &r, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(qnav_sim_env_load("open", &e, err, sizeof err), QNAV_SIM_OK);
    qnav_sim_config_default(&sc);
    assert_int_equal(qnav_sim_create(r, e, &sc, &sim, err, sizeof err), QNAV_SIM_OK);
    memset(sim_cc, 0, sizeof *sim_cc); /* padding compares equal */
    qnav_sim_ctrl_config(sim, sim_cc);
    qnav_robot_board_config(r, bc);
    qnav_sim_destroy(sim);
    qnav_sim_env_free(e);
    qnav_sim_robot_free(r);
}

static void check_robot(const char *robot, const qnav_board_config_t *generated)
{
    qnav_ctrl_config_t sim_cc, board_cc;
    qnav_board_config_t bc, as_board;
    char line[128] = "unset";
    from_profile(robot, &sim_cc, &bc);
    /* field by field (QNAV_BOARD_ROBOT_FIELDS): the generated header is the profile's */
    if (qnav_robot_board_config_diff(generated, &bc, line, sizeof line) != 0) {
        fail_msg("%s: generated header: %s (profile)", robot, line);
    }
    assert_string_equal(line, "");
    /* the simulator's controller is the board's, every byte (a field the list misses
     * would be zero in the header and the default here) */
    memset(&board_cc, 0, sizeof board_cc);
    memcpy(&board_cc, &generated->ctrl, sizeof board_cc);
    assert_memory_equal(&sim_cc, &board_cc, sizeof sim_cc);
    as_board = bc;
    as_board.ctrl = sim_cc;
    assert_int_equal(qnav_robot_board_config_diff(&as_board, generated, line, sizeof line), 0);
}

static void test_tekbot_simulator_and_board_configurations_are_identical(void **state)
{
    (void)state;
    check_robot("tekbot", &g_tekbot);
    /* the figures issue 17 found disagreeing now come from data/robots/tekbot.toml */
    assert_int_equal(g_tekbot.ctrl.max_range_mm, 2500);
    assert_int_equal(g_tekbot.track_mm, 180);
    assert_int_equal(g_tekbot.ctrl.body_radius_mm, 120);
    assert_int_equal(g_tekbot.ctrl.safety_mm, 50);
}

static void test_pioneer3dx_simulator_and_board_configurations_are_identical(void **state)
{
    (void)state;
    check_robot("pioneer3dx", &g_pioneer3dx);
    assert_int_equal(g_pioneer3dx.ctrl.n_sectors, 16);
    assert_int_equal(g_pioneer3dx.ctrl.max_range_mm, 5000);
    assert_int_equal(g_pioneer3dx.ctrl.body_radius_mm, 260);
}

static void test_a_configuration_that_differs_is_named_by_its_field(void **state)
{
    qnav_board_config_t other = g_tekbot;
    qnav_link_config_t m;
    char line[128];
    (void)state;
    other.ctrl.max_range_mm = 5000;
    assert_int_equal(qnav_robot_board_config_diff(&other, &g_tekbot, line, sizeof line), 1);
    assert_string_equal(line, "max_range_mm 5000 != 2500");
    other = g_tekbot;
    other.um_per_count = 1000;
    assert_int_equal(qnav_robot_board_config_diff(&other, &g_tekbot, line, sizeof line), 1);
    assert_string_equal(line, "um_per_count 1000 != 6872");
    /* a board of an older build that does not report a field */
    qnav_board_config_report(&g_tekbot, &m);
    m.n = 5;
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, NULL, line, sizeof line), 1);
    assert_string_equal(line, "sensor_offset_mm not reported");
}

/* The map a board reports (its generated header's, in its bytes) is its profile's, and a
 * board whose map differs is named by the field, the CRC standing for the rest. */
static void test_a_map_that_differs_is_named_by_its_field(void **state)
{
    static const qnav_map_config_t header_map = QNAV_ROBOT_TEKBOT_MAP_CONFIG;
    qnav_map_config_t other_map = header_map;
    qnav_board_map_info_t profile, board;
    qnav_board_config_t bc;
    qnav_link_config_t m;
    char err[QNAV_SIM_ERRLEN], line[128];
    (void)state;
    assert_int_equal(qnav_robot_board_load("tekbot", &bc, &profile, err, sizeof err), QNAV_SIM_OK);
    assert_int_equal(profile.on, 1);
    assert_int_equal(profile.bytes, QNAV_ROBOT_TEKBOT_MAP_BYTES);
    assert_int_equal(profile.cell_mm, header_map.cell_mm);
    qnav_board_map_info(&header_map, QNAV_ROBOT_TEKBOT_MAP_BYTES, &board);
    assert_memory_equal(&board, &profile, sizeof board);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 0);
    /* cells of another size */
    other_map.cell_mm = 400;
    qnav_board_map_info(&other_map, QNAV_ROBOT_TEKBOT_MAP_BYTES, &board);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 1);
    assert_string_equal(line, "map_cell_mm 400 != 300");
    /* a field without a name of its own: the CRC differs */
    other_map = header_map;
    other_map.look_mm = (uint16_t)(header_map.look_mm + 100u);
    qnav_board_map_info(&other_map, QNAV_ROBOT_TEKBOT_MAP_BYTES, &board);
    assert_true(board.crc != profile.crc);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 1);
    assert_non_null(strstr(line, "map_config_crc "));
    /* more bytes, no map at all, a board of link protocol 4 that does not report one */
    qnav_board_map_info(&header_map, 2048u, &board);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 1);
    assert_string_equal(line, "map_bytes 2048 != 768");
    qnav_board_map_info(NULL, 0u, &board);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 1);
    assert_string_equal(line, "map_on 0 != 1");
    qnav_board_config_report(&g_tekbot, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 1);
    assert_string_equal(line, "map_on not reported");
    /* the robot without a map expects none */
    assert_int_equal(qnav_robot_board_load("tekbot-map", &bc, &profile, err, sizeof err),
                     QNAV_SIM_OK);
    assert_int_equal(profile.on, 0);
    qnav_board_map_info(NULL, 0u, &board);
    qnav_board_config_report(&g_tekbot, &m);
    qnav_board_map_report(&board, &m);
    assert_int_equal(qnav_robot_board_diff(&m, &g_tekbot, &profile, line, sizeof line), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tekbot_simulator_and_board_configurations_are_identical),
        cmocka_unit_test(test_pioneer3dx_simulator_and_board_configurations_are_identical),
        cmocka_unit_test(test_a_configuration_that_differs_is_named_by_its_field),
        cmocka_unit_test(test_a_map_that_differs_is_named_by_its_field),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
