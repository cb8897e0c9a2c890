/*
 * qnav-policy: the command-line tool around policy files (docs/policy-format.md).
 * check FILE validates a file, show FILE prints its weights as real numbers, new writes the
 * hand-tuned probabilistic policy or a seeded random network, and header turns a policy into
 * a C header for a firmware build (the policy itself, or its compiled quality table). Every
 * failure is one line on stderr; exit 0 success, 1 failed write, 2 bad usage or bad input
 * file (docs/cli.md).
 */
#define _POSIX_C_SOURCE 200809L

#include <getopt.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/ctrl.h"
#include "qnav/cli.h"
#include "qnav/policy_io.h"
#include "qnav/rng.h"

#define EXIT_FAILED 1    /* a write or the machine failed */
#define EXIT_BAD_INPUT 2 /* the policy file given is not a good one */
#define EXIT_USAGE 2

/* The usage text; the kinds it names are the policy kinds' own list. */
static void usage(FILE *f)
{
    char kinds[80];
    (void)qnav_policy_kind_list(kinds, sizeof kinds, "", "|", "|");
    fprintf(f,
            "usage: qnav-policy check FILE\n"
            "       qnav-policy show FILE\n"
            "       qnav-policy new --kind %s [--hidden H] [--inputs 2|3] [--seed S] OUT\n"
            "       qnav-policy header --mode %s|table --name NAME IN OUT.h\n"
            "Policy files are described in docs/policy-format.md.\n",
            kinds, kinds);
}

#if defined(__GNUC__)
#define QNAV_PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define QNAV_PRINTF_LIKE(f, a)
#endif

static int usage_error(const char *fmt, ...) QNAV_PRINTF_LIKE(1, 2);
static int usage_error(const char *fmt, ...)
{
    va_list ap;
    fputs("qnav-policy: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs(" (see qnav-policy --help)\n", stderr);
    return EXIT_USAGE;
}

/* Strict unsigned decimal: the whole string, no sign, no blanks, at most max. */
static int parse_u64(const char *s, uint64_t max, uint64_t *out)
{
    uint64_t v = 0;
    if (s == NULL || *s == '\0') {
        return -1;
    }
    for (; *s != '\0'; ++s) {
        unsigned d;
        if (*s < '0' || *s > '9') {
            return -1;
        }
        d = (unsigned)(*s - '0');
        if (v > (max - d) / 10u) {
            return -1;
        }
        v = v * 10u + d;
    }
    *out = v;
    return 0;
}

/* ---- check, show --------------------------------------------------------------------- */

static int cmd_check(int argc, char **argv)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN];
    if (argc != 2) {
        return usage_error("check: expected exactly one FILE, got %d arguments", argc - 1);
    }
    if (qnav_policy_read(argv[1], &p, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_BAD_INPUT;
    }
    return 0;
}

/* Q8.8 raw to its exact decimal (at most 8 fractional digits), trailing zeros cut. */
static void q88_text(int raw, char *out, size_t outlen)
{
    size_t n;
    (void)snprintf(out, outlen, "%.8f", (double)raw / 256.0);
    n = strlen(out);
    while (n > 0 && out[n - 1] == '0') {
        out[--n] = '\0';
    }
    if (n > 0 && out[n - 1] == '.') {
        out[n++] = '0';
        out[n] = '\0';
    }
}

static void show_prob(const qnav_prob_params_t *pp)
{
    char a[32], b[32];
    q88_text(pp->k_goal, a, sizeof a);
    q88_text(pp->k_safe, b, sizeof b);
    printf("kind: probabilistic\n");
    printf("k_goal: %s  (P_goal = exp(-k_goal * dtheta / 180 deg))\n", a);
    printf("k_safe: %s  (P_safe = 1 - exp(-k_safe * level / (levels - 1)))\n", b);
}

static void show_net(const qnav_net_t *n)
{
    char a[32], b[32], c[32], d[32];
    size_t i;
    printf("kind: network\nhidden: %u\ninputs: %u\n", (unsigned)n->hidden, (unsigned)n->inputs);
    if (n->inputs == QNAV_NET_INPUTS_PREV) {
        printf("%4s %14s %14s %14s %14s %14s\n", "unit", "w_theta", "w_dist", "w_prev",
               "b_hidden", "w_out");
    } else {
        printf("%4s %14s %14s %14s %14s\n", "unit", "w_theta", "w_dist", "b_hidden", "w_out");
    }
    for (i = 0; i < n->hidden; ++i) {
        q88_text(n->w_theta[i], a, sizeof a);
        q88_text(n->w_dist[i], b, sizeof b);
        q88_text(n->b_hidden[i], c, sizeof c);
        q88_text(n->w_out[i], d, sizeof d);
        if (n->inputs == QNAV_NET_INPUTS_PREV) {
            char e[32];
            q88_text(n->w_prev[i], e, sizeof e);
            printf("%4zu %14s %14s %14s %14s %14s\n", i, a, b, e, c, d);
        } else {
            printf("%4zu %14s %14s %14s %14s\n", i, a, b, c, d);
        }
    }
    q88_text(n->b_out, a, sizeof a);
    printf("b_out: %s\n", a);
}

static int cmd_show(int argc, char **argv)
{
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN];
    size_t i;
    if (argc != 2) {
        return usage_error("show: expected exactly one FILE, got %d arguments", argc - 1);
    }
    if (qnav_policy_read_meta(argv[1], &p, &meta, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_BAD_INPUT;
    }
    printf("file: %s\n", argv[1]);
    for (i = 0; i < meta.count; ++i) {
        printf("meta %s: %s\n", meta.entry[i].name, meta.entry[i].value);
    }
    switch ((qnav_policy_kind_t)p.kind) {
    case QNAV_POLICY_PROB:
        show_prob(&p.u.prob);
        return 0;
    case QNAV_POLICY_NET:
        show_net(&p.u.net);
        return 0;
    }
    fprintf(stderr, "%s: unknown policy kind %u\n", argv[1], (unsigned)p.kind);
    return EXIT_BAD_INPUT;
}

/* ---- new ----------------------------------------------------------------------------- */

/* Uniform raw Q8.8 weight in -512..512 (+-2.0) from the splitmix64 sequence of --seed
 * (qnav/rng.h), without modulo bias worth noting (2^64 / 1025 leaves a bias below 1e-16). */
static qnav_q8_8_t random_weight(uint64_t *state)
{
    return (qnav_q8_8_t)((int32_t)(qnav_splitmix64(state) % 1025u) - 512);
}

/* A seeded random network and the command that makes it again, as its "source"; 0, or
 * -1 with err. */
static int new_network(qnav_policy_t *p, qnav_policy_meta_t *meta, uint8_t hidden,
                       uint8_t inputs, uint64_t seed, char *err, size_t errlen)
{
    char src[128];
    uint64_t state = seed;
    uint16_t k;
    qnav_policy_net_zero_inputs(p, hidden, inputs);
    for (k = 0; k < qnav_net_weight_count(&p->u.net); ++k) {
        *qnav_net_weight(&p->u.net, k) = random_weight(&state);
    }
    if (inputs == QNAV_NET_INPUTS_PAPER) {
        (void)snprintf(src, sizeof src, "qnav-policy new --kind network --hidden %u --seed %llu",
                       (unsigned)hidden, (unsigned long long)seed);
    } else {
        (void)snprintf(src, sizeof src,
                       "qnav-policy new --kind network --hidden %u --inputs 3 --seed %llu",
                       (unsigned)hidden, (unsigned long long)seed);
    }
    return qnav_policy_meta_set(meta, "source", src, err, errlen);
}

/* What `new` was asked for; kind NULL until --kind is given. */
typedef struct {
    const char *kind;
    uint64_t hidden;
    uint64_t inputs;
    uint64_t seed;
    int have_network_option; /* --hidden, --inputs or --seed */
} new_options_t;

/* One option of `new` into o; 0, or the usage error's exit code. */
static int new_option(int opt, new_options_t *o, char **argv)
{
    switch (opt) {
    case 'k':
        o->kind = optarg;
        return 0;
    case 'i':
        if (parse_u64(optarg, 255, &o->inputs) != 0 ||
            (o->inputs != QNAV_NET_INPUTS_PAPER && o->inputs != QNAV_NET_INPUTS_PREV)) {
            return usage_error("new: --inputs '%s' must be 2 or 3", optarg);
        }
        o->have_network_option = 1;
        return 0;
    case 'H':
        if (parse_u64(optarg, 255, &o->hidden) != 0 || o->hidden < 1 ||
            o->hidden > QNAV_MAX_HIDDEN) {
            return usage_error("new: --hidden '%s' must be an integer in 1..%d", optarg,
                               QNAV_MAX_HIDDEN);
        }
        o->have_network_option = 1;
        return 0;
    case 's':
        if (parse_u64(optarg, UINT64_MAX, &o->seed) != 0) {
            return usage_error("new: --seed '%s' must be an unsigned integer", optarg);
        }
        o->have_network_option = 1;
        return 0;
    case ':':
        return usage_error("new: option '%s' needs a value", argv[optind - 1]);
    default:
        return usage_error("new: unknown option '%s'", argv[optind - 1]);
    }
}

/* The options of `new` up to its OUT file (argv[optind] on success); 0 or an exit code. */
static int new_options(int argc, char **argv, new_options_t *o)
{
    static const struct option opts[] = {{"kind", required_argument, NULL, 'k'},
                                         {"hidden", required_argument, NULL, 'H'},
                                         {"seed", required_argument, NULL, 's'},
                                         {"inputs", required_argument, NULL, 'i'},
                                         {NULL, 0, NULL, 0}};
    int opt;
    o->kind = NULL;
    o->hidden = QNAV_DEFAULT_HIDDEN;
    o->inputs = QNAV_NET_INPUTS_PAPER;
    o->seed = 1;
    o->have_network_option = 0;
    opterr = 0;
    optind = 1;
    while ((opt = getopt_long(argc, argv, ":", opts, NULL)) != -1) {
        const int rc = new_option(opt, o, argv);
        if (rc != 0) {
            return rc;
        }
    }
    if (o->kind == NULL) {
        char kinds[80];
        return usage_error("new: --kind %s is required",
                           qnav_policy_kind_list(kinds, sizeof kinds, "", "|", "|"));
    }
    if (optind != argc - 1) {
        return usage_error("new: expected exactly one OUT file after the options");
    }
    return 0;
}

static int cmd_new(int argc, char **argv)
{
    new_options_t o;
    int made = -1;
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN];
    const int rc = new_options(argc, argv, &o);
    if (rc != 0) {
        return rc;
    }
    if (qnav_policy_kind_from_name(o.kind, strlen(o.kind), &p.kind) != 0) {
        char kinds[80];
        return usage_error("new: --kind '%s' must be %s", o.kind,
                           qnav_policy_kind_list(kinds, sizeof kinds, "'", ", ", " or "));
    }
    qnav_policy_meta_clear(&meta);
    switch ((qnav_policy_kind_t)p.kind) {
    case QNAV_POLICY_PROB:
        if (o.have_network_option) {
            return usage_error("new: --hidden, --inputs and --seed apply to --kind network only");
        }
        qnav_policy_prob_default(&p);
        made = qnav_policy_meta_set(&meta, "source", "qnav-policy new --kind probabilistic",
                                    err, sizeof err);
        break;
    case QNAV_POLICY_NET:
        made = new_network(&p, &meta, (uint8_t)o.hidden, (uint8_t)o.inputs, o.seed, err,
                           sizeof err);
        break;
    }
    if (made != 0 || qnav_policy_write_meta(argv[optind], &p, &meta, NULL, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_FAILED;
    }
    return 0;
}

/* ---- header -------------------------------------------------------------------------- */

static int is_c_identifier(const char *s)
{
    static const char *const keywords[] = {
        "auto", "break", "case", "char", "const", "continue", "default", "do", "double",
        "else", "enum", "extern", "float", "for", "goto", "if", "inline", "int", "long",
        "register", "restrict", "return", "short", "signed", "sizeof", "static", "struct",
        "switch", "typedef", "union", "unsigned", "void", "volatile", "while", "_Bool",
        "_Complex", "_Imaginary", "bool", "true", "false", "class", "new", "delete",
        "template", "this", "operator", "namespace", "private", "public", "protected"};
    size_t i;
    size_t n = strlen(s);
    if (n < 1 || n > 63 || s[0] == '_' || (s[0] >= '0' && s[0] <= '9')) {
        return 0;
    }
    for (i = 0; i < n; ++i) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '_')) {
            return 0;
        }
    }
    for (i = 0; i < sizeof keywords / sizeof keywords[0]; ++i) {
        if (strcmp(s, keywords[i]) == 0) {
            return 0;
        }
    }
    return 1;
}

/* A growing text buffer for the header. */
typedef struct {
    char *p;
    size_t len;
    size_t cap;
    int failed;
} text_t;

static void put(text_t *t, const char *fmt, ...) QNAV_PRINTF_LIKE(2, 3);
static void put(text_t *t, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (t->failed) {
        return;
    }
    for (;;) {
        size_t room = t->cap - t->len;
        va_start(ap, fmt);
        n = vsnprintf(t->p + t->len, room, fmt, ap);
        va_end(ap);
        if (n < 0) {
            t->failed = 1;
            return;
        }
        if ((size_t)n < room) {
            t->len += (size_t)n;
            return;
        }
        {
            size_t cap = t->cap * 2u + (size_t)n + 1u;
            char *q = (char *)realloc(t->p, cap);
            if (q == NULL) {
                t->failed = 1;
                return;
            }
            t->p = q;
            t->cap = cap;
        }
    }
}

/* Text for a C comment: printable ASCII only, and no comment opener or terminator. */
static void put_comment_safe(text_t *t, const char *s)
{
    for (; *s != '\0'; ++s) {
        unsigned char c = (unsigned char)*s;
        char prev = t->len > 0 && t->p != NULL ? t->p[t->len - 1] : '\0';
        if ((c == '/' && prev == '*') || (c == '*' && prev == '/')) {
            put(t, " ");
        }
        if (c >= 0x20 && c < 0x7f) {
            put(t, "%c", (int)c);
        } else {
            put(t, "?");
        }
    }
}

static void put_array(text_t *t, const char *field, const qnav_q8_8_t *v, unsigned n,
                      int last)
{
    unsigned i;
    put(t, "            .%s = {", field);
    for (i = 0; i < n; ++i) {
        put(t, "%s%d", i == 0 ? "" : ", ", (int)v[i]);
    }
    put(t, "}%s\n", last ? "" : ",");
}

static int header_body(int argc, char **argv, const char *cmd);

/* The policy itself as a qnav_policy_t initializer named `name`; -1 for an unknown kind. */
static int put_policy(text_t *t, const qnav_policy_t *p, const char *name)
{
    const qnav_net_t *n = &p->u.net;
    put(t, "#include \"qnav/policy.h\"\n\n");
    switch ((qnav_policy_kind_t)p->kind) {
    case QNAV_POLICY_NET:
        put(t, "#if QNAV_MAX_HIDDEN < %u\n#error \"%s needs QNAV_MAX_HIDDEN >= %u\"\n#endif\n\n",
            (unsigned)n->hidden, name, (unsigned)n->hidden);
        put(t, "/* Network policy, %u hidden units, weights raw Q8.8 (value * 256). */\n",
            (unsigned)n->hidden);
        put(t, "static const qnav_policy_t %s = {\n", name);
        put(t, "    .kind = (uint8_t)QNAV_POLICY_NET,\n    .u = {\n        .net = {\n");
        put(t, "            .hidden = %u,\n", (unsigned)n->hidden);
        put(t, "            .inputs = %u,\n", (unsigned)n->inputs);
        put_array(t, "w_theta", n->w_theta, n->hidden, 0);
        put_array(t, "w_dist", n->w_dist, n->hidden, 0);
        put_array(t, "w_prev", n->w_prev, n->hidden, 0);
        put_array(t, "b_hidden", n->b_hidden, n->hidden, 0);
        put_array(t, "w_out", n->w_out, n->hidden, 0);
        put(t, "            .b_out = %d\n        }\n    }\n};\n", (int)n->b_out);
        return 0;
    case QNAV_POLICY_PROB:
        put(t, "/* Probabilistic navigation policy, parameters raw Q8.8 (value * 256). */\n");
        put(t, "static const qnav_policy_t %s = {\n", name);
        put(t, "    .kind = (uint8_t)QNAV_POLICY_PROB,\n    .u = {\n        .prob = {\n");
        put(t, "            .k_goal = %d,\n            .k_safe = %d\n        }\n    }\n};\n",
            (int)p->u.prob.k_goal, (int)p->u.prob.k_safe);
        return 0;
    }
    return -1;
}

/* Write the header for "header" (argv from the subcommand on); full_argv is the whole
 * command line, recorded in the header as typed (before getopt_long permutes argv). */
static int cmd_header(int argc, char **argv, int full_argc, char *const *full_argv)
{
    text_t c = {NULL, 0, 0, 0};
    int i;
    int rc;
    c.cap = 256;
    c.p = (char *)malloc(c.cap);
    if (c.p == NULL) {
        fputs("qnav-policy: out of memory\n", stderr);
        return EXIT_FAILED;
    }
    c.p[0] = '\0';
    for (i = 0; i < full_argc; ++i) {
        const char *a = full_argv[i];
        /* the program by its name, not its path: the same header on every machine */
        if (i == 0 && strrchr(a, '/') != NULL) {
            a = strrchr(a, '/') + 1;
        }
        put(&c, " ");
        put_comment_safe(&c, a);
    }
    if (c.failed) {
        free(c.p);
        fputs("qnav-policy: out of memory\n", stderr);
        return EXIT_FAILED;
    }
    rc = header_body(argc, argv, c.p);
    free(c.p);
    return rc;
}

/* 1 when --mode names a policy kind (the kind's own mode; "table" takes any). */
static int mode_is_kind(const char *mode)
{
    uint8_t kind;
    return qnav_policy_kind_from_name(mode, strlen(mode), &kind) == QNAV_POLICY_IO_OK;
}

/* header's options and operands: --mode, --name, IN, OUT.h. Returns 0, or the exit code
 * after one line on stderr. */
static int header_args(int argc, char **argv, const char **mode, const char **name,
                       const char **in, const char **out)
{
    static const struct option opts[] = {{"mode", required_argument, NULL, 'm'},
                                         {"name", required_argument, NULL, 'n'},
                                         {NULL, 0, NULL, 0}};
    int opt;
    opterr = 0;
    optind = 1;
    while ((opt = getopt_long(argc, argv, ":", opts, NULL)) != -1) {
        switch (opt) {
        case 'm':
            *mode = optarg;
            break;
        case 'n':
            *name = optarg;
            break;
        case ':':
            return usage_error("header: option '%s' needs a value", argv[optind - 1]);
        default:
            return usage_error("header: unknown option '%s'", argv[optind - 1]);
        }
    }
    if (*mode == NULL || (!mode_is_kind(*mode) && strcmp(*mode, "table") != 0)) {
        char kinds[80];
        return usage_error("header: --mode must be %s or table",
                           qnav_policy_kind_list(kinds, sizeof kinds, "", ", ", ", "));
    }
    if (*name == NULL || !is_c_identifier(*name)) {
        return usage_error("header: --name must be a C identifier (letters, digits, '_'; "
                           "not starting with a digit or '_'; not a keyword; <= 63 chars)");
    }
    if (optind != argc - 2) {
        return usage_error("header: expected IN and OUT.h after the options");
    }
    *in = argv[optind];
    *out = argv[optind + 1];
    if (strcmp(*in, *out) == 0) {
        return usage_error("header: OUT.h must not be the policy file IN");
    }
    return 0;
}

/* Policy p (read from in) compiled into a quality table, as C text. Returns 0, or the exit
 * code after one line on stderr. */
static int put_table(text_t *t, const qnav_policy_t *p, const char *name, const char *in)
{
    qnav_ctrl_t ctrl;
    qnav_ctrl_config_t cfg;
    qnav_qkey_t *table = (qnav_qkey_t *)malloc(sizeof(qnav_qkey_t) * QNAV_QTABLE_ENTRIES);
    unsigned level;
    unsigned d;
    qnav_status_t st = QNAV_E_NULL;
    qnav_ctrl_config_default(&cfg);
    if (table != NULL) {
        st = qnav_ctrl_init(&ctrl, &cfg, p);
    }
    if (st == QNAV_OK) {
        st = qnav_ctrl_build_table(&ctrl, table);
    }
    if (st != QNAV_OK) {
        fprintf(stderr, "%s: cannot build the quality table: %s%s\n", in, qnav_status_str(st),
                st == QNAV_E_NO_TABLE ? " (use --mode network: the board then evaluates "
                                        "every path, docs/performance.md)"
                                      : "");
        free(table);
        return EXIT_FAILED;
    }
    put(t, "#include \"qnav/ctrl.h\"\n#include \"qnav/flash.h\"\n\n");
    put(t, "#if QNAV_DIST_LEVELS != %d || QNAV_DTHETA_MAX != %d\n", QNAV_DIST_LEVELS,
        QNAV_DTHETA_MAX);
    put(t, "#error \"%s was generated for QNAV_DIST_LEVELS %d: regenerate it with "
           "qnav-policy header for this build\"\n#endif\n\n",
        name, QNAV_DIST_LEVELS);
    put(t, "/* Path rank keys (qnav_qkey_t of rank %s_RANK) by distance level (rows,\n"
           " * 0..%d) and dtheta in degrees (columns, 0..%d); use with\n"
           " * qnav_ctrl_init_table(&ctrl, &cfg, %s, %s_RANK). */\n",
        name, QNAV_DIST_LEVELS - 1, QNAV_DTHETA_MAX, name, name);
    put(t, "#define %s_RANK %s\n", name,
        qnav_ctrl_rank(&ctrl) == QNAV_RANK_PREACT ? "QNAV_RANK_PREACT" : "QNAV_RANK_QUALITY");
    put(t, "static QNAV_FLASH const qnav_qkey_t %s[QNAV_QTABLE_ENTRIES] = {\n", name);
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        put(t, "    /* level %u */\n", level);
        for (d = 0; d <= QNAV_DTHETA_MAX; ++d) {
            int v = table[level * (QNAV_DTHETA_MAX + 1u) + d];
            put(t, "%s%d,%s", d % 12u == 0 ? "    " : " ", v,
                (d % 12u == 11u || d == QNAV_DTHETA_MAX) ? "\n" : "");
        }
    }
    put(t, "};\n");
    free(table);
    return 0;
}

static int header_body(int argc, char **argv, const char *cmd)
{
    const char *mode = NULL;
    const char *name = NULL;
    const char *in = NULL;
    const char *out = NULL;
    int i;
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN];
    text_t t = {NULL, 0, 0, 0};
    char guard[80];
    int rc = header_args(argc, argv, &mode, &name, &in, &out);
    if (rc != 0) {
        return rc;
    }
    if (qnav_policy_read(in, &p, err, sizeof err) != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_BAD_INPUT;
    }
    /* --mode network|probabilistic names a kind (table takes either) */
    if (strcmp(mode, "table") != 0 && strcmp(mode, qnav_policy_kind_name(p.kind)) != 0) {
        fprintf(stderr, "%s: kind is %s but --mode %s was asked for\n", in,
                qnav_policy_kind_name(p.kind), mode);
        return EXIT_BAD_INPUT;
    }
    for (i = 0; name[i] != '\0'; ++i) {
        char c = name[i];
        guard[i] = (c >= 'a' && c <= 'z') ? (char)(c - 'a' + 'A') : c;
    }
    guard[i] = '\0';

    t.cap = 4096;
    t.p = (char *)malloc(t.cap);
    if (t.p == NULL) {
        fprintf(stderr, "%s: out of memory\n", out);
        return EXIT_FAILED;
    }
    put(&t, "/*\n * %s: a qnav policy compiled for a firmware build (%s mode).\n", name, mode);
    put(&t, " * Generated by qnav-policy; do not edit: regenerate from the source file.\n");
    put(&t, " * Source: ");
    put_comment_safe(&t, in);
    put(&t, "\n * Command:%s\n */\n#ifndef QNAV_GENERATED_%s_H\n#define QNAV_GENERATED_%s_H\n\n", cmd, guard, guard);
    if (strcmp(mode, "table") == 0) {
        rc = put_table(&t, &p, name, in);
    } else if (put_policy(&t, &p, name) != 0) {
        fprintf(stderr, "%s: unknown policy kind %u\n", in, (unsigned)p.kind);
        rc = EXIT_BAD_INPUT;
    }
    if (rc != 0) {
        free(t.p);
        return rc;
    }
    put(&t, "\n#endif /* QNAV_GENERATED_%s_H */\n", guard);
    if (t.failed) {
        free(t.p);
        fprintf(stderr, "%s: out of memory\n", out);
        return EXIT_FAILED;
    }
    rc = qnav_policy_io_write_atomic(out, t.p, t.len, err, sizeof err);
    free(t.p);
    if (rc != 0) {
        fprintf(stderr, "%s\n", err);
        return EXIT_FAILED;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *cmd;
    if (argc < 2) {
        usage(stderr);
        return EXIT_USAGE;
    }
    cmd = argv[1];
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        usage(stdout);
        return 0;
    }
    if (strcmp(cmd, "--version") == 0) {
        fputs(QNAV_CLI_VERSION_LINE("qnav-policy"), stdout);
        return 0;
    }
    if (cmd[0] == '-') {
        return usage_error("%s: unknown option", cmd);
    }
    if (strcmp(cmd, "check") == 0) {
        return cmd_check(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "show") == 0) {
        return cmd_show(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "new") == 0) {
        return cmd_new(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "header") == 0) {
        return cmd_header(argc - 1, argv + 1, argc, argv);
    }
    return usage_error("%s: unknown subcommand (known: check, show, new, header)", cmd);
}
