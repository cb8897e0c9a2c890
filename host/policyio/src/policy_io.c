/*
 * Policy files on the host: the strict reader, the renderer and the atomic writer of the
 * text format in docs/policy-format.md. The reader works on a length-delimited buffer
 * (never relying on a terminating NUL), copies each line into a bounded local buffer after
 * checking its length, and refuses anything malformed with one "FILE:LINE: problem" line.
 * A parsed policy is finally run through qnav_policy_validate() and qnav_ctrl_init(), so
 * the reader accepts exactly what the controller accepts. Version 1 files (two-input
 * networks, the probabilistic policy) are read and written unchanged; version 2 adds the
 * network's 'inputs' line for the previous-decision input.
 */
#define _POSIX_C_SOURCE 200809L

#include "qnav/policy_io.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "qnav/ctrl.h"

#define MAGIC "qnav-policy"
#define K_RAW_MAX ((long)QNAV_PROB_PARAM_MAX_RAW) /* 64.0 in Q8.8 */
#define MAX_TOKENS 8           /* the longest valid line has 6 tokens */

/* ---- small helpers ------------------------------------------------------------------- */

#if defined(__GNUC__)
#define QNAV_PRINTF_LIKE(f, a) __attribute__((format(printf, f, a)))
#else
#define QNAV_PRINTF_LIKE(f, a)
#endif

static void set_err(char *err, size_t errlen, const char *fmt, ...) QNAV_PRINTF_LIKE(3, 4);

static void set_err(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    if (err == NULL || errlen == 0) {
        return;
    }
    va_start(ap, fmt);
    (void)vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* Copy s into out (outlen bytes) for a one-line message: printable ASCII kept, anything
 * else as \xNN, cut with "..." after max bytes of input. */
static void quote_bytes(const char *s, size_t n, size_t max, char *out, size_t outlen)
{
    size_t i;
    size_t o = 0;
    if (outlen == 0) {
        return;
    }
    for (i = 0; i < n && i < max; ++i) {
        unsigned char c = (unsigned char)s[i];
        char tmp[5];
        size_t tl;
        if (c >= 0x20 && c < 0x7f) {
            tmp[0] = (char)c;
            tmp[1] = '\0';
        } else {
            (void)snprintf(tmp, sizeof tmp, "\\x%02X", (unsigned)c);
        }
        tl = strlen(tmp);
        if (o + tl + 1 > outlen) {
            break;
        }
        memcpy(out + o, tmp, tl);
        o += tl;
    }
    if (n > max && o + 4 <= outlen) {
        memcpy(out + o, "...", 3);
        o += 3;
    }
    out[o] = '\0';
}

const char *qnav_policy_io_status_str(qnav_policy_io_status_t status)
{
    switch (status) {
    case QNAV_POLICY_IO_OK:
        return "ok";
    case QNAV_POLICY_IO_E_NULL:
        return "null argument";
    case QNAV_POLICY_IO_E_IO:
        return "cannot open, read or write the file";
    case QNAV_POLICY_IO_E_PARSE:
        return "not a good policy file";
    case QNAV_POLICY_IO_E_INVALID:
        return "invalid policy, metadata or comment";
    case QNAV_POLICY_IO_E_NAME:
        return "no policy kind of that name";
    case QNAV_POLICY_IO_E_NOMEM:
        return "out of memory";
    }
    return "unknown policyio status";
}

const char *qnav_policy_kind_name(uint8_t kind)
{
    switch ((qnav_policy_kind_t)kind) {
    case QNAV_POLICY_PROB:
        return "probabilistic";
    case QNAV_POLICY_NET:
        return "network";
    }
    return NULL;
}

/* Every kind, in the order names are listed. */
static const qnav_policy_kind_t kinds[] = {QNAV_POLICY_PROB, QNAV_POLICY_NET};
#define N_KINDS (sizeof kinds / sizeof kinds[0])

qnav_policy_io_status_t qnav_policy_kind_from_name(const char *name, size_t len, uint8_t *kind)
{
    size_t i;
    for (i = 0; i < N_KINDS; ++i) {
        const char *n = qnav_policy_kind_name((uint8_t)kinds[i]);
        if (strlen(n) == len && memcmp(n, name, len) == 0) {
            *kind = (uint8_t)kinds[i];
            return QNAV_POLICY_IO_OK;
        }
    }
    return QNAV_POLICY_IO_E_NAME;
}

const char *qnav_policy_kind_list(char *buf, size_t len, const char *quote, const char *sep,
                                  const char *last)
{
    size_t used = 0;
    size_t i;
    if (buf == NULL || len == 0) {
        return buf;
    }
    buf[0] = '\0';
    for (i = 0; i < N_KINDS && used < len; ++i) {
        const char *between = i == 0 ? "" : (i + 1 == N_KINDS ? last : sep);
        int n = snprintf(buf + used, len - used, "%s%s%s%s", between, quote,
                         qnav_policy_kind_name((uint8_t)kinds[i]), quote);
        if (n < 0) {
            break;
        }
        used += (size_t)n;
    }
    return buf;
}

int qnav_policy_file_version(const qnav_policy_t *policy)
{
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
        return 1;
    case QNAV_POLICY_NET:
        return policy->u.net.inputs == QNAV_NET_INPUTS_PAPER ? 1 : 2;
    }
    return QNAV_POLICY_FORMAT_VERSION;
}

/* ---- checks on a policy in memory ---------------------------------------------------- */

qnav_policy_io_status_t qnav_policy_check(const qnav_policy_t *policy, char *err, size_t errlen)
{
    qnav_policy_status_t st = qnav_policy_validate(policy);
    switch (st) {
    case QNAV_POLICY_OK:
        return QNAV_POLICY_IO_OK;
    case QNAV_POLICY_E_KIND:
        set_err(err, errlen, "unknown policy kind %u", (unsigned)policy->kind);
        return QNAV_POLICY_IO_E_INVALID;
    case QNAV_POLICY_E_HIDDEN:
        set_err(err, errlen, "hidden %u outside 1..%d", (unsigned)policy->u.net.hidden,
                QNAV_MAX_HIDDEN);
        return QNAV_POLICY_IO_E_INVALID;
    case QNAV_POLICY_E_INPUTS:
        set_err(err, errlen, "inputs %u: a network has 2 or 3 inputs",
                (unsigned)policy->u.net.inputs);
        return QNAV_POLICY_IO_E_INVALID;
    case QNAV_POLICY_E_PROB_PARAM:
        if (policy->u.prob.k_goal <= 0 || policy->u.prob.k_goal > K_RAW_MAX) {
            set_err(err, errlen, "k_goal %d outside (0, 64]: raw Q8.8 must be 1..%ld",
                    (int)policy->u.prob.k_goal, K_RAW_MAX);
        } else {
            set_err(err, errlen, "k_safe %d outside (0, 64]: raw Q8.8 must be 1..%ld",
                    (int)policy->u.prob.k_safe, K_RAW_MAX);
        }
        return QNAV_POLICY_IO_E_INVALID;
    case QNAV_POLICY_E_NULL:
    case QNAV_POLICY_E_KIND_DISABLED:
        break;
    }
    set_err(err, errlen, "%s", qnav_policy_status_str(st));
    return QNAV_POLICY_IO_E_INVALID;
}

int qnav_policy_equal(const qnav_policy_t *a, const qnav_policy_t *b)
{
    uint16_t k;
    uint16_t n;
    qnav_net_t na;
    qnav_net_t nb;
    if (a == NULL || b == NULL || a->kind != b->kind) {
        return 0;
    }
    switch ((qnav_policy_kind_t)a->kind) {
    case QNAV_POLICY_PROB:
        return a->u.prob.k_goal == b->u.prob.k_goal && a->u.prob.k_safe == b->u.prob.k_safe;
    case QNAV_POLICY_NET:
        na = a->u.net;
        nb = b->u.net;
        n = qnav_net_weight_count(&na);
        if (n == 0 || na.hidden != nb.hidden || na.inputs != nb.inputs) {
            return 0;
        }
        for (k = 0; k < n; ++k) {
            if (*qnav_net_weight(&na, k) != *qnav_net_weight(&nb, k)) {
                return 0;
            }
        }
        return 1;
    }
    return 0;
}

/* ---- metadata ------------------------------------------------------------------------ */

static int meta_name_ok(const char *s, size_t n)
{
    size_t i;
    if (n < 1 || n > QNAV_POLICY_META_NAME_MAX) {
        return 0;
    }
    for (i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '_' || c == '.' || c == '-')) {
            return 0;
        }
    }
    return 1;
}

/* Checks a value as the reader would deliver it: 1..200 bytes, no '#', no control
 * characters, no blanks at either end. Returns NULL or the reason. */
static const char *meta_value_problem(const char *s, size_t n)
{
    size_t i;
    if (n < 1) {
        return "is empty";
    }
    if (n > QNAV_POLICY_META_VALUE_MAX) {
        return "is longer than 200 bytes";
    }
    if (s[0] == ' ' || s[0] == '\t' || s[n - 1] == ' ' || s[n - 1] == '\t') {
        return "starts or ends with a blank";
    }
    for (i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (c == '#') {
            return "contains '#' (it would start a comment)";
        }
        if ((c < 0x20 && c != '\t') || c == 0x7f) {
            return "contains a control character";
        }
    }
    return NULL;
}

void qnav_policy_meta_clear(qnav_policy_meta_t *meta)
{
    if (meta != NULL) {
        memset(meta, 0, sizeof *meta);
    }
}

const char *qnav_policy_meta_get(const qnav_policy_meta_t *meta, const char *name)
{
    size_t i;
    if (meta == NULL || name == NULL) {
        return NULL;
    }
    for (i = 0; i < meta->count && i < QNAV_POLICY_META_MAX; ++i) {
        if (strcmp(meta->entry[i].name, name) == 0) {
            return meta->entry[i].value;
        }
    }
    return NULL;
}

qnav_policy_io_status_t qnav_policy_meta_set(qnav_policy_meta_t *meta, const char *name, const char *value,
                         char *err, size_t errlen)
{
    size_t i;
    size_t nl;
    size_t vl;
    const char *why;
    char q[80];
    if (meta == NULL || name == NULL || value == NULL) {
        set_err(err, errlen, "meta: null argument");
        return QNAV_POLICY_IO_E_NULL;
    }
    nl = strlen(name);
    vl = strlen(value);
    if (!meta_name_ok(name, nl)) {
        quote_bytes(name, nl, 40, q, sizeof q);
        set_err(err, errlen, "meta name '%s' must be 1..31 of A-Z a-z 0-9 _ . -", q);
        return QNAV_POLICY_IO_E_INVALID;
    }
    why = meta_value_problem(value, vl);
    if (why != NULL) {
        set_err(err, errlen, "meta %s: value %s", name, why);
        return QNAV_POLICY_IO_E_INVALID;
    }
    for (i = 0; i < meta->count && i < QNAV_POLICY_META_MAX; ++i) {
        if (strcmp(meta->entry[i].name, name) == 0) {
            memcpy(meta->entry[i].value, value, vl + 1);
            return QNAV_POLICY_IO_OK;
        }
    }
    if (meta->count >= QNAV_POLICY_META_MAX) {
        set_err(err, errlen, "meta %s: more than %d metadata entries", name,
                QNAV_POLICY_META_MAX);
        return QNAV_POLICY_IO_E_INVALID;
    }
    memcpy(meta->entry[meta->count].name, name, nl + 1);
    memcpy(meta->entry[meta->count].value, value, vl + 1);
    meta->count++;
    return QNAV_POLICY_IO_OK;
}

/* ---- the reader ---------------------------------------------------------------------- */

typedef struct {
    const char *p;
    size_t n;
} token_t;

typedef struct {
    const char *name; /* file name for messages */
    char *err;
    size_t errlen;
    unsigned long line; /* current line, 1-based */
    qnav_policy_t pol;
    qnav_policy_meta_t meta;
    unsigned long kind_line;
    unsigned long qformat_line;
    unsigned long hidden_line;
    unsigned long inputs_line;
    long version;       /* format version of line 1 */
    unsigned long b_out_line;
    unsigned long k_goal_line;
    unsigned long k_safe_line;
    unsigned long end_line;
    unsigned long meta_line[QNAV_POLICY_META_MAX];
    unsigned long unit_line[QNAV_MAX_HIDDEN];
    unsigned next_unit;
} parser_t;

static int fail(parser_t *ps, const char *fmt, ...) QNAV_PRINTF_LIKE(2, 3);
static int fail(parser_t *ps, const char *fmt, ...)
{
    char msg[QNAV_POLICY_IO_ERRLEN];
    char nm[200];
    va_list ap;
    va_start(ap, fmt);
    (void)vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    quote_bytes(ps->name, strlen(ps->name), 160, nm, sizeof nm);
    set_err(ps->err, ps->errlen, "%s:%lu: %s", nm, ps->line, msg);
    return -1;
}

static int tok_is(const token_t *t, const char *s)
{
    size_t n = strlen(s);
    return t->n == n && memcmp(t->p, s, n) == 0;
}

/* Decimal integer with optional sign. 0 ok, -1 not an integer. Magnitudes past 10^9
 * saturate there (out of every range this format checks), so long never overflows. */
static int parse_int(const token_t *t, long *out)
{
    size_t i = 0;
    long v = 0;
    int neg = 0;
    if (t->n == 0) {
        return -1;
    }
    if (t->p[0] == '-' || t->p[0] == '+') {
        neg = t->p[0] == '-';
        i = 1;
    }
    if (i >= t->n) {
        return -1;
    }
    for (; i < t->n; ++i) {
        char c = t->p[i];
        if (c < '0' || c > '9') {
            return -1;
        }
        if (v > 100000000L) {
            v = 1000000000L; /* saturate: any such value is out of every range here */
        } else {
            v = v * 10 + (c - '0');
        }
    }
    *out = neg ? -v : v;
    return 0;
}

/* A Q8.8 value; what names it in messages (e.g. "unit 3: " or "b_out "). */
static int parse_q88(parser_t *ps, const token_t *t, const char *what, qnav_q8_8_t *out)
{
    long v = 0;
    char q[80];
    quote_bytes(t->p, t->n, 40, q, sizeof q);
    if (parse_int(t, &v) != 0) {
        return fail(ps, "%s'%s' is not an integer (weights are raw Q8.8: value * 256)", what,
                    q);
    }
    if (v < -32768L || v > 32767L) {
        return fail(ps, "%svalue %s outside the Q8.8 range -32768..32767", what, q);
    }
    *out = (qnav_q8_8_t)v;
    return 0;
}

static int once(parser_t *ps, unsigned long *seen, const char *key)
{
    if (*seen != 0) {
        return fail(ps, "duplicate '%s' (first on line %lu)", key, *seen);
    }
    *seen = ps->line;
    return 0;
}

static int want_values(parser_t *ps, size_t ntok, size_t want, const char *key)
{
    if (ntok - 1 != want) {
        return fail(ps, "'%s' takes %zu value%s, found %zu", key, want, want == 1 ? "" : "s",
                    ntok - 1);
    }
    return 0;
}

static int line_magic(parser_t *ps, const token_t *tok, size_t ntok)
{
    long v = 0;
    char q[80];
    if (ntok == 0 || !tok_is(&tok[0], MAGIC)) {
        return fail(ps, "not a qnav policy file: line 1 must be 'qnav-policy %d' (or %d)",
                    QNAV_POLICY_FORMAT_VERSION_MIN, QNAV_POLICY_FORMAT_VERSION);
    }
    if (ntok != 2) {
        return fail(ps, "line 1 must be 'qnav-policy %d' (two tokens, found %zu)",
                    QNAV_POLICY_FORMAT_VERSION_MIN, ntok);
    }
    quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
    if (parse_int(&tok[1], &v) != 0) {
        return fail(ps, "format version '%s' is not an integer", q);
    }
    if (v < QNAV_POLICY_FORMAT_VERSION_MIN || v > QNAV_POLICY_FORMAT_VERSION) {
        return fail(ps, "unsupported format version %s (this reader reads versions %d..%d)", q,
                    QNAV_POLICY_FORMAT_VERSION_MIN, QNAV_POLICY_FORMAT_VERSION);
    }
    ps->version = v;
    return 0;
}

static int line_unit(parser_t *ps, const token_t *tok, size_t ntok)
{
    long j = 0;
    unsigned h = ps->pol.u.net.hidden;
    size_t nw = (size_t)ps->pol.u.net.inputs + 2u;
    char q[80];
    char what[32];
    size_t k;
    if (ps->hidden_line == 0) {
        return fail(ps, "'unit' before 'hidden'");
    }
    if (ps->version >= 2 && ps->inputs_line == 0) {
        return fail(ps, "'unit' before 'inputs' (version 2 names a network's inputs)");
    }
    if (ntok < 2) {
        return fail(ps, "'unit' needs an index and %zu weights", nw);
    }
    quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
    if (parse_int(&tok[1], &j) != 0) {
        return fail(ps, "unit index '%s' is not an integer", q);
    }
    if (j < 0 || j >= (long)h) {
        return fail(ps, "unit %s outside 0..%u (hidden %u)", q, h - 1u, h);
    }
    if ((unsigned)j < ps->next_unit) {
        return fail(ps, "duplicate unit %ld (first on line %lu)", j, ps->unit_line[j]);
    }
    if ((unsigned)j > ps->next_unit) {
        return fail(ps, "unit %ld out of order: expected unit %u", j, ps->next_unit);
    }
    if (ntok != 2 + nw) {
        return fail(ps, "unit %ld: expected %zu weights (%s), found %zu", j, nw,
                    nw == 4u ? "w_theta w_dist b_hidden w_out"
                             : "w_theta w_dist w_prev b_hidden w_out",
                    ntok - 2);
    }
    (void)snprintf(what, sizeof what, "unit %ld: ", j);
    for (k = 0; k < nw; ++k) {
        /* the file's order is the flat weight order of qnav_net_weight() */
        if (parse_q88(ps, &tok[2 + k], what, qnav_net_weight(&ps->pol.u.net,
                                                             (uint16_t)((size_t)j * nw + k))) != 0) {
            return -1;
        }
    }
    ps->unit_line[j] = ps->line;
    ps->next_unit++;
    return 0;
}

static int line_meta(parser_t *ps, const char *body, size_t blen, const token_t *tok,
                     size_t ntok)
{
    char q[80];
    size_t i;
    const char *v;
    size_t vl;
    const char *why;
    qnav_policy_meta_entry_t *e;
    if (ntok < 3) {
        return fail(ps, "'meta' needs a name and a value");
    }
    quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
    if (!meta_name_ok(tok[1].p, tok[1].n)) {
        return fail(ps, "meta name '%s' must be 1..31 of A-Z a-z 0-9 _ . -", q);
    }
    for (i = 0; i < ps->meta.count; ++i) {
        if (tok_is(&tok[1], ps->meta.entry[i].name)) {
            return fail(ps, "duplicate meta '%s' (first on line %lu)", q, ps->meta_line[i]);
        }
    }
    if (ps->meta.count >= QNAV_POLICY_META_MAX) {
        return fail(ps, "more than %d meta lines", QNAV_POLICY_META_MAX);
    }
    /* the value runs from the third token to the end of the (comment-stripped) body */
    v = tok[2].p;
    vl = (size_t)((body + blen) - v);
    while (vl > 0 && (v[vl - 1] == ' ' || v[vl - 1] == '\t')) {
        vl--;
    }
    why = meta_value_problem(v, vl);
    if (why != NULL) {
        return fail(ps, "meta %s: value %s", q, why);
    }
    e = &ps->meta.entry[ps->meta.count];
    memcpy(e->name, tok[1].p, tok[1].n);
    e->name[tok[1].n] = '\0';
    memcpy(e->value, v, vl);
    e->value[vl] = '\0';
    ps->meta_line[ps->meta.count] = ps->line;
    ps->meta.count++;
    return 0;
}

static int line_end(parser_t *ps, size_t ntok)
{
    qnav_ctrl_t ctrl;
    qnav_ctrl_config_t cfg;
    qnav_status_t st;
    if (ntok != 1) {
        return fail(ps, "'end' takes no values");
    }
    ps->end_line = ps->line;
    if (ps->qformat_line == 0) {
        return fail(ps, "missing 'qformat'");
    }
    switch ((qnav_policy_kind_t)ps->pol.kind) {
    case QNAV_POLICY_NET:
        if (ps->hidden_line == 0) {
            return fail(ps, "missing 'hidden'");
        }
        if (ps->version >= 2 && ps->inputs_line == 0) {
            return fail(ps, "missing 'inputs'");
        }
        if (ps->next_unit < ps->pol.u.net.hidden) {
            return fail(ps, "missing unit %u (hidden %u needs units 0..%u)", ps->next_unit,
                        (unsigned)ps->pol.u.net.hidden, ps->pol.u.net.hidden - 1u);
        }
        if (ps->b_out_line == 0) {
            return fail(ps, "missing 'b_out'");
        }
        break;
    case QNAV_POLICY_PROB:
        if (ps->k_goal_line == 0) {
            return fail(ps, "missing 'k_goal'");
        }
        if (ps->k_safe_line == 0) {
            return fail(ps, "missing 'k_safe'");
        }
        break;
    }
    /* final word to the controller: the file is good exactly when init accepts it */
    qnav_ctrl_config_default(&cfg);
    st = qnav_ctrl_init(&ctrl, &cfg, &ps->pol);
    if (st != QNAV_OK) {
        return fail(ps, "policy refused by qnav_ctrl_init: %s (status %d)", qnav_status_str(st),
                    (int)st);
    }
    return 0;
}

/* The keys that belong to one kind of policy; the other kind names them in its error. */
static int is_net_key(const parser_t *ps, const token_t *key)
{
    return (tok_is(key, "inputs") && ps->version >= 2) || tok_is(key, "hidden") ||
           tok_is(key, "unit") || tok_is(key, "b_out");
}

static int is_prob_key(const token_t *key)
{
    return tok_is(key, "k_goal") || tok_is(key, "k_safe");
}

static int line_inputs(parser_t *ps, const token_t *tok, size_t ntok)
{
    char q[80];
    long n = 0;
    if (once(ps, &ps->inputs_line, "inputs") != 0 || want_values(ps, ntok, 1, "inputs") != 0) {
        return -1;
    }
    if (ps->next_unit != 0) {
        return fail(ps, "'inputs' after the first 'unit'");
    }
    quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
    if (parse_int(&tok[1], &n) != 0 ||
        (n != (long)QNAV_NET_INPUTS_PAPER && n != (long)QNAV_NET_INPUTS_PREV)) {
        return fail(ps, "inputs '%s': a network has 2 or 3 inputs", q);
    }
    ps->pol.u.net.inputs = (uint8_t)n;
    return 0;
}

static int line_hidden(parser_t *ps, const token_t *tok, size_t ntok)
{
    char q[80];
    long h = 0;
    if (once(ps, &ps->hidden_line, "hidden") != 0 || want_values(ps, ntok, 1, "hidden") != 0) {
        return -1;
    }
    quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
    if (parse_int(&tok[1], &h) != 0) {
        return fail(ps, "hidden '%s' is not an integer", q);
    }
    if (h < 1 || h > QNAV_MAX_HIDDEN) {
        return fail(ps, "hidden %s outside 1..%d", q, QNAV_MAX_HIDDEN);
    }
    ps->pol.u.net.hidden = (uint8_t)h;
    return 0;
}

/* A key of a network policy file (q: the key, quoted for messages). */
static int line_key_net(parser_t *ps, const token_t *tok, size_t ntok, const char *q)
{
    const token_t *key = &tok[0];
    if (is_prob_key(key)) {
        return fail(ps, "'%s' is not a key of kind network", q);
    }
    if (!is_net_key(ps, key)) {
        return fail(ps, "unknown key '%s'", q);
    }
    if (tok_is(key, "inputs")) {
        return line_inputs(ps, tok, ntok);
    }
    if (tok_is(key, "unit")) {
        return line_unit(ps, tok, ntok);
    }
    if (tok_is(key, "b_out")) {
        if (once(ps, &ps->b_out_line, "b_out") != 0 || want_values(ps, ntok, 1, "b_out") != 0) {
            return -1;
        }
        return parse_q88(ps, &tok[1], "b_out: ", &ps->pol.u.net.b_out);
    }
    return line_hidden(ps, tok, ntok);
}

/* A key of a probabilistic policy file (q: the key, quoted for messages). */
static int line_key_prob(parser_t *ps, const token_t *tok, size_t ntok, const char *q)
{
    const token_t *key = &tok[0];
    int goal = tok_is(key, "k_goal");
    qnav_q8_8_t v = 0;
    if (is_net_key(ps, key)) {
        return fail(ps, "'%s' is not a key of kind probabilistic", q);
    }
    if (!is_prob_key(key)) {
        return fail(ps, "unknown key '%s'", q);
    }
    if (once(ps, goal ? &ps->k_goal_line : &ps->k_safe_line, q) != 0 ||
        want_values(ps, ntok, 1, q) != 0) {
        return -1;
    }
    if (parse_q88(ps, &tok[1], goal ? "k_goal: " : "k_safe: ", &v) != 0) {
        return -1;
    }
    if (v <= 0 || v > K_RAW_MAX) {
        return fail(ps, "%s %d outside (0, 64]: raw Q8.8 must be 1..%ld", q, (int)v, K_RAW_MAX);
    }
    if (goal) {
        ps->pol.u.prob.k_goal = v;
    } else {
        ps->pol.u.prob.k_safe = v;
    }
    return 0;
}

/* The first key: the kind, which decides the keys that may follow. */
static int line_kind(parser_t *ps, const token_t *tok, size_t ntok, const char *q)
{
    char v[80];
    char names[80];
    if (!tok_is(&tok[0], "kind")) {
        return fail(ps, "expected 'kind' as the first key, found '%s'", q);
    }
    if (want_values(ps, ntok, 1, "kind") != 0) {
        return -1;
    }
    if (qnav_policy_kind_from_name(tok[1].p, tok[1].n, &ps->pol.kind) != 0) {
        quote_bytes(tok[1].p, tok[1].n, 40, v, sizeof v);
        return fail(ps, "unknown kind '%s' (expected %s)", v,
                    qnav_policy_kind_list(names, sizeof names, "'", ", ", " or "));
    }
    switch ((qnav_policy_kind_t)ps->pol.kind) {
    case QNAV_POLICY_NET:
        ps->pol.u.net.inputs = QNAV_NET_INPUTS_PAPER; /* version 2 may say 3 */
        break;
    case QNAV_POLICY_PROB:
        break;
    }
    ps->kind_line = ps->line;
    return 0;
}

static int line_key(parser_t *ps, const char *body, size_t blen, const token_t *tok,
                    size_t ntok)
{
    char q[80];
    const token_t *key = &tok[0];
    quote_bytes(key->p, key->n, 40, q, sizeof q);
    if (ps->end_line != 0) {
        return fail(ps, "content after 'end' (line %lu)", ps->end_line);
    }
    if (ps->kind_line == 0) {
        return line_kind(ps, tok, ntok, q);
    }
    if (tok_is(key, "kind")) {
        return once(ps, &ps->kind_line, "kind");
    }
    if (tok_is(key, "qformat")) {
        if (once(ps, &ps->qformat_line, "qformat") != 0 ||
            want_values(ps, ntok, 1, "qformat") != 0) {
            return -1;
        }
        if (!tok_is(&tok[1], "Q8.8")) {
            quote_bytes(tok[1].p, tok[1].n, 40, q, sizeof q);
            return fail(ps, "unsupported qformat '%s' (version 1 has only Q8.8)", q);
        }
        return 0;
    }
    if (tok_is(key, "meta")) {
        return line_meta(ps, body, blen, tok, ntok);
    }
    if (tok_is(key, "end")) {
        return line_end(ps, ntok);
    }
    switch ((qnav_policy_kind_t)ps->pol.kind) {
    case QNAV_POLICY_NET:
        return line_key_net(ps, tok, ntok, q);
    case QNAV_POLICY_PROB:
        return line_key_prob(ps, tok, ntok, q);
    }
    return fail(ps, "unknown kind %u", (unsigned)ps->pol.kind); /* line_kind set a known one */
}

/* The bytes of one line: no NUL, no lone carriage return, no control character but tab. */
static int line_bytes(parser_t *ps, const char *s, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)s[i];
        if (c == 0) {
            return fail(ps, "NUL byte at column %zu", i + 1);
        }
        if (c == '\r') {
            return fail(ps, "carriage return not followed by a line feed at column %zu", i + 1);
        }
        if ((c < 0x20 && c != '\t') || c == 0x7f) {
            return fail(ps, "control character 0x%02X at column %zu", (unsigned)c, i + 1);
        }
    }
    return 0;
}

/* The blank-separated tokens of buf[0..blen): their count, MAX_TOKENS + 1 when there are
 * more than MAX_TOKENS (the first MAX_TOKENS are in tok). */
static size_t split_tokens(const char *buf, size_t blen, token_t *tok)
{
    size_t ntok = 0;
    size_t i = 0;
    while (i < blen) {
        while (i < blen && (buf[i] == ' ' || buf[i] == '\t')) {
            i++;
        }
        if (i >= blen) {
            break;
        }
        if (ntok == MAX_TOKENS) {
            return MAX_TOKENS + 1u; /* more than any key takes: "too many" */
        }
        tok[ntok].p = buf + i;
        while (i < blen && buf[i] != ' ' && buf[i] != '\t') {
            i++;
        }
        tok[ntok].n = (size_t)((buf + i) - tok[ntok].p);
        ntok++;
    }
    return ntok;
}

/* One line of the file: n bytes at s, without its line ending; ps->line is its number. */
static int parse_line(parser_t *ps, const char *s, size_t n)
{
    char buf[QNAV_POLICY_LINE_MAX + 1];
    token_t tok[MAX_TOKENS];
    size_t ntok;
    size_t blen = n;
    if (n > QNAV_POLICY_LINE_MAX) {
        return fail(ps, "line longer than %d bytes", QNAV_POLICY_LINE_MAX);
    }
    if (line_bytes(ps, s, n) != 0) {
        return -1;
    }
    memcpy(buf, s, n);
    buf[n] = '\0';
    if (ps->line == 1 && n >= 3 && memcmp(buf, "\xEF\xBB\xBF", 3) == 0) {
        return fail(ps, "byte order mark before 'qnav-policy': save without BOM");
    }
    /* comments: from '#' to the end of the line, on every line but the first */
    if (ps->line > 1) {
        char *hash = memchr(buf, '#', n);
        if (hash != NULL) {
            blen = (size_t)(hash - buf);
        }
    }
    ntok = split_tokens(buf, blen, tok);
    if (ntok > MAX_TOKENS) {
        /* a meta value is free text; every other line is short */
        if (!tok_is(&tok[0], "meta")) {
            return fail(ps, "too many values on one line (more than %d tokens)", MAX_TOKENS);
        }
        ntok = MAX_TOKENS;
    }
    if (ps->line == 1) {
        return line_magic(ps, tok, ntok);
    }
    return ntok > 0 ? line_key(ps, buf, blen, tok, ntok) : 0;
}

qnav_policy_io_status_t qnav_policy_parse_meta(const char *text, size_t len, const char *name,
                           qnav_policy_t *out, qnav_policy_meta_t *meta, char *err,
                           size_t errlen)
{
    parser_t *ps;
    size_t pos = 0;
    int rc = 0;
    if (name == NULL) {
        name = "(policy)";
    }
    if (out == NULL || (text == NULL && len > 0)) {
        set_err(err, errlen, "%s: null argument", name);
        return QNAV_POLICY_IO_E_NULL;
    }
    /* the parser state holds a whole policy and metadata: keep it off the stack */
    ps = (parser_t *)calloc(1, sizeof *ps);
    if (ps == NULL) {
        set_err(err, errlen, "%s: out of memory", name);
        return QNAV_POLICY_IO_E_NOMEM;
    }
    ps->name = name;
    ps->err = err;
    ps->errlen = errlen;
    if (len == 0) {
        ps->line = 1;
        rc = fail(ps, "empty file (line 1 must be 'qnav-policy %d')",
                  QNAV_POLICY_FORMAT_VERSION);
    } else if (len > (size_t)QNAV_POLICY_FILE_MAX) {
        ps->line = 1;
        rc = fail(ps, "file larger than %ld bytes", QNAV_POLICY_FILE_MAX);
    }
    while (rc == 0 && pos < len) {
        size_t start = pos;
        size_t eol = pos;
        size_t n;
        while (eol < len && text[eol] != '\n') {
            eol++;
        }
        pos = eol < len ? eol + 1 : len;
        ps->line++;
        n = eol - start;
        if (n > 0 && eol < len && text[eol - 1] == '\r') {
            n--; /* CRLF line ending: accepted (docs/policy-format.md) */
        }
        rc = parse_line(ps, text + start, n);
    }
    if (rc == 0 && ps->end_line == 0) {
        rc = fail(ps, "truncated: no 'end' line");
    }
    if (rc == 0) {
        *out = ps->pol;
        if (meta != NULL) {
            *meta = ps->meta;
        }
    }
    free(ps);
    return rc == 0 ? QNAV_POLICY_IO_OK : QNAV_POLICY_IO_E_PARSE;
}

qnav_policy_io_status_t qnav_policy_parse(const char *text, size_t len, const char *name, qnav_policy_t *out,
                      char *err, size_t errlen)
{
    return qnav_policy_parse_meta(text, len, name, out, NULL, err, errlen);
}

qnav_policy_io_status_t qnav_policy_read_meta(const char *path, qnav_policy_t *out, qnav_policy_meta_t *meta,
                          char *err, size_t errlen)
{
    FILE *f;
    char *buf;
    size_t cap = (size_t)QNAV_POLICY_FILE_MAX + 1;
    size_t len = 0;
    qnav_policy_io_status_t rc;
    char nm[200];
    if (path == NULL) {
        set_err(err, errlen, "(null path): cannot open");
        return QNAV_POLICY_IO_E_NULL;
    }
    quote_bytes(path, strlen(path), 160, nm, sizeof nm);
    f = fopen(path, "rb");
    if (f == NULL) {
        set_err(err, errlen, "%s: cannot open (%s)", nm, strerror(errno));
        return QNAV_POLICY_IO_E_IO;
    }
    buf = (char *)malloc(cap);
    if (buf == NULL) {
        fclose(f);
        set_err(err, errlen, "%s: out of memory", nm);
        return QNAV_POLICY_IO_E_NOMEM;
    }
    /* read one byte more than the limit so that an oversized file is detected */
    while (len < cap) {
        size_t got = fread(buf + len, 1, cap - len, f);
        if (got == 0) {
            break;
        }
        len += got;
    }
    if (ferror(f)) {
        int e = errno;
        fclose(f);
        free(buf);
        set_err(err, errlen, "%s: read error (%s)", nm, strerror(e));
        return QNAV_POLICY_IO_E_IO;
    }
    fclose(f);
    if (len > (size_t)QNAV_POLICY_FILE_MAX) {
        unsigned long line = 1;
        size_t i;
        for (i = 0; i < (size_t)QNAV_POLICY_FILE_MAX; ++i) {
            line += buf[i] == '\n';
        }
        free(buf);
        set_err(err, errlen, "%s:%lu: file larger than %ld bytes", nm, line,
                QNAV_POLICY_FILE_MAX);
        return QNAV_POLICY_IO_E_PARSE;
    }
    rc = qnav_policy_parse_meta(buf, len, path, out, meta, err, errlen);
    free(buf);
    return rc;
}

qnav_policy_io_status_t qnav_policy_read(const char *path, qnav_policy_t *out, char *err, size_t errlen)
{
    return qnav_policy_read_meta(path, out, NULL, err, errlen);
}

/* ---- rendering ----------------------------------------------------------------------- */

typedef struct {
    char *buf;
    size_t cap;
    size_t len; /* length of the full text, even past cap */
} out_t;

static void emit(out_t *o, const char *fmt, ...) QNAV_PRINTF_LIKE(2, 3);
static void emit(out_t *o, const char *fmt, ...)
{
    va_list ap;
    int n;
    char *dst = NULL;
    size_t room = 0;
    if (o->buf != NULL && o->len < o->cap) {
        dst = o->buf + o->len;
        room = o->cap - o->len;
    }
    va_start(ap, fmt);
    n = vsnprintf(dst, room, fmt, ap);
    va_end(ap);
    if (n > 0) {
        o->len += (size_t)n;
    }
}

/* A Q8.8 value as a comment: 4 decimals, sign always shown. */
static void emit_real(out_t *o, int raw)
{
    emit(o, " %+.4f", (double)raw / 256.0);
}

/* The comment as '#' lines: split at newlines and so that no line exceeds the limit;
 * control characters become '?'. */
static void emit_comment(out_t *o, const char *c)
{
    const size_t width = QNAV_POLICY_LINE_MAX - 2; /* room after the "# " prefix */
    size_t n = strlen(c);
    size_t i = 0;
    do {
        size_t end = i;
        size_t s = i;
        while (end < n && c[end] != '\n') {
            end++;
        }
        do {
            char line[QNAV_POLICY_LINE_MAX + 1];
            size_t k = end - s < width ? end - s : width;
            size_t m;
            for (m = 0; m < k; ++m) {
                unsigned char ch = (unsigned char)c[s + m];
                line[m] = ((ch < 0x20 && ch != '\t') || ch == 0x7f) ? '?' : (char)ch;
            }
            line[k] = '\0';
            if (k > 0) {
                emit(o, "# %s\n", line);
            } else {
                emit(o, "#\n");
            }
            s += k;
        } while (s < end);
        i = end + 1;
    } while (i < n);
}

/* A network's unit lines (the flat weight order) and b_out. */
static void emit_net(out_t *o, const qnav_net_t *net)
{
    qnav_net_t n = *net;
    size_t per = (size_t)n.inputs + 2u;
    size_t j;
    size_t k;
    emit(o, "%s", per == 4u
                      ? "# unit j  w_theta  w_dist b_hidden   w_out   (raw Q8.8 = value * 256)\n"
                      : "# unit j  w_theta  w_dist  w_prev b_hidden   w_out   (raw Q8.8 = value * 256)\n");
    for (j = 0; j < n.hidden; ++j) {
        emit(o, "unit %2zu ", j);
        for (k = 0; k < per; ++k) {
            emit(o, " %*d", k == per - 2u ? 8 : 7, /* b_hidden's column is wider */
                 (int)*qnav_net_weight(&n, (uint16_t)(j * per + k)));
        }
        emit(o, "   #");
        for (k = 0; k < per; ++k) {
            emit_real(o, *qnav_net_weight(&n, (uint16_t)(j * per + k)));
        }
        emit(o, "\n");
    }
    emit(o, "b_out %d   #", (int)n.b_out);
    emit_real(o, n.b_out);
    emit(o, "\n");
}

int qnav_policy_format(const qnav_policy_t *policy, const qnav_policy_meta_t *meta,
                       const char *comment, char *buf, size_t buflen, char *err,
                       size_t errlen)
{
    out_t o;
    size_t i;
    if (qnav_policy_check(policy, err, errlen) != 0) {
        return QNAV_POLICY_IO_E_INVALID;
    }
    if (comment != NULL && strlen(comment) > QNAV_POLICY_COMMENT_MAX) {
        set_err(err, errlen, "comment longer than %d bytes", QNAV_POLICY_COMMENT_MAX);
        return QNAV_POLICY_IO_E_INVALID;
    }
    if (meta != NULL) {
        if (meta->count > QNAV_POLICY_META_MAX) {
            set_err(err, errlen, "more than %d metadata entries", QNAV_POLICY_META_MAX);
            return QNAV_POLICY_IO_E_INVALID;
        }
        for (i = 0; i < meta->count; ++i) {
            const qnav_policy_meta_entry_t *e = &meta->entry[i];
            size_t nl = strnlen(e->name, sizeof e->name);
            size_t vl = strnlen(e->value, sizeof e->value);
            const char *why = meta_value_problem(e->value, vl);
            size_t k;
            if (nl == sizeof e->name || vl == sizeof e->value || !meta_name_ok(e->name, nl)) {
                set_err(err, errlen, "metadata entry %zu: bad name or unterminated text", i);
                return QNAV_POLICY_IO_E_INVALID;
            }
            if (why != NULL) {
                set_err(err, errlen, "meta %s: value %s", e->name, why);
                return QNAV_POLICY_IO_E_INVALID;
            }
            for (k = 0; k < i; ++k) {
                if (strcmp(meta->entry[k].name, e->name) == 0) {
                    set_err(err, errlen, "meta %s appears twice", e->name);
                    return QNAV_POLICY_IO_E_INVALID;
                }
            }
        }
    }
    o.buf = buf;
    o.cap = buflen;
    o.len = 0;
    if (buf != NULL && buflen > 0) {
        buf[0] = '\0';
    }
    emit(&o, "%s %d\n", MAGIC, qnav_policy_file_version(policy));
    if (comment != NULL) {
        emit_comment(&o, comment);
    }
    emit(&o, "kind %s\n", qnav_policy_kind_name(policy->kind));
    emit(&o, "qformat Q8.8\n");
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_NET:
        emit(&o, "hidden %u\n", (unsigned)policy->u.net.hidden);
        if (qnav_policy_file_version(policy) >= 2) {
            emit(&o, "inputs %u\n", (unsigned)policy->u.net.inputs);
        }
        break;
    case QNAV_POLICY_PROB:
        break;
    }
    for (i = 0; meta != NULL && i < meta->count; ++i) {
        emit(&o, "meta %s %s\n", meta->entry[i].name, meta->entry[i].value);
    }
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_NET:
        emit_net(&o, &policy->u.net);
        break;
    case QNAV_POLICY_PROB:
        emit(&o, "k_goal %d   #", (int)policy->u.prob.k_goal);
        emit_real(&o, policy->u.prob.k_goal);
        emit(&o, "\nk_safe %d   #", (int)policy->u.prob.k_safe);
        emit_real(&o, policy->u.prob.k_safe);
        emit(&o, "\n");
        break;
    }
    emit(&o, "end\n");
    return (int)o.len;
}

/* ---- writing ------------------------------------------------------------------------- */

/* All len bytes of data to fd, through short writes and interruptions. Returns 0, or -1
 * with errno set. */
static int write_all(int fd, const void *data, size_t len)
{
    size_t done = 0;
    while (done < len) {
        ssize_t w = write(fd, (const char *)data + done, len - done);
        if (w < 0) {
            if (errno == EINTR) {
                continue;
            }
            return -1;
        }
        done += (size_t)w;
    }
    return 0;
}

/* Make a rename durable: fsync the directory that holds path (pl bytes), named in dir
 * (pl + 2 bytes of the caller's). Some file systems refuse fsync on a directory: not an
 * error. */
static void sync_dir(char *dir, const char *path, size_t pl)
{
    char *slash;
    int fd;
    memcpy(dir, path, pl + 1);
    slash = strrchr(dir, '/');
    if (slash == NULL) {
        memcpy(dir, ".", 2);
    } else if (slash == dir) {
        dir[1] = '\0';
    } else {
        *slash = '\0';
    }
    fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        (void)close(fd);
    }
}

qnav_policy_io_status_t qnav_policy_io_write_atomic(const char *path, const void *data, size_t len, char *err,
                                size_t errlen)
{
    char *tmp;
    char *dir;
    size_t pl;
    int fd;
    char nm[200];
    if (path == NULL || (data == NULL && len > 0)) {
        set_err(err, errlen, "(null): null argument");
        return QNAV_POLICY_IO_E_NULL;
    }
    quote_bytes(path, strlen(path), 160, nm, sizeof nm);
    pl = strlen(path);
    if (pl == 0) {
        set_err(err, errlen, "(empty path): cannot write");
        return QNAV_POLICY_IO_E_IO;
    }
    tmp = (char *)malloc(pl + 16);
    dir = (char *)malloc(pl + 2);
    if (tmp == NULL || dir == NULL) {
        free(tmp);
        free(dir);
        set_err(err, errlen, "%s: out of memory", nm);
        return QNAV_POLICY_IO_E_NOMEM;
    }
    memcpy(tmp, path, pl);
    memcpy(tmp + pl, ".tmpXXXXXX", 11);
    fd = mkstemp(tmp);
    if (fd < 0) {
        set_err(err, errlen, "%s: cannot create a temporary file beside it (%s)", nm,
                strerror(errno));
        free(tmp);
        free(dir);
        return QNAV_POLICY_IO_E_IO;
    }
    if (fchmod(fd, 0644) != 0) {
        goto io_error;
    }
    if (write_all(fd, data, len) != 0 || fsync(fd) != 0) {
        goto io_error;
    }
    if (close(fd) != 0) {
        fd = -1;
        goto io_error;
    }
    fd = -1;
    if (rename(tmp, path) != 0) {
        goto io_error;
    }
    sync_dir(dir, path, pl);
    free(tmp);
    free(dir);
    return QNAV_POLICY_IO_OK;

io_error:
    set_err(err, errlen, "%s: cannot write (%s)", nm, strerror(errno));
    if (fd >= 0) {
        (void)close(fd);
    }
    (void)unlink(tmp);
    free(tmp);
    free(dir);
    return QNAV_POLICY_IO_E_IO;
}

qnav_policy_io_status_t qnav_policy_write_meta(const char *path, const qnav_policy_t *policy,
                           const qnav_policy_meta_t *meta, const char *comment, char *err,
                           size_t errlen)
{
    char msg[QNAV_POLICY_IO_ERRLEN];
    char nm[200];
    char *buf;
    int n;
    qnav_policy_io_status_t rc;
    const char *p = path != NULL ? path : "(null)";
    quote_bytes(p, strlen(p), 160, nm, sizeof nm);
    n = qnav_policy_format(policy, meta, comment, NULL, 0, msg, sizeof msg);
    if (n < 0) {
        set_err(err, errlen, "%s: refusing to write an invalid policy: %s", nm, msg);
        return QNAV_POLICY_IO_E_INVALID;
    }
    buf = (char *)malloc((size_t)n + 1);
    if (buf == NULL) {
        set_err(err, errlen, "%s: out of memory", nm);
        return QNAV_POLICY_IO_E_NOMEM;
    }
    if (qnav_policy_format(policy, meta, comment, buf, (size_t)n + 1, msg, sizeof msg) != n) {
        set_err(err, errlen, "%s: the policy's text changed length while it was written: %s", nm,
                msg);
        free(buf);
        return QNAV_POLICY_IO_E_INVALID;
    }
    rc = qnav_policy_io_write_atomic(path, buf, (size_t)n, err, errlen);
    free(buf);
    return rc;
}

qnav_policy_io_status_t qnav_policy_write(const char *path, const qnav_policy_t *policy, const char *comment,
                      char *err, size_t errlen)
{
    return qnav_policy_write_meta(path, policy, NULL, comment, err, errlen);
}
