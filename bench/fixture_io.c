/*
 * The benchmark generators' shared input and output (fixture_io.h): policy lists in
 * policies.txt's format, and the headers of policies and scans, byte for byte what the
 * committed fixtures hold (bench.fixtures_match_generator compares them).
 */
#define _POSIX_C_SOURCE 200809L
#include "fixture_io.h"

#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "qnav/policy_io.h"
#include "qnav/sim.h"
#include "vector_policy.h"

const char *const qnav_fx_set_names[QNAV_BENCH_SETS] = QNAV_BENCH_SET_NAMES;
static const char *const set_macros[QNAV_BENCH_SETS] = {
    "QNAV_BENCH_SET_EVOLVED", "QNAV_BENCH_SET_RANDOM", "QNAV_BENCH_SET_PROB",
    "QNAV_BENCH_SET_ADVERSARY"};
static const char *const type_names[QNAV_BENCH_SCAN_TYPES] = QNAV_BENCH_SCAN_NAMES;
static const char *const type_macros[QNAV_BENCH_SCAN_TYPES] = {
    "QNAV_BENCH_SCAN_CLEAR", "QNAV_BENCH_SCAN_BEHIND", "QNAV_BENCH_SCAN_OBSTACLE",
    "QNAV_BENCH_SCAN_CORRIDOR", "QNAV_BENCH_SCAN_DENSE", "QNAV_BENCH_SCAN_RANDOM",
    "QNAV_BENCH_SCAN_ADVERSARY"};

void qnav_fx_fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("qnav bench: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(code);
}

/* ---- policy lists ------------------------------------------------------------------ */

int qnav_fx_id_ok(const char *s)
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
    snprintf(err, errlen, "source '%.400s' is none of file:PATH, vector:H:SEED:WIDE (H 1..16), "
             "vector-prev:H:SEED, prob:default, prob:tekbot", src);
    return -1;
}

/* The entry of one list line (8 fields, checked) into e; ids of e[-count..-1] must differ. */
static void parse_entry(const char *path, unsigned lineno, const char *line, const char *dir,
                        qnav_fx_policy_t *e, const qnav_fx_policy_t *before, unsigned count)
{
    char id[64], set[32], group[8], src[512], ex[64], cond[64], run[32], commit[48], extra[8];
    char err[QNAV_POLICY_IO_ERRLEN];
    int n = sscanf(line, "%63s %31s %7s %511s %63s %63s %31s %47s %7s", id, set, group, src, ex,
                   cond, run, commit, extra);
    if (n != 8) {
        qnav_fx_fail(2, "%s:%u: expected 8 fields (ID SET TABLE SOURCE EXPERIMENT CONDITION RUN COMMIT), got %d",
                     path, lineno, n);
    }
    if (!qnav_fx_id_ok(id)) {
        qnav_fx_fail(2, "%s:%u: ID '%s' is not 1..%u letters, digits or '-'", path, lineno, id,
                     QNAV_BENCH_ID_LEN - 1u);
    }
    for (unsigned i = 0; i < count; ++i) {
        if (strcmp(before[i].id, id) == 0) {
            qnav_fx_fail(2, "%s:%u: ID '%s' given twice", path, lineno, id);
        }
    }
    memcpy(e->id, id, strlen(id) + 1u); /* qnav_fx_id_ok bounded it below QNAV_BENCH_ID_LEN */
    e->set = QNAV_BENCH_SETS;
    for (uint8_t s = 0; s < QNAV_BENCH_SETS; ++s) {
        if (strcmp(set, qnav_fx_set_names[s]) == 0) {
            e->set = s;
        }
    }
    if (e->set == QNAV_BENCH_SETS) {
        qnav_fx_fail(2, "%s:%u: SET '%s' is not evolved, random, prob or adversary", path, lineno, set);
    }
    if (strcmp(group, "-") == 0) {
        e->group = 0;
    } else if (strlen(group) == 1 && group[0] >= '1' && group[0] <= '9') {
        e->group = (uint8_t)(group[0] - '0');
    } else {
        qnav_fx_fail(2, "%s:%u: TABLE '%s' is not - or 1..9", path, lineno, group);
    }
    if (load_source(dir, src, &e->policy, err, sizeof err) != 0) {
        qnav_fx_fail(2, "%s:%u: %s", path, lineno, err);
    }
    if (e->group != 0 && (e->policy.kind != QNAV_POLICY_NET ||
                          e->policy.u.net.inputs != QNAV_NET_INPUTS_PAPER)) {
        qnav_fx_fail(2, "%s:%u: only a 2-input network has a table", path, lineno);
    }
    if (e->policy.kind == QNAV_POLICY_NET && e->policy.u.net.hidden > 16) {
        qnav_fx_fail(2, "%s:%u: more than 16 hidden units do not fit the ATmega128 build", path, lineno);
    }
    snprintf(e->provenance, sizeof e->provenance, "%.100s, %.40s %.40s %.20s at %.40s", src, ex, cond,
             run, commit);
}

unsigned qnav_fx_read_list(const char *dir, const char *name, qnav_fx_policy_t *out, unsigned max)
{
    char path[1024];
    char line[1024];
    unsigned lineno = 0;
    unsigned count = 0;
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "r");
    if (!f) {
        qnav_fx_fail(2, "%s: cannot open (%s)", path, strerror(errno));
    }
    while (fgets(line, sizeof line, f)) {
        ++lineno;
        if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0') {
            continue;
        }
        if (count == max) {
            qnav_fx_fail(2, "%s:%u: more than %u policies", path, lineno, max);
        }
        parse_entry(path, lineno, line, dir, &out[count], out, count);
        ++count;
    }
    fclose(f);
    return count;
}

/* ---- output ------------------------------------------------------------------------ */

void qnav_fx_open(qnav_fx_out_t *o, const char *dir, const char *name)
{
    int fd;
    snprintf(o->path, sizeof o->path, "%s/%s", dir, name);
    snprintf(o->tmp, sizeof o->tmp, "%s/.%s.XXXXXX", dir, name);
    fd = mkstemp(o->tmp);
    if (fd < 0 || fchmod(fd, 0644) != 0 || !(o->f = fdopen(fd, "w"))) {
        qnav_fx_fail(1, "%s: cannot create (%s)", o->tmp, strerror(errno));
    }
}

void qnav_fx_close(qnav_fx_out_t *o)
{
    if (ferror(o->f) || fclose(o->f) != 0 || rename(o->tmp, o->path) != 0) {
        unlink(o->tmp);
        qnav_fx_fail(1, "%s: write failed (%s)", o->path, strerror(errno));
    }
}

void qnav_fx_put_values(FILE *f, const int32_t *v, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        fprintf(f, "%s%d,", i % 12u == 0 ? "\n   " : " ", (int)v[i]);
    }
    fputc('\n', f);
}

static void put_weights(FILE *f, const char *name, const qnav_q8_8_t *w, unsigned h)
{
    fprintf(f, "        .%s = {", name);
    for (unsigned j = 0; j < h; ++j) {
        fprintf(f, "%s%d", j ? ", " : "", (int)w[j]);
    }
    fputs("},\n", f);
}

static void put_policy(FILE *f, const qnav_fx_policy_t *e)
{
    const qnav_net_t *n = &e->policy.u.net;
    fprintf(f, "    /* %s */\n", e->provenance);
    fprintf(f, "    {\"%s\", %s, %u, {.kind = ", e->id, set_macros[e->set], (unsigned)e->group);
    switch ((qnav_policy_kind_t)e->policy.kind) {
    case QNAV_POLICY_PROB:
        fprintf(f, "QNAV_POLICY_PROB, .u = {.prob = {%d, %d}}}},\n", (int)e->policy.u.prob.k_goal,
                (int)e->policy.u.prob.k_safe);
        break;
    case QNAV_POLICY_NET:
        fprintf(f, "QNAV_POLICY_NET, .u = {.net = {\n        .hidden = %u, .inputs = %u,\n",
                (unsigned)n->hidden, (unsigned)n->inputs);
        put_weights(f, "w_theta", n->w_theta, n->hidden);
        put_weights(f, "w_dist", n->w_dist, n->hidden);
        if (n->inputs == QNAV_NET_INPUTS_PREV) {
            put_weights(f, "w_prev", n->w_prev, n->hidden);
        }
        put_weights(f, "b_hidden", n->b_hidden, n->hidden);
        put_weights(f, "w_out", n->w_out, n->hidden);
        fprintf(f, "        .b_out = %d}}}},\n", (int)n->b_out);
        break;
    }
}

void qnav_fx_write_policies(const char *dir, const char *about, const qnav_fx_policy_t *p,
                            unsigned n)
{
    qnav_fx_out_t o;
    qnav_fx_open(&o, dir, "bench_policies.h");
    fprintf(o.f, "/*\n * %s\n */\n", about);
    fputs("#ifndef QNAV_BENCH_POLICIES_H\n#define QNAV_BENCH_POLICIES_H\n\n"
          "#include \"bench_fixtures.h\"\n\n", o.f);
    fprintf(o.f, "#define QNAV_BENCH_POLICY_COUNT %uu\n\n", n);
    fputs("static const qnav_bench_policy_t qnav_bench_policies[QNAV_BENCH_POLICY_COUNT] QNAV_FLASH = {\n",
          o.f);
    for (unsigned i = 0; i < n; ++i) {
        put_policy(o.f, &p[i]);
    }
    fputs("};\n\n#endif /* QNAV_BENCH_POLICIES_H */\n", o.f);
    qnav_fx_close(&o);
}

/* The ranges array of sector count n: the scans that use it are contiguous in ranges[]. */
static void put_ranges(FILE *f, uint16_t n, const qnav_fx_scan_t *s, unsigned count,
                       const int32_t *ranges)
{
    unsigned first = 0, total = 0;
    for (unsigned i = 0; i < count; ++i) {
        if (s[i].n == n) {
            first = total == 0 ? s[i].offset : first;
            total += s[i].n;
        }
    }
    fprintf(f, "static const qnav_mm_t qnav_bench_ranges_%u[%u] QNAV_FLASH = {", (unsigned)n, total);
    qnav_fx_put_values(f, &ranges[first], total);
    fputs("};\n\n", f);
}

void qnav_fx_write_scans(const char *dir, const char *about, const qnav_fx_scan_t *s,
                         unsigned n, const int32_t *ranges, unsigned max_range_mm)
{
    qnav_fx_out_t o;
    qnav_fx_open(&o, dir, "bench_scans.h");
    fprintf(o.f, "/*\n * %s\n */\n", about);
    fputs("#ifndef QNAV_BENCH_SCANS_H\n#define QNAV_BENCH_SCANS_H\n\n#include \"bench_fixtures.h\"\n\n",
          o.f);
    fprintf(o.f, "/* TekBot sonar maximum range (data/robots/tekbot.toml), mm */\n"
                 "#define QNAV_BENCH_MAX_RANGE_MM %uu\n", max_range_mm);
    fprintf(o.f, "#define QNAV_BENCH_SCAN_COUNT %uu\n\n", n);
    for (unsigned i = 0; i < n; ++i) {
        if (i == 0 || s[i].n != s[i - 1].n) {
            put_ranges(o.f, s[i].n, s, n, ranges);
        }
    }
    fputs("static const qnav_bench_scan_t qnav_bench_scans[QNAV_BENCH_SCAN_COUNT] QNAV_FLASH = {\n", o.f);
    for (unsigned i = 0; i < n; ++i) {
        unsigned j = 0;
        while (s[j].n != s[i].n) {
            ++j; /* the first scan of this sector count starts its array */
        }
        fprintf(o.f, "    {%u, %s, %u, %d, &qnav_bench_ranges_%u[%u]}, /* %s:%u%s%s */\n",
                (unsigned)s[i].n, type_macros[s[i].type], (unsigned)s[i].k, (int)s[i].bearing,
                (unsigned)s[i].n, (unsigned)(s[i].offset - s[j].offset), type_names[s[i].type],
                (unsigned)s[i].k, s[i].note[0] ? ", " : "", s[i].note);
    }
    fputs("};\n\n#endif /* QNAV_BENCH_SCANS_H */\n", o.f);
    qnav_fx_close(&o);
}

typedef struct {
    qnav_fx_pose_t *out;
    unsigned max, n;
    uint32_t every;
} pose_keeper_t;

static void keep_pose(void *user, const qnav_sim_sample_t *s)
{
    pose_keeper_t *k = (pose_keeper_t *)user;
    if (s->tick % k->every == 0u && k->n < k->max) {
        k->out[k->n].x_m = s->x_m;
        k->out[k->n].y_m = s->y_m;
        k->out[k->n].heading_rad = s->heading_rad;
        k->out[k->n++].tick = s->tick;
    }
}

unsigned qnav_fx_episode_poses(qnav_sim_t *sim, const qnav_ctrl_t *ctrl, uint64_t episode_seed,
                               uint32_t every, qnav_fx_pose_t *out, unsigned max,
                               qnav_sim_result_t *res, const char *what)
{
    pose_keeper_t k = {out, max, 0u, every};
    if (qnav_sim_run_episode(sim, ctrl, episode_seed, res, keep_pose, &k) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s: %s", what, qnav_sim_last_error(sim));
    }
    return k.n;
}

void qnav_fx_scan_at(qnav_sim_t *sim, double x_m, double y_m, double heading_rad,
                     qnav_sim_scan_t *scan, const char *what)
{
    if (qnav_sim_place(sim, x_m, y_m, heading_rad) != QNAV_SIM_OK ||
        qnav_sim_scan(sim, scan) != QNAV_SIM_OK) {
        qnav_fx_fail(2, "%s: %s", what, qnav_sim_last_error(sim));
    }
}
