/*
 * The adversarial benchmark (issue 19, item 2; bench/README.md, "Adversarial search"): a
 * search for the policies and scans that make qnav_ctrl_step() cost the most, beside the
 * fixtures. A step's cost is the number of hidden-unit evaluations it makes, counted by
 * libqnav built with QNAV_BENCH_COUNT = 1 (qnav_ctrl_count_evals): deterministic, and
 * proportional to ATmega128 cycles up to the step's fixed part (tools/bench-proxy checks
 * it against simavr). For each target (N, H) of the issue:
 *
 *   1. screen: every seed policy with H hidden units (the fixtures' 2-input networks, the
 *      policies evolved in other worlds listed in bench/adversary/policies.txt, random
 *      networks) on every seed scan of N sectors (the fixtures', scans ray-cast by the
 *      simulator along episodes in several worlds, random ones), each with its own goal
 *      bearing and a few random ones;
 *   2. scan search: each evolved policy unchanged, its scan and bearing hill-climbed from
 *      its worst seed scan (what any evolved policy can cost);
 *   3. joint search: the worst of those and every random network, policy weights (over
 *      the whole Q8.8 range) and scan hill-climbed together (what any policy can cost).
 *
 * It prints what each phase found and, with --out, writes the worst few of each target as
 * the adversarial set (bench_policies.h and bench_scans.h in the fixtures' format, policy
 * k found with scan adversary:k), which the ATmega128 image qnav_bench_avr_adversary runs.
 * Deterministic: same seed and effort, same output; no clock is read.
 *
 *   qnav_bench_adversary [--seed S] [--effort E] [--out DIR] SOURCE_ROOT
 *
 * Bad input: one line on stderr, exit 2.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_grid.h"
#include "fixture_io.h"
#include "qnav/rng.h"
#include "qnav/sim.h"

#if !QNAV_BENCH_COUNT
#error "adversary.c needs libqnav built with QNAV_BENCH_COUNT=1"
#endif

/* The targets (issue 19): sector count and hidden units. */
typedef struct {
    uint16_t n;
    uint8_t hidden;
} target_t;
static const target_t targets[] = {{32u, 12u}, {32u, 16u}, {180u, 12u}};
#define N_TARGETS (sizeof targets / sizeof targets[0])

/* Worlds whose scans seed the search: the paper's cluttered ones and one of each family of
 * the simulator's generator at a high difficulty (docs/sim.md, "World families"). */
static const char *const worlds[] = {
    "dense", "cluttered", "gen:pocket:11:0.9", "gen:gaps:12:0.9", "gen:clutter:13:0.9",
    "gen:corridor:14:0.9", "gen:rooms:15:0.9", "gen:pocket:16:0.5", "gen:clutter:17:0.5"};
#define N_WORLDS (sizeof worlds / sizeof worlds[0])
#define WORLD_EVERY_TICKS 10u   /* one scan kept every this many ticks of an episode */
#define WORLD_MAX_SCANS 60u     /* per episode */
#define WORLD_DRIVERS 3u        /* episodes per world: the TekBot's probabilistic policy and
                                   the first listed evolved policies */

/* Search sizes at --effort 1 (a few minutes on one core); --effort E multiplies the
 * iterations of both climbs. */
#define RANDOM_SCANS 24u        /* per sector count */
#define RANDOM_NETS 6u          /* per hidden-unit count */
#define SCREEN_BEARINGS 3u      /* random bearings tried per seed scan, besides its own */
#define SCAN_ITERS 1500u        /* scan search, per evolved policy */
#define JOINT_FROM_EVOLVED 4u   /* joint search starts from this many scan-search results */
#define JOINT_ITERS 10000u      /* joint search, per start */
#define JOINT_POLICY_PCT 30u    /* share of joint iterations that mutate the policy */
/* Written per target: the joint search's worst, and the scan search's worst of the listed
 * policies and of the fixtures' (evolved policies as they are). */
#define WRITE_JOINT 3u
#define WRITE_LISTED 2u
#define WRITE_FIXTURE 1u

#define MAX_SEEDS 160u

/* Where a seed policy comes from. */
enum { FROM_FIXTURE = 0, FROM_LIST, FROM_RANDOM };

typedef struct {
    qnav_policy_t policy;
    char id[QNAV_BENCH_ID_LEN];
    char origin[200];
    uint8_t from;     /* FROM_* */
    uint8_t evolved;  /* 1: evolved (a fixture of the evolved set, or listed) */
} seed_t;

typedef struct {
    uint16_t n;
    qnav_cdeg_t bearing;
    qnav_mm_t r[QNAV_MAX_SECTORS];
    char origin[96];  /* the seed scan it was made from */
} scan_t;

typedef struct {
    scan_t *s;
    unsigned count;
    unsigned cap;
} pool_t;

/* A (policy, scan) pair and its cost. */
typedef struct {
    qnav_policy_t policy;
    scan_t scan;
    uint32_t cost;
    unsigned seed;    /* index of the seed policy it started from */
} cand_t;

/* A written member of the adversarial set. */
typedef struct {
    cand_t c;
    char id[QNAV_BENCH_ID_LEN];
    const char *how;
} member_t;

typedef struct {
    uint64_t seed;
    uint32_t effort;
    const char *root;
    const char *out;
} options_t;

/* ---- random numbers (xorshift64*, seeded through qnav/rng.h's splitmix64) ---------- */
/* Its own generator rather than qnav/rng.h's xoshiro256**: the committed adversarial set
 * (bench/adversary/) is this sequence's, and another would change it. */

typedef struct {
    uint64_t s;
} rng_t;

/* splitmix64's first output from state x (a seed mixer). */
static uint64_t splitmix64(uint64_t x)
{
    return qnav_splitmix64(&x);
}

/* A stream for (seed, a, b, c): phases and starts do not share one. */
static rng_t rng_for(uint64_t seed, unsigned a, unsigned b, unsigned c)
{
    rng_t r;
    r.s = splitmix64(seed ^ splitmix64(((uint64_t)a << 40) ^ ((uint64_t)b << 20) ^ c)) | 1u;
    return r;
}

static uint64_t rng_next(rng_t *r)
{
    r->s ^= r->s >> 12;
    r->s ^= r->s << 25;
    r->s ^= r->s >> 27;
    return r->s * 2685821657736338717ull;
}

static uint32_t rng_below(rng_t *r, uint32_t n)
{
    return (uint32_t)((rng_next(r) >> 32) % n);
}

static int32_t rng_range(rng_t *r, int32_t lo, int32_t hi)
{
    return lo + (int32_t)rng_below(r, (uint32_t)(hi - lo + 1));
}

/* Cauchy(0, scale) clipped to +-clip (simevo's mutation). */
static double rng_cauchy(rng_t *r, double scale, double clip)
{
    double u = ((double)(rng_next(r) >> 11) + 0.5) / 9007199254740992.0;
    double v = scale * tan(3.14159265358979323846 * (u - 0.5));
    return v > clip ? clip : (v < -clip ? -clip : v);
}

static int16_t sat_q8_8(double w)
{
    double q = floor(w + 0.5);
    return (int16_t)(q > 32767.0 ? 32767.0 : (q < -32768.0 ? -32768.0 : q));
}

/* ---- cost ---------------------------------------------------------------------------- */

/* Hidden-unit evaluations of one step of c on s, with the benchmark grid's inputs. */
static uint32_t step_cost(qnav_ctrl_t *c, const scan_t *s)
{
    qnav_ctrl_input_t in;
    qnav_ctrl_output_t out;
    uint32_t evals = 0;
    memset(&in, 0, sizeof in);
    in.ranges_mm = s->r;
    in.goal_bearing_cdeg = s->bearing;
    in.prev_heading_cdeg = QNAV_BENCH_PREV_CDEG;
    qnav_ctrl_count_evals(c, &evals);
    qnav_ctrl_step(c, &in, &out, 0);
    qnav_ctrl_count_evals(c, 0);
    return evals;
}

static void ctrl_for(qnav_ctrl_t *c, const qnav_policy_t *p, uint16_t n)
{
    qnav_ctrl_config_t cfg;
    qnav_bench_config(&cfg, n);
    if (qnav_ctrl_init(c, &cfg, p) != QNAV_OK) {
        qnav_fx_fail(2, "a seed policy does not initialise a controller");
    }
}

/* ---- seed scans ---------------------------------------------------------------------- */

static scan_t *pool_add(pool_t *p, uint16_t n, const char *origin)
{
    scan_t *s;
    if (p->count == p->cap) {
        p->cap = p->cap ? 2u * p->cap : 256u;
        p->s = realloc(p->s, p->cap * sizeof *p->s);
        if (!p->s) {
            qnav_fx_fail(1, "out of memory");
        }
    }
    s = &p->s[p->count++];
    memset(s, 0, sizeof *s);
    s->n = n;
    snprintf(s->origin, sizeof s->origin, "%s", origin);
    return s;
}

static void fixture_scans(pool_t *p, uint16_t n)
{
    static const char *const names[QNAV_BENCH_SCAN_TYPES] = QNAV_BENCH_SCAN_NAMES;
    qnav_mm_t r[QNAV_MAX_SECTORS];
    for (uint16_t i = 0; i < qnav_bench_scan_count(); ++i) {
        qnav_cdeg_t bearing;
        uint8_t type, k;
        char origin[48];
        if (qnav_bench_load_scan(i, r, &bearing, &type, &k) != n) {
            continue;
        }
        snprintf(origin, sizeof origin, "fixture scan %s:%u", names[type], (unsigned)k);
        scan_t *s = pool_add(p, n, origin);
        memcpy(s->r, r, n * sizeof r[0]);
        s->bearing = bearing;
    }
}

/* One episode of driver in world (noise: the TekBot's typical), then the scan at every
 * kept pose (qnav_sim_place + qnav_sim_scan, as the fixtures' dense scans). */
static void world_episode(pool_t *p, uint16_t n, const char *world, const seed_t *driver,
                          qnav_sim_robot_t *robot)
{
    char err[QNAV_SIM_ERRLEN];
    qnav_sim_env_t *env = NULL;
    qnav_sim_t *sim = NULL;
    qnav_sim_config_t cfg;
    qnav_sim_robot_info_t info;
    qnav_sim_result_t res;
    qnav_ctrl_config_t ccfg;
    qnav_ctrl_t ctrl;
    static qnav_fx_pose_t poses[WORLD_MAX_SCANS];
    unsigned kept;
    if (qnav_sim_env_load(world, &env, err, sizeof err) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s", err);
    }
    qnav_sim_robot_info(robot, &info);
    qnav_sim_config_default(&cfg);
    cfg.n_sectors = n;
    cfg.sensor_noise = info.sensor_noise;
    cfg.actuation_noise = info.actuation_noise;
    if (qnav_sim_create(robot, env, &cfg, &sim, err, sizeof err) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s: %s", world, err);
    }
    qnav_sim_ctrl_config(sim, &ccfg);
    if (qnav_ctrl_init(&ctrl, &ccfg, &driver->policy) != QNAV_OK) {
        qnav_fx_fail(2, "%s: cannot run %s", world, driver->id);
    }
    kept = qnav_fx_episode_poses(sim, &ctrl, 1u, WORLD_EVERY_TICKS, poses, WORLD_MAX_SCANS, &res,
                                 world);
    for (unsigned k = 0; k < kept; ++k) {
        qnav_sim_scan_t sc;
        char origin[96];
        qnav_fx_scan_at(sim, poses[k].x_m, poses[k].y_m, poses[k].heading_rad, &sc, world);
        if (sc.max_range_mm != qnav_bench_max_range_mm()) {
            qnav_fx_fail(2, "%s: the simulator's range %u mm is not the benchmark's", world,
                         (unsigned)sc.max_range_mm);
        }
        snprintf(origin, sizeof origin, "%s tick %u (%s)", world, (unsigned)poses[k].tick, driver->id);
        scan_t *s = pool_add(p, n, origin);
        memcpy(s->r, sc.ranges_mm, n * sizeof sc.ranges_mm[0]);
        s->bearing = sc.goal_bearing_cdeg;
    }
    qnav_sim_destroy(sim);
    qnav_sim_env_free(env);
}

/* Scans ray-cast in every world, driven by the TekBot's probabilistic policy and the first
 * evolved policies of the list. */
static void world_scans(pool_t *p, uint16_t n, const char *root, const seed_t *seeds,
                        unsigned n_seeds)
{
    char err[QNAV_SIM_ERRLEN], path[1024];
    qnav_sim_robot_t *robot = NULL;
    seed_t drivers[WORLD_DRIVERS];
    unsigned n_drivers = 1;
    snprintf(path, sizeof path, "%s/data/robots/tekbot.toml", root);
    if (qnav_sim_robot_load(path, &robot, err, sizeof err) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s", err);
    }
    memset(&drivers[0], 0, sizeof drivers[0]);
    qnav_sim_robot_prob_policy(robot, &drivers[0].policy);
    snprintf(drivers[0].id, sizeof drivers[0].id, "prob-tekbot");
    for (unsigned i = 0; i < n_seeds && n_drivers < WORLD_DRIVERS; ++i) {
        if (seeds[i].from == FROM_LIST) {
            drivers[n_drivers++] = seeds[i];
        }
    }
    for (unsigned w = 0; w < N_WORLDS; ++w) {
        for (unsigned d = 0; d < n_drivers; ++d) {
            world_episode(p, n, worlds[w], &drivers[d], robot);
        }
    }
    qnav_sim_robot_free(robot);
}

/* i.i.d. ranges over 0..1.25 x the maximum (as the fixtures' random scans), half of them
 * drawn from only a few distance levels (many short runs of few levels). */
static void random_scans(pool_t *p, uint16_t n, rng_t *rng)
{
    int32_t top = (int32_t)(qnav_bench_max_range_mm() + qnav_bench_max_range_mm() / 4u);
    for (unsigned k = 0; k < RANDOM_SCANS; ++k) {
        char origin[32];
        int32_t few[3];
        snprintf(origin, sizeof origin, "random scan %u", k);
        scan_t *s = pool_add(p, n, origin);
        for (unsigned j = 0; j < 3; ++j) {
            few[j] = rng_range(rng, 0, top);
        }
        for (uint16_t i = 0; i < n; ++i) {
            s->r[i] = (qnav_mm_t)(k % 2u ? few[rng_below(rng, 3)] : rng_range(rng, 0, top));
        }
        s->bearing = (qnav_cdeg_t)rng_range(rng, -18000, 17999);
    }
}

/* ---- seed policies ------------------------------------------------------------------- */

static int usable(const qnav_policy_t *p)
{
    return p->kind == QNAV_POLICY_NET && p->u.net.inputs == QNAV_NET_INPUTS_PAPER;
}

/* The fixtures' 2-input networks (bench/fixtures/policies.txt). */
static unsigned fixture_policies(seed_t *out, unsigned max)
{
    unsigned count = 0;
    for (uint8_t i = 0; i < qnav_bench_policy_count() && count < max; ++i) {
        seed_t *s = &out[count];
        uint8_t set = qnav_bench_load_policy(i, &s->policy, s->id);
        if (!usable(&s->policy)) {
            continue;
        }
        s->from = FROM_FIXTURE;
        s->evolved = set == QNAV_BENCH_SET_EVOLVED;
        snprintf(s->origin, sizeof s->origin, "fixture %s", s->id);
        ++count;
    }
    return count;
}

/* The policies evolved in other worlds (bench/adversary/policies.txt). */
static unsigned listed_policies(const char *root, seed_t *out, unsigned max)
{
    static qnav_fx_policy_t list[MAX_SEEDS];
    char dir[1024];
    unsigned count = 0, n;
    snprintf(dir, sizeof dir, "%s/bench/adversary", root);
    n = qnav_fx_read_list(dir, "policies.txt", list, MAX_SEEDS);
    for (unsigned i = 0; i < n && count < max; ++i) {
        seed_t *s = &out[count];
        if (!usable(&list[i].policy)) {
            continue;
        }
        s->policy = list[i].policy;
        memcpy(s->id, list[i].id, sizeof s->id);
        snprintf(s->origin, sizeof s->origin, "%.23s (%.170s)", list[i].id, list[i].provenance);
        s->from = FROM_LIST;
        s->evolved = 1;
        ++count;
    }
    return count;
}

/* Random networks of every target's hidden-unit count: simevo's initial population
 * (clipped Cauchy weights) at scales from mild to saturating. */
static unsigned random_policies(uint64_t seed, seed_t *out, unsigned max)
{
    static const double scales[RANDOM_NETS] = {0.3, 1.0, 2.0, 4.0, 8.0, 30.0};
    unsigned count = 0;
    for (unsigned t = 0; t < N_TARGETS; ++t) {
        uint8_t h = targets[t].hidden;
        int seen = 0;
        for (unsigned i = 0; i < t; ++i) {
            seen |= targets[i].hidden == h;
        }
        for (unsigned k = 0; !seen && k < RANDOM_NETS && count < max; ++k) {
            seed_t *s = &out[count++];
            rng_t rng = rng_for(seed, 1u, h, k);
            qnav_policy_net_zero(&s->policy, h);
            for (uint16_t w = 0; w < qnav_net_weight_count(&s->policy.u.net); ++w) {
                *qnav_net_weight(&s->policy.u.net, w) = sat_q8_8(256.0 * rng_cauchy(&rng, scales[k], 10.0 * scales[k]));
            }
            snprintf(s->id, sizeof s->id, "random-h%u-%u", (unsigned)h, k);
            snprintf(s->origin, sizeof s->origin, "%s (clipped Cauchy weights of scale %.1f, seed %llu)",
                     s->id, scales[k], (unsigned long long)seed);
            s->from = FROM_RANDOM;
            s->evolved = 0;
        }
    }
    return count;
}

/* ---- moves --------------------------------------------------------------------------- */

static qnav_mm_t clip_range(int32_t v)
{
    int32_t top = (int32_t)(qnav_bench_max_range_mm() + qnav_bench_max_range_mm() / 4u);
    return (qnav_mm_t)(v < 0 ? 0 : (v > top ? top : v));
}

static qnav_cdeg_t wrap_cdeg(int32_t b)
{
    while (b >= 18000) {
        b -= 36000;
    }
    while (b < -18000) {
        b += 36000;
    }
    return (qnav_cdeg_t)b;
}

/* One random change of a scan: a sector anywhere or a few levels up or down, a block of
 * sectors set to one range, a sector copied from another, the bearing nudged or drawn. */
static void mutate_scan(scan_t *s, rng_t *rng)
{
    int32_t level_mm = (int32_t)qnav_bench_max_range_mm() / (QNAV_DIST_LEVELS - 1);
    uint16_t i = (uint16_t)rng_below(rng, s->n);
    switch (rng_below(rng, 6)) {
    case 0:
        s->r[i] = clip_range(rng_range(rng, 0, 1 << 16));
        break;
    case 1:
        s->r[i] = clip_range(s->r[i] + level_mm * rng_range(rng, -3, 3));
        break;
    case 2: {
        uint16_t len = (uint16_t)(1u + rng_below(rng, s->n / 4u + 1u));
        qnav_mm_t v = clip_range(rng_range(rng, 0, 1 << 16));
        for (uint16_t j = 0; j < len; ++j) {
            s->r[(i + j) % s->n] = v;
        }
        break;
    }
    case 3:
        s->r[i] = s->r[rng_below(rng, s->n)];
        break;
    case 4:
        s->bearing = wrap_cdeg(s->bearing + rng_range(rng, -1000, 1000));
        break;
    default:
        s->bearing = (qnav_cdeg_t)rng_range(rng, -18000, 17999);
        break;
    }
}

/* One random change of a network's weight: simevo's mutation, a larger step, or a value
 * anywhere in Q8.8. */
static void mutate_policy(qnav_policy_t *p, rng_t *rng)
{
    qnav_q8_8_t *w = qnav_net_weight(&p->u.net, (uint16_t)rng_below(rng, qnav_net_weight_count(&p->u.net)));
    switch (rng_below(rng, 4)) {
    case 0:
    case 1:
        *w = sat_q8_8(*w + 256.0 * rng_cauchy(rng, 0.3, 10.0));
        break;
    case 2:
        *w = sat_q8_8(*w + rng_range(rng, -2048, 2048));
        break;
    default:
        *w = (qnav_q8_8_t)rng_range(rng, -32768, 32767);
        break;
    }
}

/*
 * Hill-climb c: each iteration changes its policy (policy_pct % of them, then c's
 * controller *cur is made again) or its scan, and keeps the change when the cost does not
 * fall (equal costs move along plateaus).
 */
static void climb(cand_t *c, qnav_ctrl_t **cur, qnav_ctrl_t **spare, uint32_t iters,
                  unsigned policy_pct, rng_t *rng)
{
    scan_t trial;
    for (uint32_t it = 0; it < iters; ++it) {
        uint32_t cost;
        if (rng_below(rng, 100) < policy_pct) {
            qnav_policy_t p = c->policy;
            mutate_policy(&p, rng);
            ctrl_for(*spare, &p, c->scan.n);
            cost = step_cost(*spare, &c->scan);
            if (cost >= c->cost) {
                qnav_ctrl_t *t = *cur;
                *cur = *spare;
                *spare = t;
                c->policy = p;
                c->cost = cost;
            }
            continue;
        }
        trial = c->scan;
        mutate_scan(&trial, rng);
        cost = step_cost(*cur, &trial);
        if (cost >= c->cost) {
            c->scan = trial;
            c->cost = cost;
        }
    }
}

/* ---- the search ---------------------------------------------------------------------- */

typedef struct {
    options_t opt;
    seed_t seeds[MAX_SEEDS];
    unsigned n_seeds;
    pool_t pools[N_TARGETS];   /* seed scans of each target's sector count */
    qnav_ctrl_t ctrl[2];
    member_t set[N_TARGETS * (WRITE_JOINT + WRITE_LISTED + WRITE_FIXTURE)];
    unsigned n_set;
} search_t;

/* The pool of n-sector seed scans (made once per sector count). */
static pool_t *pool_for(search_t *S, uint16_t n)
{
    unsigned t = 0;
    while (targets[t].n != n) {
        ++t;
    }
    pool_t *p = &S->pools[t];
    if (p->count == 0) {
        rng_t rng = rng_for(S->opt.seed, 2u, n, 0u);
        fixture_scans(p, n);
        world_scans(p, n, S->opt.root, S->seeds, S->n_seeds);
        random_scans(p, n, &rng);
    }
    return p;
}

/* Phase 1 for one seed policy: its worst seed scan, each tried with its own bearing and
 * SCREEN_BEARINGS random ones. */
static void screen(search_t *S, unsigned seed, const pool_t *pool, const target_t *t, cand_t *c)
{
    rng_t rng = rng_for(S->opt.seed, 3u, t->n, seed);
    qnav_ctrl_t *ctrl = &S->ctrl[0];
    memset(c, 0, sizeof *c);
    c->policy = S->seeds[seed].policy;
    c->seed = seed;
    ctrl_for(ctrl, &c->policy, t->n);
    for (unsigned i = 0; i < pool->count; ++i) {
        scan_t s = pool->s[i];
        for (unsigned b = 0; b <= SCREEN_BEARINGS; ++b) {
            uint32_t cost;
            if (b > 0) {
                s.bearing = (qnav_cdeg_t)rng_range(&rng, -18000, 17999);
            }
            cost = step_cost(ctrl, &s);
            if (cost > c->cost || (i == 0 && b == 0)) {
                c->scan = s;
                c->cost = cost;
            }
        }
    }
}

/* The fixtures' worst: their policies of this target on their scans, as the grid runs them. */
static void fixtures_worst(search_t *S, const target_t *t, const pool_t *pool)
{
    uint32_t worst = 0;
    const char *who = "-", *what = "-";
    for (unsigned i = 0; i < S->n_seeds; ++i) {
        if (S->seeds[i].from != FROM_FIXTURE || S->seeds[i].policy.u.net.hidden != t->hidden) {
            continue;
        }
        ctrl_for(&S->ctrl[0], &S->seeds[i].policy, t->n);
        for (unsigned k = 0; k < pool->count && strncmp(pool->s[k].origin, "fixture", 7) == 0; ++k) {
            uint32_t cost = step_cost(&S->ctrl[0], &pool->s[k]);
            if (cost > worst) {
                worst = cost;
                who = S->seeds[i].id;
                what = pool->s[k].origin;
            }
        }
    }
    printf("  fixtures (their policies on their scans): worst %u (%s, %s)\n", (unsigned)worst,
           who, what);
}

static int by_cost(const void *a, const void *b)
{
    const cand_t *x = a, *y = b;
    if (x->cost != y->cost) {
        return x->cost < y->cost ? 1 : -1;
    }
    return x->seed < y->seed ? -1 : (x->seed > y->seed);
}

static void print_cands(search_t *S, const char *title, const cand_t *c, unsigned n, unsigned top)
{
    printf("  %s: %u candidates, worst first:\n", title, n);
    for (unsigned i = 0; i < n && i < top; ++i) {
        printf("    %6u  %-22s %s, bearing %d cdeg\n", (unsigned)c[i].cost, S->seeds[c[i].seed].id,
               c[i].scan.origin, (int)c[i].scan.bearing);
    }
}

/* Add the first `count` candidates of c[0..n-1] from seeds of kind `from` (any: -1) to
 * the set, with ids adv-<tag><H>-n<N>-<k>. */
static void keep(search_t *S, const target_t *t, const cand_t *c, unsigned n, int from,
                 unsigned count, char tag, const char *how)
{
    unsigned k = 0;
    for (unsigned i = 0; i < n && k < count; ++i) {
        member_t *m;
        if (from >= 0 && S->seeds[c[i].seed].from != from) {
            continue;
        }
        m = &S->set[S->n_set++];
        m->c = c[i];
        m->how = how;
        /* bounded (H <= 32, N <= 360, k < 100) so the id always fits */
        snprintf(m->id, sizeof m->id, "adv-%c%u-n%u-%u", tag, (unsigned)t->hidden % 100u,
                 (unsigned)t->n % 1000u, k++ % 100u);
    }
}

/* A climb from `from` into *to: policy_pct % of its iterations change the policy; its
 * random numbers depend on the target, the kind of climb and the seed policy only. */
static void search_from(search_t *S, unsigned ti, const cand_t *from, unsigned policy_pct,
                        uint32_t iters, cand_t *to)
{
    rng_t rng = rng_for(S->opt.seed, 4u + policy_pct, ti, from->seed);
    qnav_ctrl_t *cur = &S->ctrl[0], *spare = &S->ctrl[1];
    *to = *from;
    ctrl_for(cur, &from->policy, targets[ti].n);
    climb(to, &cur, &spare, iters * S->opt.effort, policy_pct, &rng);
}

/* Phases 1-3 for one target; its worst go into the set. */
static void search_target(search_t *S, unsigned ti)
{
    const target_t *t = &targets[ti];
    static cand_t first[MAX_SEEDS], scan_found[MAX_SEEDS], joint[MAX_SEEDS];
    unsigned n_first = 0, n_scan = 0, n_joint = 0;
    pool_t *pool = pool_for(S, t->n);
    printf("\nN = %u, H = %u (hidden-unit evaluations per step; every path: %u, the design's "
           "bound: %u)\n", (unsigned)t->n, (unsigned)t->hidden, (unsigned)(QNAV_PATHS * t->hidden),
           (unsigned)(2u * QNAV_PATHS * t->hidden));
    fixtures_worst(S, t, pool);
    for (unsigned i = 0; i < S->n_seeds; ++i) {
        if (S->seeds[i].policy.u.net.hidden == t->hidden) {
            screen(S, i, pool, t, &first[n_first++]);
        }
    }
    qsort(first, n_first, sizeof first[0], by_cost);
    printf("  seeds: %u policies x %u scans x %u bearings\n", n_first, pool->count, SCREEN_BEARINGS + 1u);
    print_cands(S, "screen", first, n_first, 5);
    for (unsigned i = 0; i < n_first; ++i) {
        if (S->seeds[first[i].seed].evolved) {
            search_from(S, ti, &first[i], 0u, SCAN_ITERS, &scan_found[n_scan++]);
        }
    }
    qsort(scan_found, n_scan, sizeof scan_found[0], by_cost);
    print_cands(S, "scan search (evolved policies unchanged)", scan_found, n_scan, 8);
    for (unsigned i = 0; i < n_scan && i < JOINT_FROM_EVOLVED; ++i) {
        search_from(S, ti, &scan_found[i], JOINT_POLICY_PCT, JOINT_ITERS, &joint[n_joint++]);
    }
    for (unsigned i = 0; i < n_first; ++i) {
        if (!S->seeds[first[i].seed].evolved) {
            search_from(S, ti, &first[i], JOINT_POLICY_PCT, JOINT_ITERS, &joint[n_joint++]);
        }
    }
    qsort(joint, n_joint, sizeof joint[0], by_cost);
    print_cands(S, "joint search (policy and scan)", joint, n_joint, 8);
    keep(S, t, joint, n_joint, -1, WRITE_JOINT, 'j', "joint search");
    keep(S, t, scan_found, n_scan, FROM_LIST, WRITE_LISTED, 'e', "scan search, the evolved policy unchanged");
    keep(S, t, scan_found, n_scan, FROM_FIXTURE, WRITE_FIXTURE, 'f', "scan search, the fixture policy unchanged");
}

/* ---- output -------------------------------------------------------------------------- */

static void write_set(const search_t *S)
{
    static qnav_fx_policy_t pol[N_TARGETS * (WRITE_JOINT + WRITE_LISTED + WRITE_FIXTURE)];
    static qnav_fx_scan_t scans[N_TARGETS * (WRITE_JOINT + WRITE_LISTED + WRITE_FIXTURE)];
    static int32_t ranges[N_TARGETS * (WRITE_JOINT + WRITE_LISTED + WRITE_FIXTURE) * QNAV_MAX_SECTORS];
    char about[1024];
    uint32_t offset = 0;
    for (unsigned i = 0; i < S->n_set; ++i) {
        const member_t *m = &S->set[i];
        const seed_t *from = &S->seeds[m->c.seed];
        snprintf(pol[i].id, sizeof pol[i].id, "%s", m->id);
        pol[i].set = QNAV_BENCH_SET_ADVERSARY;
        pol[i].group = 0;
        pol[i].policy = m->c.policy;
        snprintf(pol[i].provenance, sizeof pol[i].provenance, "%s from %s; %u evaluations on scan adversary:%u",
                 m->how, from->origin, (unsigned)m->c.cost, i);
        scans[i].n = m->c.scan.n;
        scans[i].type = QNAV_BENCH_SCAN_ADVERSARY;
        scans[i].k = (uint8_t)i;
        scans[i].bearing = m->c.scan.bearing;
        scans[i].offset = offset;
        snprintf(scans[i].note, sizeof scans[i].note, "with %s, from %s", m->id, m->c.scan.origin);
        for (uint16_t j = 0; j < m->c.scan.n; ++j) {
            ranges[offset + j] = m->c.scan.r[j];
        }
        offset += m->c.scan.n;
    }
    snprintf(about, sizeof about,
             "The adversarial set (bench/README.md, \"Adversarial search\"): policy k was found with\n"
             " * scan adversary:k. Generated by bench/adversary.c, do not edit:\n"
             " *   build/host-release/bench/qnav_bench_adversary --seed %llu --effort %u --out bench/adversary .",
             (unsigned long long)S->opt.seed, (unsigned)S->opt.effort);
    qnav_fx_write_policies(S->opt.out, about, pol, S->n_set);
    qnav_fx_write_scans(S->opt.out, about, scans, S->n_set, ranges, qnav_bench_max_range_mm());
}

static void parse_args(int argc, char **argv, options_t *o)
{
    o->seed = 1;
    o->effort = 1;
    o->out = 0;
    o->root = 0;
    for (int i = 1; i < argc; ++i) {
        char *end = 0;
        if (strcmp(argv[i], "--seed") == 0 && i + 1 < argc) {
            o->seed = strtoull(argv[++i], &end, 10);
        } else if (strcmp(argv[i], "--effort") == 0 && i + 1 < argc) {
            unsigned long e = strtoul(argv[++i], &end, 10);
            if (e < 1 || e > 10000) {
                qnav_fx_fail(2, "--effort %s: not a whole number in 1..10000", argv[i]);
            }
            o->effort = (uint32_t)e;
        } else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
            o->out = argv[++i];
        } else if (argv[i][0] != '-' && !o->root) {
            o->root = argv[i];
        } else {
            qnav_fx_fail(2, "usage: qnav_bench_adversary [--seed S] [--effort E] [--out DIR] SOURCE_ROOT");
        }
        if (end && *end) {
            qnav_fx_fail(2, "%s %s: not a whole number", argv[i - 1], argv[i]);
        }
    }
    if (!o->root) {
        qnav_fx_fail(2, "usage: qnav_bench_adversary [--seed S] [--effort E] [--out DIR] SOURCE_ROOT");
    }
}

int main(int argc, char **argv)
{
    static search_t S;
    unsigned n_fix, n_list, n_rand;
    parse_args(argc, argv, &S.opt);
    n_fix = fixture_policies(S.seeds, MAX_SEEDS);
    n_list = listed_policies(S.opt.root, S.seeds + n_fix, MAX_SEEDS - n_fix);
    n_rand = random_policies(S.opt.seed, S.seeds + n_fix + n_list, MAX_SEEDS - n_fix - n_list);
    S.n_seeds = n_fix + n_list + n_rand;
    printf("qnav adversarial search: seed %llu, effort %u\n", (unsigned long long)S.opt.seed,
           (unsigned)S.opt.effort);
    printf("seed policies: %u fixtures (2-input networks), %u evolved in other worlds "
           "(bench/adversary/policies.txt), %u random\n", n_fix, n_list, n_rand);
    for (unsigned t = 0; t < N_TARGETS; ++t) {
        search_target(&S, t);
        fflush(stdout);
    }
    printf("\nadversarial set: %u policies, policy k with scan adversary:k\n", S.n_set);
    for (unsigned i = 0; i < S.n_set; ++i) {
        printf("  %-16s N %3u  %6u evaluations  %s from %s\n", S.set[i].id, (unsigned)S.set[i].c.scan.n,
               (unsigned)S.set[i].c.cost, S.set[i].how, S.seeds[S.set[i].c.seed].id);
    }
    if (S.opt.out) {
        write_set(&S);
        printf("written: %s/bench_policies.h, %s/bench_scans.h\n", S.opt.out, S.opt.out);
    }
    return 0;
}
