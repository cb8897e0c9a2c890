/*
 * World families (sim/src/worldgen.hpp): every family's worlds are passable for the
 * TekBot's and the Pioneer's bodies over many seeds and difficulties (by the library's own
 * walled-in check at qnav_sim_create and by a stricter grid), the same spec gives a
 * byte-identical TOML, malformed specs give one line naming the field, gaps at difficulty 1
 * are 2.5-3 robot diameters wide, the U-pocket's opening faces the start (the straight
 * line from the start zone to the destination runs into its bottom), `qnav-sim gen-env
 * --family` writes exactly the world that the spec loads, and the passability flood
 * counts the shortest grid path to each zone.
 */
#include "sim_test_util.hpp"

#include <cmath>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "capi_internal.hpp"
#include "env.hpp"
#include "geometry.hpp"
#include "worldgen.hpp"

static const char *const kFamilies[] = {"clutter", "gaps", "corridor", "pocket", "rooms", "shelves"};
static const char *const kRobots[] = {"tekbot", "pioneer3dx"};
static const char *const kDifficulties[] = {"0", "0.5", "1"};

static qnav_sim_robot_t *load_robot(const char *name) {
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_robot_t *r = nullptr;
    if (qnav_sim_robot_load(name, &r, err, sizeof err) != QNAV_SIM_OK) fail_msg("%s", err);
    return r;
}

static std::string spec_of(const char *family, int seed, const char *difficulty, const char *robot) {
    return std::string("gen:") + family + ":" + std::to_string(seed) + ":" + difficulty + ":" + robot;
}

// The distance from every start zone to the nearest obstacle or wall is at least r.
static double zone_clearance(const qnav::Environment &env) {
    double worst = qnav::kInf;
    for (const qnav::StartZone &z : env.start_zones) {
        const qnav::Shape zs = qnav::make_box(z.x_m + z.w_m / 2, z.y_m + z.h_m / 2, z.w_m, z.h_m, 0.0);
        for (const qnav::Shape &s : env.obstacle_shapes()) worst = std::min(worst, qnav::shape_distance(zs, s));
        for (const qnav::Shape &s : env.wall_shapes()) worst = std::min(worst, qnav::shape_distance(zs, s));
    }
    return worst;
}

static void test_every_family_is_passable_for_both_robots_over_many_seeds(void **state) {
    (void)state;
    // 10 seeds per family and robot, the difficulty cycling through 0, 0.35, 0.7 and 1.
    const char *const difficulties[] = {"0", "0.35", "0.7", "1"};
    for (const char *robot_name : kRobots) {
        qnav_sim_robot_t *robot = load_robot(robot_name);
        qnav_sim_robot_info_t ri;
        qnav_sim_robot_info(robot, &ri);
        for (const char *family : kFamilies)
            for (int seed = 0; seed < 10; ++seed) {
                const std::string spec = spec_of(family, seed * 7919 + 11, difficulties[seed % 4], robot_name);
                char err[QNAV_SIM_ERRLEN] = "";
                qnav_sim_env_t *env = nullptr;
                if (qnav_sim_env_load(spec.c_str(), &env, err, sizeof err) != QNAV_SIM_OK)
                    fail_msg("%s: %s", spec.c_str(), err);
                const qnav::Environment &e = env->env;
                // The library's own check, as every simulation makes it: the generator
                // vouches for its robot's radius (a wider path), so the walled-in flood
                // that qnav_sim_create skips for it must pass too.
                qnav_sim_config_t cfg;
                qnav_sim_config_default(&cfg);
                qnav_sim_t *sim = nullptr;
                if (qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err) != QNAV_SIM_OK)
                    fail_msg("%s: %s", spec.c_str(), err);
                assert_true(e.clearance_checked_m == ri.radius_m);
                if (qnav::first_walled_in_zone(e, ri.radius_m) >= 0) fail_msg("%s: walled in for the body radius", spec.c_str());
                // A stricter one: 5 cm cells, a disc 2 cm wider than the body.
                if (qnav::passable_path_m(e, ri.radius_m + 0.02, 0.05) <= 0)
                    fail_msg("%s: walled in on a 5 cm grid", spec.c_str());
                if (zone_clearance(e) < ri.radius_m) fail_msg("%s: start zone closer than the body radius", spec.c_str());
                assert_true(e.episode_limit_s >= 30.0);
                assert_true(e.circles.size() + e.boxes.size() > 0);
                qnav_sim_destroy(sim);
                qnav_sim_env_free(env);
            }
        qnav_sim_robot_free(robot);
    }
}

static void test_same_spec_gives_byte_identical_toml_and_seeds_differ(void **state) {
    (void)state;
    for (const char *family : kFamilies) {
        const std::string spec = spec_of(family, 42, "0.5", "tekbot");
        const std::string a = qnav::environment_to_toml(qnav::load_world(spec));
        const std::string b = qnav::environment_to_toml(qnav::load_world(spec));
        assert_string_equal(a.c_str(), b.c_str());
        // The short form is the same world with the same (canonical) name.
        const qnav::Environment s = qnav::load_world(std::string("gen:") + family + ":42");
        assert_string_equal(qnav::environment_to_toml(s).c_str(), a.c_str());
        assert_string_equal(s.name.c_str(), spec.c_str());
        const qnav::Environment t = qnav::load_world(std::string("gen:") + family + ":42:0.500:tekbot");
        assert_string_equal(t.name.c_str(), spec.c_str());
        // Another seed, another difficulty or another robot is another world.
        assert_string_not_equal(qnav::environment_to_toml(qnav::load_world(spec_of(family, 43, "0.5", "tekbot"))).c_str(), a.c_str());
        assert_string_not_equal(qnav::environment_to_toml(qnav::load_world(spec_of(family, 42, "0.9", "tekbot"))).c_str(), a.c_str());
        assert_string_not_equal(qnav::environment_to_toml(qnav::load_world(spec_of(family, 42, "0.5", "pioneer3dx"))).c_str(), a.c_str());
    }
}

static void test_bad_specs_give_one_line_naming_the_field(void **state) {
    (void)state;
    struct Case {
        const char *spec, *message;
    };
    const std::string fams = qnav_sim_world_families();
    const Case cases[] = {
        {"gen:maze:1", "world spec 'gen:maze:1': unknown family 'maze' (families: clutter, gaps, corridor, pocket, rooms, shelves)"},
        {"gen:gaps", "world spec 'gen:gaps': expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]] (no seed)"},
        {"gen:", "world spec 'gen:': expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]] (no seed)"},
        {"gen::1", "world spec 'gen::1': family is empty (expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]])"},
        {"gen:gaps::1", "world spec 'gen:gaps::1': seed is empty (expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]])"},
        {"gen:gaps:1:", "world spec 'gen:gaps:1:': difficulty is empty (expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]])"},
        {"gen:gaps:1:0.5:", "world spec 'gen:gaps:1:0.5:': robot is empty (expected gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]])"},
        {"gen:gaps:x1", "world spec 'gen:gaps:x1': seed 'x1' is not a whole number in [0, 18446744073709551615]"},
        {"gen:gaps:-1", "world spec 'gen:gaps:-1': seed '-1' is not a whole number in [0, 18446744073709551615]"},
        {"gen:gaps:18446744073709551616", "world spec 'gen:gaps:18446744073709551616': seed '18446744073709551616' is not a whole number in [0, 18446744073709551615]"},
        {"gen:gaps:1:1.5", "world spec 'gen:gaps:1:1.5': difficulty '1.5' is not a number in [0, 1] with at most 3 decimals"},
        {"gen:gaps:1:0.1234", "world spec 'gen:gaps:1:0.1234': difficulty '0.1234' is not a number in [0, 1] with at most 3 decimals"},
        {"gen:gaps:1:1e-1", "world spec 'gen:gaps:1:1e-1': difficulty '1e-1' is not a number in [0, 1] with at most 3 decimals"},
        {"gen:gaps:1:-0", "world spec 'gen:gaps:1:-0': difficulty '-0' is not a number in [0, 1] with at most 3 decimals"},
        {"gen:gaps:1:0.", "world spec 'gen:gaps:1:0.': difficulty '0.' is not a number in [0, 1] with at most 3 decimals"},
    };
    assert_string_equal(fams.c_str(), "clutter, gaps, corridor, pocket, rooms, shelves");
    for (const Case &c : cases) {
        char err[QNAV_SIM_ERRLEN] = "";
        qnav_sim_env_t *env = reinterpret_cast<qnav_sim_env_t *>(0x1);
        assert_int_equal(qnav_sim_env_load(c.spec, &env, err, sizeof err), QNAV_SIM_E_PARAM);
        assert_null(env);
        assert_string_equal(err, c.message);
    }
    // A robot that does not exist: the loader's line, prefixed with the spec.
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = nullptr;
    assert_int_equal(qnav_sim_env_load("gen:gaps:1:0.5:/nonexistent/robot.toml", &env, err, sizeof err), QNAV_SIM_E_IO);
    assert_string_equal(err, "world spec 'gen:gaps:1:0.5:/nonexistent/robot.toml': robot: /nonexistent/robot.toml: cannot open (No such file or directory)");
    // ".5" and "1.000" are fine and spelled canonically in the name.
    const qnav::WorldSpec w = qnav::parse_world_spec("gen:rooms:0:.5");
    assert_int_equal(w.difficulty_milli, 500);
    assert_string_equal(qnav::world_spec_name(qnav::parse_world_spec("gen:rooms:0:1.000:pioneer3dx")).c_str(), "gen:rooms:0:1:pioneer3dx");
    assert_string_equal(qnav::world_spec_name(qnav::parse_world_spec("gen:rooms:0:0.050")).c_str(), "gen:rooms:0:0.05:tekbot");
}

// Gaps at difficulty 1: a disc of 2.5 robot diameters (less the grid's slack) passes every
// wall, one of 3 diameters passes none.
static void test_gaps_at_difficulty_one_are_two_and_a_half_to_three_diameters(void **state) {
    (void)state;
    for (const char *robot_name : kRobots) {
        for (int seed = 0; seed < 10; ++seed) {
            const qnav::Environment e = qnav::load_world(spec_of("gaps", seed, "1", robot_name));
            const double diam = robot_name[0] == 't' ? 0.24 : 0.52;
            if (qnav::passable_path_m(e, 1.25 * diam - 0.06, 0.1) <= 0)
                fail_msg("%s: a gap narrower than 2.5 diameters", e.name.c_str());
            if (qnav::passable_path_m(e, 1.5 * diam + 0.01, 0.1) > 0)
                fail_msg("%s: a gap wider than 3 diameters", e.name.c_str());
        }
    }
}

// The segment from p to the destination: the first obstacle it meets is box `bottom`,
// and the two arms lie on opposite sides of it, between p and the bottom.
static void assert_segment_runs_into_pocket(const qnav::Environment &e, qnav::Vec2 p, std::size_t bottom,
                                            std::size_t arm_a, std::size_t arm_b) {
    const qnav::Vec2 goal{e.dest_x_m, e.dest_y_m};
    const double len = qnav::norm(goal - p);
    const qnav::Vec2 u = (1.0 / len) * (goal - p);
    const std::vector<qnav::Shape> obs = e.obstacle_shapes();
    double first = qnav::kInf;
    std::size_t which = obs.size();
    for (std::size_t k = 0; k < obs.size(); ++k) {
        const double t = qnav::ray_hit(obs[k], p, u);
        if (t < first) {
            first = t;
            which = k;
        }
    }
    const std::size_t bottom_shape = e.circles.size() + bottom;
    if (which != bottom_shape || first >= len)
        fail_msg("%s: the line from (%.2f, %.2f) meets obstacle %zu at %.2f m, not the pocket's bottom %zu",
                 e.name.c_str(), p.x, p.y, which, first, bottom_shape);
    const qnav::BoxObstacle &a = e.boxes[arm_a], &b = e.boxes[arm_b];
    const double sa = qnav::cross(u, qnav::Vec2{a.x_m, a.y_m} - p), sb = qnav::cross(u, qnav::Vec2{b.x_m, b.y_m} - p);
    assert_true(sa * sb < 0);
    assert_true(qnav::dot(u, qnav::Vec2{a.x_m, a.y_m} - p) > 0);
    assert_true(qnav::dot(u, qnav::Vec2{a.x_m, a.y_m} - p) < first);
}

static void test_u_pocket_faces_the_start(void **state) {
    (void)state;
    for (const char *robot_name : kRobots)
        for (const char *difficulty : kDifficulties)
            for (int seed = 0; seed < 10; ++seed) {
                qnav::WorldNotes notes;
                const qnav::Environment e = qnav::load_world(spec_of("pocket", seed, difficulty, robot_name), &notes);
                assert_true(notes.pocket_bottoms.size() == 1);
                assert_true(notes.pocket_arms.size() == 2);
                assert_int_equal(e.start_zones.size(), 1);
                const qnav::StartZone &z = e.start_zones[0];
                // From the centre and the four corners of the start zone.
                const qnav::Vec2 pts[] = {{z.x_m + z.w_m / 2, z.y_m + z.h_m / 2}, {z.x_m, z.y_m}, {z.x_m + z.w_m, z.y_m},
                                          {z.x_m, z.y_m + z.h_m}, {z.x_m + z.w_m, z.y_m + z.h_m}};
                for (const qnav::Vec2 &p : pts)
                    assert_segment_runs_into_pocket(e, p, notes.pocket_bottoms[0], notes.pocket_arms[0], notes.pocket_arms[1]);
            }
}

// Run qnav-sim with args; returns its exit status and its stderr+stdout.
static int run_tool(const std::string &args, std::string *out) {
    const std::string cmd = std::string(QNAV_SIM_TOOL) + " " + args + " 2>&1";
    FILE *p = popen(cmd.c_str(), "r");
    assert_non_null(p);
    char buf[1024];
    out->clear();
    while (fgets(buf, sizeof buf, p)) out->append(buf);
    const int st = pclose(p);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_gen_env_writes_the_world_the_spec_loads_and_refuses_bad_names(void **state) {
    (void)state;
    char dir[] = "/tmp/qnav_worldgen_XXXXXX";
    assert_non_null(mkdtemp(dir));
    const std::string file = std::string(dir) + "/w.toml";
    std::string out;
    assert_int_equal(run_tool("gen-env --family rooms --seed 9 --difficulty 0.25 --robot pioneer3dx --out " + file, &out), 0);
    const std::string written = read_text_file(file);
    assert_string_equal(written.c_str(), qnav::environment_to_toml(qnav::load_world("gen:rooms:9:0.25:pioneer3dx")).c_str());
    // draw-env draws a spec like a file.
    assert_int_equal(run_tool("draw-env --env gen:pocket:3:0.5:pioneer3dx --robot pioneer3dx --out " + std::string(dir) + "/p.svg", &out), 0);
    assert_true(read_text_file(std::string(dir) + "/p.svg").find("</svg>") != std::string::npos);
    // Bad input: one line, exit 2, nothing written.
    assert_int_equal(run_tool("gen-env --family maze --seed 1 --out " + std::string(dir) + "/x.toml", &out), 2);
    assert_string_equal(out.c_str(), "world spec 'gen:maze:1:0.5:tekbot': unknown family 'maze' (families: clutter, gaps, corridor, pocket, rooms, shelves)\n");
    assert_int_equal(run_tool("gen-env --family gaps --density 0.2 --out " + std::string(dir) + "/x.toml", &out), 2);
    assert_string_equal(out.c_str(), "--density: not with --family (use --difficulty)\n");
    assert_int_equal(run_tool("gen-env --difficulty 0.2 --out " + std::string(dir) + "/x.toml", &out), 2);
    assert_string_equal(out.c_str(), "--difficulty: only with --family (the density form takes --density)\n");
    assert_int_equal(run_tool("gen-env --family gaps --name 'a\"\nb' --out " + std::string(dir) + "/x.toml", &out), 2);
    assert_string_equal(out.c_str(), "--name: must not contain control characters (newline, tab, ...)\n");
    assert_int_equal(access((std::string(dir) + "/x.toml").c_str(), F_OK), -1);
    // Quotes and backslashes are escaped and read back.
    assert_int_equal(run_tool("gen-env --density 0.1 --name 'a\"b\\c' --out " + file, &out), 0);
    char err[QNAV_SIM_ERRLEN] = "";
    qnav_sim_env_t *env = nullptr;
    assert_int_equal(qnav_sim_env_load(file.c_str(), &env, err, sizeof err), QNAV_SIM_OK);
    assert_string_equal(env->env.name.c_str(), "a\"b\\c");
    qnav_sim_env_free(env);
    for (const char *f : {"w.toml", "p.svg"}) std::remove((std::string(dir) + "/" + f).c_str());
    rmdir(dir);
}

// The passability flood on a hand-made 10 x 3 grid of 0.1 m cells: the destination's cell
// is (9, 1), the zones' cells (0, 1) and (5, 1).
static void test_zone_steps_count_the_shortest_grid_path_to_each_zone(void **state) {
    (void)state;
    qnav::Environment env;
    env.width_m = 1.0;
    env.height_m = 0.3;
    env.dest_x_m = 0.95;
    env.dest_y_m = 0.15;
    env.dest_radius_m = 0.04;
    env.start_zones = {{0.0, 0.1, 0.1, 0.1}, {0.5, 0.1, 0.1, 0.1}};
    std::vector<char> free(30, 1);
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, false) == std::vector<int>{9, 4}));
    // Column 7 closed but for its bottom cell: a detour of two steps.
    free[1 * 10 + 7] = free[2 * 10 + 7] = 0;
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, false) == std::vector<int>{11, 6}));
    // Closed: no path; a zone on a blocked cell has none either.
    free[7] = 0;
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, false) == std::vector<int>{-1, -1}));
    free[7] = 1;
    free[1 * 10 + 5] = 0;
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, false) == std::vector<int>{11, -1}));
    // No cell centre in the destination disc: only from_goal_cell floods from its cell.
    free[1 * 10 + 5] = 1;
    env.dest_x_m = 0.92;  // 3 cm from the centre of its cell (9, 1)
    env.dest_radius_m = 0.01;
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, false) == std::vector<int>{-1, -1}));
    assert_true((qnav::zone_steps(env, free, 10, 3, 0.1, true) == std::vector<int>{11, 6}));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_family_is_passable_for_both_robots_over_many_seeds),
        cmocka_unit_test(test_same_spec_gives_byte_identical_toml_and_seeds_differ),
        cmocka_unit_test(test_bad_specs_give_one_line_naming_the_field),
        cmocka_unit_test(test_gaps_at_difficulty_one_are_two_and_a_half_to_three_diameters),
        cmocka_unit_test(test_u_pocket_faces_the_start),
        cmocka_unit_test(test_gen_env_writes_the_world_the_spec_loads_and_refuses_bad_names),
        cmocka_unit_test(test_zone_steps_count_the_shortest_grid_path_to_each_zone),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
