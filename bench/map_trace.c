/*
 * The map's benchmark trace (bench/fixtures/README.md, "The map's trace"): episodes of the
 * TekBot with its map (data/robots/tekbot.toml, NAME+map) in generated worlds of several
 * families, each tick's pose and sonar scan as the simulator gives them, and what libqnav's
 * map makes of them on the host (the sub-goal's bearing and distance and the flags) for the
 * target to match. Written as bench_map_trace.h (QNAV_FLASH data) by qnav_bench_fixtures.
 */
#include "map_trace.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture_io.h"
#include "bench_map.h"
#include "qnav/map.h"
#include "qnav/sim.h"
#include "qnav/trig.h"

/* Worlds of three families (difficulty 0.5), one episode each, at most this many ticks:
 * the image holds them in flash beside libqnav. */
static const char *const worlds[] = {"gen:rooms:41:0.5:tekbot", "gen:gaps:42:0.5:tekbot",
                                     "gen:clutter:43:0.5:tekbot"};
#define N_WORLDS (sizeof worlds / sizeof worlds[0])
#define MAX_TICKS 300u
#define PI 3.14159265358979323846

static uint32_t mm(double m)
{
    return (uint32_t)ceil(m * 1000.0);
}

/* World k's ticks: each pose's scan (the robot placed there again) and what the map made
 * of it, as the header's array map_ticks_k. */
static void write_ticks(FILE *f, unsigned k, qnav_sim_t *sim, qnav_map_t *map,
                        const qnav_sim_env_info_t *ei, const qnav_fx_pose_t *poses, unsigned n)
{
    uint32_t t;
    fprintf(f, "static const qnav_bench_map_tick_t map_ticks_%u[%u] QNAV_FLASH = {\n", k,
            n);
    for (t = 0; t < n; ++t) {
        /* the pose in whole mm and 0.01 deg, as the target reads it */
        const qnav_map_pose_t p = {(int32_t)lround(poses[t].x_m * 1000.0),
                                   (int32_t)lround(poses[t].y_m * 1000.0),
                                   (int32_t)lround(poses[t].heading_rad * 18000.0 / PI)};
        qnav_sim_scan_t sc;
        qnav_ctrl_input_t in;
        int got;
        uint16_t i;
        qnav_fx_scan_at(sim, p.x_mm / 1000.0, p.y_mm / 1000.0, p.heading_cdeg * PI / 18000.0, &sc,
                        worlds[k]);
        if (sc.n_sectors != QNAV_BENCH_MAP_MAX_SECTORS) {
            qnav_fx_fail(2, "%s: %u sectors (the trace holds %u)", worlds[k], (unsigned)sc.n_sectors,
                         (unsigned)QNAV_BENCH_MAP_MAX_SECTORS);
        }
        memset(&in, 0, sizeof in);
        in.ranges_mm = sc.ranges_mm;
        (void)qnav_map_follow(map, &p, (int32_t)lround(ei->dest_x_m * 1000.0),
                              (int32_t)lround(ei->dest_y_m * 1000.0)); /* as the board */
        qnav_map_observe(map, sc.ranges_mm, &p);
        got = qnav_map_guide(map, &p, (int32_t)lround(ei->dest_x_m * 1000.0),
                             (int32_t)lround(ei->dest_y_m * 1000.0), &in);
        fprintf(f, "    {%ld, %ld, %ld, {", (long)p.x_mm, (long)p.y_mm,
                (long)qnav_wrap_cdeg(p.heading_cdeg));
        for (i = 0; i < sc.n_sectors; ++i) {
            fprintf(f, "%s%u", i ? ", " : "", (unsigned)sc.ranges_mm[i]);
        }
        fprintf(f, "}, %d, %u, %d},\n", (int)in.goal_bearing_cdeg, (unsigned)in.goal_range_mm, got);
    }
}

/* One world's episode, replayed through a fresh map, written as world k of the header. */
static size_t one_world(FILE *f, const char *root, unsigned k, qnav_map_config_t *mc,
                        qnav_ctrl_config_t *cc)
{
    static qnav_fx_pose_t poses[MAX_TICKS];
    unsigned n;
    static uint16_t mem[40000];
    char err[QNAV_SIM_ERRLEN], spec[1100];
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t cfg;
    qnav_sim_env_info_t ei;
    qnav_sim_result_t res;
    qnav_ctrl_t ctrl;
    qnav_policy_t pol;
    qnav_map_t map;
    size_t bytes;
    int32_t x0, y0;
    uint32_t side;
    snprintf(spec, sizeof spec, "%s/data/robots/tekbot.toml+map", root);
    if (qnav_sim_robot_load(spec, &robot, err, sizeof err) != QNAV_SIM_OK ||
        qnav_sim_env_load(worlds[k], &env, err, sizeof err) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s", err);
    }
    bytes = qnav_sim_robot_map_bytes(robot);
    if (!qnav_sim_robot_map_config(robot, mc) || mc->compact != 1u || bytes == 0u ||
        bytes > sizeof mem) {
        qnav_fx_fail(2, "%s: the benchmark is of a compact [map] in the board's [map] bytes",
                     spec);
    }
    qnav_sim_config_default(&cfg);
    if (qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s: %s", worlds[k], err);
    }
    qnav_sim_ctrl_config(sim, cc);
    qnav_sim_robot_prob_policy(robot, &pol);
    if (qnav_ctrl_init(&ctrl, cc, &pol) != QNAV_OK) {
        qnav_fx_fail(2, "%s: the profile's controller does not start", spec);
    }
    n = qnav_fx_episode_poses(sim, &ctrl, 1u, 1u, poses, MAX_TICKS, &res, worlds[k]);
    qnav_sim_env_info(env, &ei);
    /* the map the board places at the goal, from the start (the simulator's, too) */
    if (n == 0u ||
        !qnav_map_place(mc, bytes, (int32_t)lround(poses[0].x_m * 1000.0),
                        (int32_t)lround(poses[0].y_m * 1000.0), (int32_t)lround(ei.dest_x_m * 1000.0),
                        (int32_t)lround(ei.dest_y_m * 1000.0), &x0, &y0, &side) ||
        qnav_map_init(&map, mc, cc, x0, y0, side, side, mem, bytes) != QNAV_OK) {
        qnav_fx_fail(2, "%s: no map of %lu bytes placed between start and goal", worlds[k],
                     (unsigned long)bytes);
    }
    fprintf(f, "/* %s: %u ticks of episode 1 (%s in the simulator) */\n", worlds[k],
            n, res.reached ? "reached" : "not reached");
    if (mm(ei.width_m) > 32767u || mm(ei.height_m) > 32767u) {
        qnav_fx_fail(2, "%s: larger than 32.7 m (the trace keeps poses in 16 bits)", worlds[k]);
    }
    write_ticks(f, k, sim, &map, &ei, poses, n);
    fprintf(f, "};\n\n");
    fprintf(f, "#define QNAV_BENCH_MAP_WORLD_%u {\"%s\", %ld, %ld, %lu, %ld, %ld, map_ticks_%u, %u}\n\n", k,
            worlds[k], (long)x0, (long)y0, (unsigned long)side,
            lround(ei.dest_x_m * 1000.0), lround(ei.dest_y_m * 1000.0), k, n);
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
    return bytes;
}

void qnav_fx_write_map_trace(const char *root, const char *out_dir, const char *note)
{
    qnav_fx_out_t o;
    qnav_map_config_t mc;
    qnav_ctrl_config_t cc;
    size_t most = 0u;
    unsigned k;
    FILE *f;
    qnav_fx_open(&o, out_dir, "bench_map_trace.h");
    f = o.f;
    fprintf(f, "/*\n * The map's benchmark trace (bench/map_trace.c). %s\n */\n", note);
    fprintf(f, "#ifndef QNAV_BENCH_MAP_TRACE_H\n#define QNAV_BENCH_MAP_TRACE_H\n\n");
    fprintf(f, "#include \"bench_map.h\"\n\n");
    for (k = 0; k < N_WORLDS; ++k) {
        const size_t b = one_world(f, root, k, &mc, &cc);
        most = b > most ? b : most;
    }
    fprintf(f, "#define QNAV_BENCH_MAP_WORLDS %u\n", (unsigned)N_WORLDS);
    fprintf(f, "#define QNAV_BENCH_MAP_WORLD_LIST {");
    for (k = 0; k < N_WORLDS; ++k) {
        fprintf(f, "%sQNAV_BENCH_MAP_WORLD_%u", k ? ", " : "", k);
    }
    fprintf(f, "}\n/* The board's memory for the map ([map] bytes) */\n#define QNAV_BENCH_MAP_BYTES %lu\n\n",
            (unsigned long)most);
    fprintf(f, "/* The profile's map and the controller fields it reads (qnav/map.h) */\n");
    {
#define MAP_FIELD_VALUE(name, bits) (unsigned)mc.name,
        const unsigned values[] = {QNAV_MAP_CONFIG_FIELDS(MAP_FIELD_VALUE)};
#undef MAP_FIELD_VALUE
        size_t k;
        fprintf(f, "#define QNAV_BENCH_MAP_CONFIG {");
        for (k = 0; k < sizeof values / sizeof values[0]; ++k) {
            fprintf(f, "%s%u", k ? ", " : "", values[k]);
        }
        fprintf(f, "}\n");
    }
    fprintf(f, "#define QNAV_BENCH_MAP_SECTORS %u\n#define QNAV_BENCH_MAP_RANGE_MM %u\n"
               "#define QNAV_BENCH_MAP_OFFSET_MM %u\n#define QNAV_BENCH_MAP_RADIUS_MM %u\n"
               "#define QNAV_BENCH_MAP_SAFETY_MM %u\n\n#endif\n",
            (unsigned)cc.n_sectors, (unsigned)cc.max_range_mm, (unsigned)cc.sensor_offset_mm,
            (unsigned)cc.body_radius_mm, (unsigned)cc.safety_mm);
    qnav_fx_close(&o);
}
