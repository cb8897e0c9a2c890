/*
 * Generator of the benchmark set (bench/fixtures/README.md): reads the policy list
 * bench/fixtures/policies.txt and its policy files, ray-casts the dense scans with the
 * simulator's own sonar (qnav_sim_place + qnav_sim_scan in data/envs/dense.toml, TekBot,
 * no noise), computes the synthetic scans (clear, goal behind, obstacle at the goal,
 * corridor, i.i.d. random) and compiles the AVR flash tables, then writes three C headers
 * of QNAV_FLASH data. Same inputs, same bytes: a CTest compares the committed headers with
 * a fresh run.
 *
 *   qnav_bench_fixtures SOURCE_ROOT OUT_DIR
 *
 * Bad input: one line "FILE:LINE: problem" on stderr, exit 2; a failed write: exit 1.
 */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench_fixtures.h"
#include "qnav/policy_io.h"
#include "qnav/sim.h"
#include "vector_policy.h"

#define MAX_POLICIES 64
#define MAX_GROUPS 8
#define TABLES_PER_GROUP 1
#define BODY_RADIUS_MM 120.0 /* TekBot: ranges are measured from the body's rim */
#define PI 3.14159265358979323846

static const uint16_t sector_counts[] = {8, 16, 32, 64, 180, 360};
#define N_COUNTS (sizeof sector_counts / sizeof sector_counts[0])

static const char *const set_names[QNAV_BENCH_SETS] = {"evolved", "random", "prob"};
static const char *const set_macros[QNAV_BENCH_SETS] = {
    "QNAV_BENCH_SET_EVOLVED", "QNAV_BENCH_SET_RANDOM", "QNAV_BENCH_SET_PROB"};
static const char *const type_macros[QNAV_BENCH_SCAN_TYPES] = {
    "QNAV_BENCH_SCAN_CLEAR", "QNAV_BENCH_SCAN_BEHIND", "QNAV_BENCH_SCAN_OBSTACLE",
    "QNAV_BENCH_SCAN_CORRIDOR", "QNAV_BENCH_SCAN_DENSE", "QNAV_BENCH_SCAN_RANDOM"};

/* Dense poses: world frame x, y (m) and heading (deg), in the free lanes of dense.toml
 * (start zones, between the rows, near the destination), some facing away from it. */
static const double dense_poses[][3] = {
    {1.6, 1.1, 90.0}, {5.0, 1.1, -90.0}, {8.4, 1.1, 120.0}, {4.7, 4.0, 60.0},
    {4.8, 5.9, 100.0}, {5.0, 7.8, 80.0}, {2.4, 2.2, 45.0}, {7.6, 4.1, 150.0}};
#define N_DENSE (sizeof dense_poses / sizeof dense_poses[0])

/* Goal bearings of the synthetic scans, 0.01 deg. */
static const qnav_cdeg_t clear_bearings[] = {0, 4500, -9000, 13500};
static const qnav_cdeg_t obstacle_bearings[] = {0, 3000, -6000};
static const qnav_cdeg_t corridor_bearings[] = {0, 1000, -2000};
/* The shared benchmark's bearings for its PRNG scans (bench_common.h before issue 9). */
static const qnav_cdeg_t random_bearings[] = {0, 4500, -9000, 17999, -13550, 2050};
#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

typedef struct {
    char id[QNAV_BENCH_ID_LEN];
    uint8_t set;
    uint8_t group;
    char provenance[256];
    qnav_policy_t policy;
} policy_entry_t;

/* A wall in the robot frame (x ahead, y left), mm. */
typedef struct {
    double x0, y0, x1, y1;
} segment_t;

static policy_entry_t policies[MAX_POLICIES];
static unsigned n_policies;

static void fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("qnav_bench_fixtures: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(code);
}

/* ---- policy list ------------------------------------------------------------------- */

static int id_ok(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= QNAV_BENCH_ID_LEN) {
        return 0;
    }
    for (; *s; ++s) {
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
              *s == '-')) {
            return 0;
        }
    }
    return 1;
}

/* The policy that SOURCE names; 0, or -1 with a message in err. */
static int load_source(const char *dir, const char *src, qnav_policy_t *p, char *err, size_t errlen)
{
    unsigned h, wide;
    unsigned long seed;
    if (strncmp(src, "file:", 5) == 0) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, src + 5);
        return qnav_policy_read(path, p, err, errlen);
    }
    if (sscanf(src, "vector:%u:%lx:%u", &h, &seed, &wide) == 3 && h >= 1 && h <= 16 && wide <= 1) {
        qnav_vectors_net_policy(p, (uint8_t)h, (uint32_t)seed, (uint8_t)wide);
        return 0;
    }
    if (sscanf(src, "vector-prev:%u:%lx", &h, &seed) == 2 && h >= 1 && h <= 16) {
        /* the same network with a third input whose weights mirror w_theta's */
        qnav_vectors_net_policy(p, (uint8_t)h, (uint32_t)seed, 0u);
        p->u.net.inputs = QNAV_NET_INPUTS_PREV;
        for (unsigned j = 0; j < h; ++j) {
            p->u.net.w_prev[j] = (qnav_q8_8_t)(-p->u.net.w_theta[j] / 2);
        }
        return 0;
    }
    if (strcmp(src, "prob:default") == 0) {
        qnav_policy_prob_default(p);
        return 0;
    }
    if (strcmp(src, "prob:tekbot") == 0) {
        char e[QNAV_SIM_ERRLEN];
        qnav_sim_robot_t *robot = NULL;
        char path[1024];
        snprintf(path, sizeof path, "%s/../../data/robots/tekbot.toml", dir);
        if (qnav_sim_robot_load(path, &robot, e, sizeof e) != QNAV_SIM_OK) {
            snprintf(err, errlen, "%s", e);
            return -1;
        }
        qnav_sim_robot_prob_policy(robot, p);
        qnav_sim_robot_free(robot);
        return 0;
    }
    snprintf(err, errlen, "source '%s' is none of file:PATH, vector:H:SEED:WIDE (H 1..16), "
             "vector-prev:H:SEED, prob:default, prob:tekbot", src);
    return -1;
}

static void read_manifest(const char *dir)
{
    char path[1024];
    char line[1024];
    unsigned lineno = 0;
    FILE *f;
    snprintf(path, sizeof path, "%s/policies.txt", dir);
    f = fopen(path, "r");
    if (!f) {
        fail(2, "%s: cannot open (%s)", path, strerror(errno));
    }
    while (fgets(line, sizeof line, f)) {
        char id[64], set[32], group[8], src[512], ex[64], cond[64], run[32], commit[48], extra[8];
        char err[QNAV_POLICY_IO_ERRLEN];
        policy_entry_t *e;
        int n;
        ++lineno;
        if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0') {
            continue;
        }
        n = sscanf(line, "%63s %31s %7s %511s %63s %63s %31s %47s %7s", id, set, group, src, ex,
                   cond, run, commit, extra);
        if (n != 8) {
            fail(2, "%s:%u: expected 8 fields (ID SET TABLE SOURCE EXPERIMENT CONDITION RUN COMMIT), got %d",
                 path, lineno, n);
        }
        if (n_policies == MAX_POLICIES) {
            fail(2, "%s:%u: more than %d policies", path, lineno, MAX_POLICIES);
        }
        e = &policies[n_policies];
        if (!id_ok(id)) {
            fail(2, "%s:%u: ID '%s' is not 1..%u letters, digits or '-'", path, lineno, id,
                 QNAV_BENCH_ID_LEN - 1u);
        }
        for (unsigned i = 0; i < n_policies; ++i) {
            if (strcmp(policies[i].id, id) == 0) {
                fail(2, "%s:%u: ID '%s' given twice", path, lineno, id);
            }
        }
        snprintf(e->id, sizeof e->id, "%s", id);
        e->set = QNAV_BENCH_SETS;
        for (uint8_t s = 0; s < QNAV_BENCH_SETS; ++s) {
            if (strcmp(set, set_names[s]) == 0) {
                e->set = s;
            }
        }
        if (e->set == QNAV_BENCH_SETS) {
            fail(2, "%s:%u: SET '%s' is not evolved, random or prob", path, lineno, set);
        }
        if (strcmp(group, "-") == 0) {
            e->group = 0;
        } else if (strlen(group) == 1 && group[0] >= '1' && group[0] <= '0' + MAX_GROUPS) {
            e->group = (uint8_t)(group[0] - '0');
        } else {
            fail(2, "%s:%u: TABLE '%s' is not - or 1..%d", path, lineno, group, MAX_GROUPS);
        }
        if (load_source(dir, src, &e->policy, err, sizeof err) != 0) {
            fail(2, "%s:%u: %s", path, lineno, err);
        }
        if (e->group != 0 && (e->policy.kind != QNAV_POLICY_NET ||
                              e->policy.u.net.inputs != QNAV_NET_INPUTS_PAPER)) {
            fail(2, "%s:%u: only a 2-input network has a table", path, lineno);
        }
        if (e->policy.kind == QNAV_POLICY_NET && e->policy.u.net.hidden > 16) {
            fail(2, "%s:%u: more than 16 hidden units do not fit the ATmega128 build", path, lineno);
        }
        snprintf(e->provenance, sizeof e->provenance, "%s, %s %s %s at %s", src, ex, cond, run,
                 commit);
        ++n_policies;
    }
    fclose(f);
    for (uint8_t g = 1; g <= MAX_GROUPS; ++g) {
        unsigned c = 0;
        for (unsigned i = 0; i < n_policies; ++i) {
            c += policies[i].group == g;
        }
        if (c > TABLES_PER_GROUP) {
            fail(2, "%s: table group %u holds %u tables; at most %d fits an AVR image beside the scans",
                 path, (unsigned)g, c, TABLES_PER_GROUP);
        }
    }
}

/* ---- output ------------------------------------------------------------------------ */

typedef struct {
    FILE *f;
    char tmp[1100];
    char path[1100];
} out_t;

static void out_open(out_t *o, const char *dir, const char *name)
{
    int fd;
    snprintf(o->path, sizeof o->path, "%s/%s", dir, name);
    snprintf(o->tmp, sizeof o->tmp, "%s/.%s.XXXXXX", dir, name);
    fd = mkstemp(o->tmp);
    if (fd < 0 || fchmod(fd, 0644) != 0 || !(o->f = fdopen(fd, "w"))) {
        fail(1, "%s: cannot create (%s)", o->tmp, strerror(errno));
    }
}

static void out_close(out_t *o)
{
    if (ferror(o->f) || fclose(o->f) != 0 || rename(o->tmp, o->path) != 0) {
        unlink(o->tmp);
        fail(1, "%s: write failed (%s)", o->path, strerror(errno));
    }
}

static void put_values(FILE *f, const int32_t *v, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        fprintf(f, "%s%d,", i % 12u == 0 ? "\n   " : " ", (int)v[i]);
    }
    fputc('\n', f);
}

static const char header_note[] =
    "Generated by bench/gen_fixtures.c from bench/fixtures/policies.txt, do not edit:\n"
    " *   cmake --build --preset host-release --target qnav_bench_fixtures\n"
    " *   build/host-release/bench/qnav_bench_fixtures . bench/fixtures\n"
    " * The CTest bench.fixtures_match_generator fails when it is stale.";

static void put_weights(FILE *f, const char *name, const qnav_q8_8_t *w, unsigned h)
{
    fprintf(f, "        .%s = {", name);
    for (unsigned j = 0; j < h; ++j) {
        fprintf(f, "%s%d", j ? ", " : "", (int)w[j]);
    }
    fputs("},\n", f);
}

static void write_policies(const char *dir)
{
    out_t o;
    out_open(&o, dir, "bench_policies.h");
    fprintf(o.f, "/*\n * The benchmark's policies (bench/fixtures/README.md). %s\n */\n", header_note);
    fputs("#ifndef QNAV_BENCH_POLICIES_H\n#define QNAV_BENCH_POLICIES_H\n\n"
          "#include \"bench_fixtures.h\"\n\n", o.f);
    fprintf(o.f, "#define QNAV_BENCH_POLICY_COUNT %uu\n\n", n_policies);
    fputs("static const qnav_bench_policy_t qnav_bench_policies[QNAV_BENCH_POLICY_COUNT] QNAV_FLASH = {\n",
          o.f);
    for (unsigned i = 0; i < n_policies; ++i) {
        const policy_entry_t *e = &policies[i];
        fprintf(o.f, "    /* %s */\n", e->provenance);
        fprintf(o.f, "    {\"%s\", %s, %u, {.kind = ", e->id, set_macros[e->set], (unsigned)e->group);
        switch ((qnav_policy_kind_t)e->policy.kind) {
        case QNAV_POLICY_PROB:
            fprintf(o.f, "QNAV_POLICY_PROB, .u = {.prob = {%d, %d}}}},\n",
                    (int)e->policy.u.prob.k_goal, (int)e->policy.u.prob.k_safe);
            break;
        case QNAV_POLICY_NET: {
            const qnav_net_t *n = &e->policy.u.net;
            fprintf(o.f, "QNAV_POLICY_NET, .u = {.net = {\n        .hidden = %u, .inputs = %u,\n",
                    (unsigned)n->hidden, (unsigned)n->inputs);
            put_weights(o.f, "w_theta", n->w_theta, n->hidden);
            put_weights(o.f, "w_dist", n->w_dist, n->hidden);
            if (n->inputs == QNAV_NET_INPUTS_PREV) {
                put_weights(o.f, "w_prev", n->w_prev, n->hidden);
            }
            put_weights(o.f, "b_hidden", n->b_hidden, n->hidden);
            put_weights(o.f, "w_out", n->w_out, n->hidden);
            fprintf(o.f, "        .b_out = %d}}}},\n", (int)n->b_out);
            break;
        }
        }
    }
    fputs("};\n\n#endif /* QNAV_BENCH_POLICIES_H */\n", o.f);
    out_close(&o);
}

/* ---- scans ------------------------------------------------------------------------- */

#define MAX_SCANS_PER_N 32
#define MAX_RANGES (MAX_SCANS_PER_N * (8 + 16 + 32 + 64 + 180 + 360))

typedef struct {
    uint16_t n;
    uint8_t type, k;
    qnav_cdeg_t bearing;
    uint16_t offset;
    char note[96];
} scan_entry_t;

static scan_entry_t scans[N_COUNTS * MAX_SCANS_PER_N];
static unsigned n_scans;
static int32_t ranges[MAX_RANGES];
static unsigned n_ranges;
static unsigned max_range_mm;

static scan_entry_t *add_scan(uint16_t n, uint8_t type, uint8_t k, qnav_cdeg_t bearing)
{
    scan_entry_t *s = &scans[n_scans++];
    s->n = n;
    s->type = type;
    s->k = k;
    s->bearing = bearing;
    s->offset = (uint16_t)n_ranges;
    s->note[0] = '\0';
    n_ranges += n;
    return s;
}

/* Distance (mm) along direction a (rad) from the origin to segment w, or -1. */
static double ray_hit(double a, const segment_t *w)
{
    double dx = cos(a), dy = sin(a);
    double ex = w->x1 - w->x0, ey = w->y1 - w->y0;
    double den = dx * ey - dy * ex;
    double t, u;
    if (fabs(den) < 1e-12) {
        return -1.0;
    }
    t = (w->x0 * ey - w->y0 * ex) / den;
    u = (w->x0 * dy - w->y0 * dx) / den;
    return (t > 0.0 && u >= 0.0 && u <= 1.0) ? t : -1.0;
}

/* The sim's sonar model on walls: each sector reports the nearest wall point inside its
 * 360/N wedge, from the body's rim, clipped to [30, max] mm (sampled 64 rays per wedge). */
static void cast_walls(int32_t *r, uint16_t n, const segment_t *walls, unsigned n_walls)
{
    for (uint16_t s = 0; s < n; ++s) {
        double c = 2.0 * PI * s / n, half = PI / n;
        double best = 1e9;
        for (int i = 0; i <= 64; ++i) {
            double a = c - half + 2.0 * half * i / 64.0;
            for (unsigned w = 0; w < n_walls; ++w) {
                double d = ray_hit(a, &walls[w]);
                if (d >= 0.0 && d < best) {
                    best = d;
                }
            }
        }
        best -= BODY_RADIUS_MM;
        if (best > max_range_mm) {
            best = max_range_mm;
        }
        if (best < 30.0) {
            best = 30.0;
        }
        r[s] = (int32_t)lround(best);
    }
}

static void synthetic_scans(uint16_t n)
{
    unsigned k;
    for (k = 0; k < COUNT(clear_bearings); ++k) {
        scan_entry_t *s = add_scan(n, QNAV_BENCH_SCAN_CLEAR, (uint8_t)k, clear_bearings[k]);
        for (uint16_t i = 0; i < n; ++i) {
            ranges[s->offset + i] = (int32_t)max_range_mm;
        }
    }
    {
        /* goal behind: open; a wall 0.8 m ahead; a dead end (wall 0.6 m ahead and a wall
         * 0.5 m to the left) with the goal just right of behind */
        static const segment_t ahead[] = {{920, -600, 920, 600}};
        static const segment_t dead_end[] = {{720, -800, 720, 800}, {-1500, 620, 720, 620}};
        scan_entry_t *s = add_scan(n, QNAV_BENCH_SCAN_BEHIND, 0, 18000);
        cast_walls(&ranges[s->offset], n, NULL, 0);
        s = add_scan(n, QNAV_BENCH_SCAN_BEHIND, 1, 18000);
        cast_walls(&ranges[s->offset], n, ahead, COUNT(ahead));
        snprintf(s->note, sizeof s->note, "wall 0.8 m ahead");
        s = add_scan(n, QNAV_BENCH_SCAN_BEHIND, 2, -17500);
        cast_walls(&ranges[s->offset], n, dead_end, COUNT(dead_end));
        snprintf(s->note, sizeof s->note, "walls 0.6 m ahead and 0.5 m left");
    }
    for (k = 0; k < COUNT(obstacle_bearings); ++k) {
        /* a 0.6 m wide wall across the goal direction, 1.5 m from the rim */
        double a = obstacle_bearings[k] * PI / 18000.0;
        double d = 1500.0 + BODY_RADIUS_MM, cx = d * cos(a), cy = d * sin(a);
        segment_t w = {cx - 300.0 * -sin(a), cy - 300.0 * cos(a), cx + 300.0 * -sin(a),
                       cy + 300.0 * cos(a)};
        scan_entry_t *s = add_scan(n, QNAV_BENCH_SCAN_OBSTACLE, (uint8_t)k, obstacle_bearings[k]);
        cast_walls(&ranges[s->offset], n, &w, 1);
    }
    for (k = 0; k < COUNT(corridor_bearings); ++k) {
        static const segment_t walls[] = {{-6000, 720, 6000, 720}, {-6000, -720, 6000, -720}};
        scan_entry_t *s = add_scan(n, QNAV_BENCH_SCAN_CORRIDOR, (uint8_t)k, corridor_bearings[k]);
        cast_walls(&ranges[s->offset], n, walls, COUNT(walls));
    }
}

static void dense_scans(const char *root, uint16_t n)
{
    char err[QNAV_SIM_ERRLEN], path[1024];
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t cfg;
    snprintf(path, sizeof path, "%s/data/robots/tekbot.toml", root);
    if (qnav_sim_robot_load(path, &robot, err, sizeof err) != QNAV_SIM_OK) {
        fail(2, "%s", err);
    }
    snprintf(path, sizeof path, "%s/data/envs/dense.toml", root);
    if (qnav_sim_env_load(path, &env, err, sizeof err) != QNAV_SIM_OK) {
        fail(2, "%s", err);
    }
    qnav_sim_config_default(&cfg);
    cfg.n_sectors = n;
    if (qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err) != QNAV_SIM_OK ||
        qnav_sim_reset(sim, 1u) != QNAV_SIM_OK) {
        fail(2, "dense: %s", err);
    }
    for (unsigned p = 0; p < N_DENSE; ++p) {
        qnav_sim_scan_t sc;
        scan_entry_t *s;
        if (qnav_sim_place(sim, dense_poses[p][0], dense_poses[p][1], dense_poses[p][2] * PI / 180.0) !=
                QNAV_SIM_OK ||
            qnav_sim_scan(sim, &sc) != QNAV_SIM_OK) {
            fail(2, "dense pose %u: %s", p, qnav_sim_last_error(sim));
        }
        if (sc.max_range_mm != max_range_mm || sc.n_sectors != n) {
            fail(2, "dense pose %u: the simulator's scan has %u sectors and max %u mm", p,
                 (unsigned)sc.n_sectors, (unsigned)sc.max_range_mm);
        }
        s = add_scan(n, QNAV_BENCH_SCAN_DENSE, (uint8_t)p, sc.goal_bearing_cdeg);
        snprintf(s->note, sizeof s->note, "pose x %.1f m, y %.1f m, heading %.0f deg",
                 dense_poses[p][0], dense_poses[p][1], dense_poses[p][2]);
        for (uint16_t i = 0; i < n; ++i) {
            ranges[s->offset + i] = sc.ranges_mm[i];
        }
    }
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
    qnav_sim_robot_free(robot);
}

static void random_scans(uint16_t n)
{
    for (unsigned k = 0; k < COUNT(random_bearings); ++k) {
        uint32_t st = 0xBE7C0000ul + k;
        scan_entry_t *s = add_scan(n, QNAV_BENCH_SCAN_RANDOM, (uint8_t)k, random_bearings[k]);
        for (uint16_t i = 0; i < n; ++i) {
            ranges[s->offset + i] = (int32_t)(qnav_vectors_rand(&st) % (max_range_mm + max_range_mm / 4u + 1u));
        }
    }
}

static void tekbot_max_range(const char *root)
{
    char err[QNAV_SIM_ERRLEN], path[1024];
    qnav_sim_robot_t *robot = NULL;
    qnav_sim_robot_info_t info;
    snprintf(path, sizeof path, "%s/data/robots/tekbot.toml", root);
    if (qnav_sim_robot_load(path, &robot, err, sizeof err) != QNAV_SIM_OK) {
        fail(2, "%s", err);
    }
    qnav_sim_robot_info(robot, &info);
    max_range_mm = (unsigned)lround(info.range_max_m * 1000.0);
    qnav_sim_robot_free(robot);
}

static void write_scans(const char *root, const char *dir)
{
    out_t o;
    static const char *const type_names[QNAV_BENCH_SCAN_TYPES] = {"clear", "behind", "obstacle",
                                                                 "corridor", "dense", "random"};
    tekbot_max_range(root);
    for (unsigned c = 0; c < N_COUNTS; ++c) {
        synthetic_scans(sector_counts[c]);
        dense_scans(root, sector_counts[c]);
        random_scans(sector_counts[c]);
    }
    out_open(&o, dir, "bench_scans.h");
    fprintf(o.f, "/*\n * The benchmark's scans (bench/fixtures/README.md): for each sector count, "
                 "the scan types\n * of bench_fixtures.h. %s\n */\n", header_note);
    fputs("#ifndef QNAV_BENCH_SCANS_H\n#define QNAV_BENCH_SCANS_H\n\n#include \"bench_fixtures.h\"\n\n",
          o.f);
    fprintf(o.f, "/* TekBot sonar maximum range (data/robots/tekbot.toml), mm */\n"
                 "#define QNAV_BENCH_MAX_RANGE_MM %uu\n", max_range_mm);
    fprintf(o.f, "#define QNAV_BENCH_SCAN_COUNT %uu\n\n", n_scans);
    for (unsigned c = 0; c < N_COUNTS; ++c) {
        unsigned first = 0, count = 0;
        for (unsigned i = 0; i < n_scans; ++i) {
            if (scans[i].n == sector_counts[c]) {
                first = count == 0 ? scans[i].offset : first;
                count += scans[i].n;
            }
        }
        fprintf(o.f, "static const qnav_mm_t qnav_bench_ranges_%u[%u] QNAV_FLASH = {",
                (unsigned)sector_counts[c], count);
        put_values(o.f, &ranges[first], count);
        fputs("};\n\n", o.f);
    }
    fputs("static const qnav_bench_scan_t qnav_bench_scans[QNAV_BENCH_SCAN_COUNT] QNAV_FLASH = {\n", o.f);
    for (unsigned i = 0; i < n_scans; ++i) {
        const scan_entry_t *s = &scans[i];
        unsigned j = 0;
        while (scans[j].n != s->n) {
            ++j; /* the first scan of this sector count starts its array */
        }
        unsigned first = s->offset - scans[j].offset;
        fprintf(o.f, "    {%u, %s, %u, %d, &qnav_bench_ranges_%u[%u]}, /* %s:%u%s%s */\n", (unsigned)s->n,
                type_macros[s->type], (unsigned)s->k, (int)s->bearing, (unsigned)s->n, first,
                type_names[s->type], (unsigned)s->k, s->note[0] ? ", " : "", s->note);
    }
    fputs("};\n\n#endif /* QNAV_BENCH_SCANS_H */\n", o.f);
    out_close(&o);
}

/* ---- tables ------------------------------------------------------------------------ */

static void write_tables(const char *dir)
{
    out_t o;
    out_open(&o, dir, "bench_tables.h");
    fprintf(o.f, "/*\n * Compiled rank-key tables of the AVR table images, %d per image "
                 "(QNAV_BENCH_TABLE_GROUP);\n * other targets compile every policy's table at run "
                 "time. %s\n */\n", TABLES_PER_GROUP, header_note);
    fputs("#ifndef QNAV_BENCH_TABLES_H\n#define QNAV_BENCH_TABLES_H\n\n#include \"bench_fixtures.h\"\n\n"
          "#if QNAV_DIST_LEVELS != 32 || QNAV_DTHETA_MAX != 180\n"
          "#error \"bench_tables.h was generated for other QNAV_DIST_LEVELS/QNAV_DTHETA_MAX\"\n#endif\n\n",
          o.f);
    for (uint8_t g = 1; g <= MAX_GROUPS; ++g) {
        unsigned in_group = 0;
        char idx[64] = "", tabs[256] = "", ranks[128] = "";
        for (unsigned i = 0; i < n_policies; ++i) {
            qnav_ctrl_t ctrl;
            qnav_ctrl_config_t cfg;
            static qnav_qkey_t table[QNAV_QTABLE_ENTRIES];
            int32_t v[QNAV_QTABLE_ENTRIES];
            if (policies[i].group != g) {
                continue;
            }
            if (in_group == 0) {
                fprintf(o.f, "#if QNAV_BENCH_TABLE_GROUP == %u\n\n", (unsigned)g);
            }
            qnav_ctrl_config_default(&cfg);
            cfg.max_range_mm = (qnav_mm_t)max_range_mm;
            if (qnav_ctrl_init(&ctrl, &cfg, &policies[i].policy) != QNAV_OK ||
                qnav_ctrl_build_table(&ctrl, table) != QNAV_OK) {
                fail(2, "%s: cannot compile a table", policies[i].id);
            }
            for (unsigned e = 0; e < QNAV_QTABLE_ENTRIES; ++e) {
                v[e] = table[e];
            }
            fprintf(o.f, "/* %s (policy %u) */\nstatic const qnav_qkey_t qnav_bench_table_%u[QNAV_QTABLE_ENTRIES] "
                         "QNAV_FLASH = {", policies[i].id, i, i);
            put_values(o.f, v, QNAV_QTABLE_ENTRIES);
            fputs("};\n\n", o.f);
            snprintf(idx + strlen(idx), sizeof idx - strlen(idx), "%s%u", in_group ? ", " : "", i);
            snprintf(tabs + strlen(tabs), sizeof tabs - strlen(tabs), "%sqnav_bench_table_%u",
                     in_group ? ", " : "", i);
            snprintf(ranks + strlen(ranks), sizeof ranks - strlen(ranks), "%s%s", in_group ? ", " : "",
                     qnav_ctrl_rank(&ctrl) == QNAV_RANK_PREACT ? "QNAV_RANK_PREACT" : "QNAV_RANK_QUALITY");
            ++in_group;
        }
        if (in_group) {
            fprintf(o.f, "#define QNAV_BENCH_GROUP_TABLES %uu\n", in_group);
            fprintf(o.f, "static const uint8_t qnav_bench_group_policy[QNAV_BENCH_GROUP_TABLES] = {%s};\n", idx);
            fprintf(o.f, "static const qnav_qkey_t *const qnav_bench_group_table[QNAV_BENCH_GROUP_TABLES] = {%s};\n",
                    tabs);
            fprintf(o.f, "static const uint8_t qnav_bench_group_rank[QNAV_BENCH_GROUP_TABLES] = {%s};\n\n#endif\n\n",
                    ranks);
        }
    }
    fputs("#endif /* QNAV_BENCH_TABLES_H */\n", o.f);
    out_close(&o);
}

int main(int argc, char **argv)
{
    char dir[1024];
    if (argc != 3) {
        fprintf(stderr, "usage: qnav_bench_fixtures SOURCE_ROOT OUT_DIR\n");
        return 2;
    }
    snprintf(dir, sizeof dir, "%s/bench/fixtures", argv[1]);
    read_manifest(dir);
    write_policies(argv[2]);
    write_scans(argv[1], argv[2]);
    write_tables(argv[2]);
    return 0;
}
