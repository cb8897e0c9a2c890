/*
 * Tests of the policy-file reader and writer (host/policyio): exact round trips of random
 * policies, every refusal naming the right line, the committed corpus of bad files
 * (tests/policyio/bad/ with its side table expected.tsv), a mutation test that truncates
 * and corrupts good files and must never crash (run under ASan and UBSan in the debug
 * build), agreement with qnav_ctrl_init on the probabilistic parameters, and atomic writes.
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "qnav/ctrl.h"
#include "qnav/policy_io.h"

#ifndef QNAV_POLICYIO_BAD_DIR
#error "QNAV_POLICYIO_BAD_DIR must name tests/policyio/bad"
#endif

static uint64_t rng_state;

static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static void random_policy(qnav_policy_t *p)
{
    memset(p, 0, sizeof *p);
    if (rng_next() % 4u == 0u) {
        p->kind = (uint8_t)QNAV_POLICY_PROB;
        p->u.prob.k_goal = (qnav_q8_8_t)(1 + (int)(rng_next() % 16384u));
        p->u.prob.k_safe = (qnav_q8_8_t)(1 + (int)(rng_next() % 16384u));
    } else {
        uint16_t k;
        uint8_t h = (uint8_t)(1u + rng_next() % QNAV_MAX_HIDDEN);
        qnav_policy_net_zero(p, h);
        for (k = 0; k < QNAV_NET_WEIGHTS(h); ++k) {
            /* full int16 range, with the extremes made likely */
            uint64_t r = rng_next();
            int32_t v = (int32_t)(r % 65536u) - 32768;
            if (r % 17u == 0u) {
                v = (r % 34u == 0u) ? -32768 : 32767;
            }
            *qnav_net_weight(&p->u.net, k) = (qnav_q8_8_t)v;
        }
    }
}

/* The file as the writer renders it (malloc'd, exactly len bytes, no NUL after it, so
 * that ASan catches any read past the end). */
static char *render(const qnav_policy_t *p, const qnav_policy_meta_t *meta,
                    const char *comment, size_t *len)
{
    char err[QNAV_POLICY_IO_ERRLEN];
    int n = qnav_policy_format(p, meta, comment, NULL, 0, err, sizeof err);
    char *tmp;
    char *out;
    assert_true(n > 0);
    tmp = malloc((size_t)n + 1);
    assert_non_null(tmp);
    assert_int_equal(qnav_policy_format(p, meta, comment, tmp, (size_t)n + 1, err, sizeof err),
                     n);
    out = malloc((size_t)n);
    assert_non_null(out);
    memcpy(out, tmp, (size_t)n);
    free(tmp);
    *len = (size_t)n;
    return out;
}

/* Parse a string; returns the status and leaves the message in err. */
static int parse_str(const char *text, qnav_policy_t *out, char *err)
{
    size_t n = strlen(text);
    char *copy = malloc(n > 0 ? n : 1);
    int rc;
    assert_non_null(copy);
    memcpy(copy, text, n);
    rc = qnav_policy_parse(copy, n, "t.policy", out, err, QNAV_POLICY_IO_ERRLEN);
    free(copy);
    return rc;
}

static void assert_refused(const char *text, const char *prefix, const char *fragment)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    assert_int_equal(parse_str(text, &p, err), QNAV_POLICY_IO_E_PARSE);
    if (strncmp(err, prefix, strlen(prefix)) != 0 || strstr(err, fragment) == NULL) {
        fail_msg("message '%s' lacks prefix '%s' or fragment '%s'", err, prefix, fragment);
    }
    assert_null(strchr(err, '\n'));
}

static const char net_text[] = "qnav-policy 1\n"
                               "# comment line\n"
                               "kind network\n"
                               "qformat Q8.8\n"
                               "hidden 2\n"
                               "meta source simevo --env dense   # trailing comment\n"
                               "unit 0 -512 300 12 -40   # -2.0 ...\n"
                               "\n"
                               "\tunit 1  +256\t-128 0 1024\n"
                               "b_out -32768\n"
                               "end\n"
                               "# after end: comments and blank lines are fine\n\n";

/* ---- accepted files ------------------------------------------------------------------ */

static void test_reader_accepts_documented_network_file(void **state)
{
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    (void)state;
    assert_int_equal(qnav_policy_parse_meta(net_text, sizeof net_text - 1, "n.policy", &p,
                                            &meta, err, sizeof err),
                     0);
    assert_int_equal(p.kind, QNAV_POLICY_NET);
    assert_int_equal(p.u.net.hidden, 2);
    assert_int_equal(p.u.net.w_theta[0], -512);
    assert_int_equal(p.u.net.w_dist[0], 300);
    assert_int_equal(p.u.net.b_hidden[0], 12);
    assert_int_equal(p.u.net.w_out[0], -40);
    assert_int_equal(p.u.net.w_theta[1], 256);
    assert_int_equal(p.u.net.w_out[1], 1024);
    assert_int_equal(p.u.net.b_out, -32768);
    assert_int_equal(meta.count, 1);
    assert_string_equal(qnav_policy_meta_get(&meta, "source"), "simevo --env dense");
}

static const char net3_text[] = "qnav-policy 2\n"
                                "kind network\n"
                                "qformat Q8.8\n"
                                "hidden 2\n"
                                "inputs 3\n"
                                "unit 0 -512 300 -77 12 -40\n"
                                "unit 1 256 -128 99 0 1024\n"
                                "b_out 5\n"
                                "end\n";

static void test_version_2_file_with_three_inputs_reads_and_writes_back_the_same(void **state)
{
    qnav_policy_t p;
    qnav_policy_t q;
    char buf[1024];
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    int n;
    (void)state;
    assert_int_equal(qnav_policy_parse(net3_text, sizeof net3_text - 1, "n3.policy", &p, err,
                                       sizeof err),
                     0);
    assert_int_equal(p.u.net.inputs, 3);
    assert_int_equal(p.u.net.w_prev[0], -77);
    assert_int_equal(p.u.net.b_hidden[0], 12);
    assert_int_equal(p.u.net.w_prev[1], 99);
    assert_int_equal(p.u.net.w_out[1], 1024);
    assert_int_equal(qnav_policy_file_version(&p), 2);
    n = qnav_policy_format(&p, NULL, NULL, buf, sizeof buf, err, sizeof err);
    assert_true(n > 0 && (size_t)n < sizeof buf);
    assert_non_null(strstr(buf, "qnav-policy 2\n"));
    assert_non_null(strstr(buf, "inputs 3\n"));
    assert_int_equal(qnav_policy_parse(buf, (size_t)n, "again", &q, err, sizeof err), 0);
    assert_true(qnav_policy_equal(&p, &q));
    q.u.net.w_prev[1] = 98;
    assert_false(qnav_policy_equal(&p, &q));
}

static void test_two_input_network_is_still_written_as_version_1(void **state)
{
    qnav_policy_t p;
    char buf[1024];
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    int n;
    (void)state;
    qnav_policy_net_zero(&p, 2);
    n = qnav_policy_format(&p, NULL, NULL, buf, sizeof buf, err, sizeof err);
    assert_true(n > 0);
    assert_memory_equal(buf, "qnav-policy 1\n", 14);
    assert_null(strstr(buf, "inputs"));
    assert_string_equal(qnav_policy_kind_name(QNAV_POLICY_NET), "network");
    assert_null(qnav_policy_kind_name(9));
}

static void test_reader_accepts_crlf_line_endings(void **state)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    (void)state;
    assert_int_equal(parse_str("qnav-policy 1\r\nkind probabilistic\r\nqformat Q8.8\r\n"
                               "k_goal 512\r\nk_safe 1536\r\nend\r\n",
                               &p, err),
                     0);
    assert_int_equal(p.kind, QNAV_POLICY_PROB);
    assert_int_equal(p.u.prob.k_goal, 512);
    assert_int_equal(p.u.prob.k_safe, 1536);
}

static void test_reader_accepts_missing_final_newline_after_end(void **state)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    (void)state;
    assert_int_equal(parse_str("qnav-policy 1\nkind probabilistic\nqformat Q8.8\n"
                               "k_safe 1\nk_goal 16384\nend",
                               &p, err),
                     0);
    assert_int_equal(p.u.prob.k_goal, 16384);
    assert_int_equal(p.u.prob.k_safe, 1);
}

static void test_reader_leaves_output_untouched_on_error(void **state)
{
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    (void)state;
    memset(&p, 0xA5, sizeof p);
    memset(&meta, 0x5A, sizeof meta);
    static const char text[] = "qnav-policy 1\nkind network\nmeta a b\n";
    assert_int_equal(qnav_policy_parse_meta(text, sizeof text - 1, "x", &p, &meta, err,
                                            sizeof err),
                     QNAV_POLICY_IO_E_PARSE);
    assert_non_null(strstr(err, "x:3: truncated: no 'end' line"));
    assert_int_equal(p.kind, 0xA5);
    assert_int_equal(((unsigned char *)&meta)[0], 0x5A);
}

/* ---- round trips --------------------------------------------------------------------- */

static void test_random_policies_round_trip_exactly_through_text(void **state)
{
    int i;
    (void)state;
    rng_state = 1;
    for (i = 0; i < 500; ++i) {
        qnav_policy_t p;
        qnav_policy_t q;
        qnav_policy_meta_t meta;
        qnav_policy_meta_t meta2;
        char err[QNAV_POLICY_IO_ERRLEN] = "";
        char value[64];
        size_t len;
        char *text;
        random_policy(&p);
        qnav_policy_meta_clear(&meta);
        (void)snprintf(value, sizeof value, "run %d of the round trip", i);
        assert_int_equal(qnav_policy_meta_set(&meta, "source", value, err, sizeof err), 0);
        assert_int_equal(qnav_policy_meta_set(&meta, "fitness", "-0.25", err, sizeof err), 0);
        text = render(&p, &meta, i % 2 ? "a comment\nover two lines" : NULL, &len);
        memset(&q, 0x77, sizeof q);
        if (qnav_policy_parse_meta(text, len, "rt", &q, &meta2, err, sizeof err) != 0) {
            fail_msg("round trip %d refused: %s", i, err);
        }
        assert_true(qnav_policy_equal(&p, &q));
        assert_int_equal(meta2.count, 2);
        assert_string_equal(meta2.entry[0].value, value);
        assert_string_equal(qnav_policy_meta_get(&meta2, "fitness"), "-0.25");
        free(text);
    }
}

static void test_write_then_read_gives_the_same_policy_and_leaves_no_temp_file(void **state)
{
    char dir[] = "/tmp/qnav_policyio_XXXXXX";
    char path[256];
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    qnav_policy_t q;
    DIR *d;
    struct dirent *e;
    int files = 0;
    struct stat st;
    (void)state;
    assert_non_null(mkdtemp(dir));
    (void)snprintf(path, sizeof path, "%s/net.policy", dir);
    rng_state = 99;
    random_policy(&p);
    assert_int_equal(qnav_policy_write(path, &p, "written by a test", err, sizeof err), 0);
    /* overwrite: the rename replaces the old file */
    random_policy(&p);
    assert_int_equal(qnav_policy_write(path, &p, NULL, err, sizeof err), 0);
    assert_int_equal(qnav_policy_read(path, &q, err, sizeof err), 0);
    assert_true(qnav_policy_equal(&p, &q));
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0644);
    d = opendir(dir);
    assert_non_null(d);
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] != '.') {
            files++;
        }
    }
    closedir(d);
    assert_int_equal(files, 1);
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0);
}

static void test_writer_refuses_invalid_policy_and_keeps_old_file(void **state)
{
    char dir[] = "/tmp/qnav_policyio_XXXXXX";
    char path[256];
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    qnav_policy_t q;
    (void)state;
    assert_non_null(mkdtemp(dir));
    (void)snprintf(path, sizeof path, "%s/prob.policy", dir);
    qnav_policy_prob_default(&p);
    assert_int_equal(qnav_policy_write(path, &p, NULL, err, sizeof err), 0);
    p.u.prob.k_goal = 0;
    assert_int_equal(qnav_policy_write(path, &p, NULL, err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_non_null(strstr(err, "refusing to write an invalid policy: k_goal 0 outside"));
    assert_int_equal(qnav_policy_read(path, &q, err, sizeof err), 0);
    qnav_policy_prob_default(&p);
    assert_int_equal(q.u.prob.k_goal, p.u.prob.k_goal); /* the old file is intact */
    p.kind = 9;
    assert_int_equal(qnav_policy_write(path, &p, NULL, err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_non_null(strstr(err, "unknown policy kind 9"));
    assert_int_equal(unlink(path), 0);
    assert_int_equal(rmdir(dir), 0);
}

static void test_writer_reports_unwritable_directory(void **state)
{
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    (void)state;
    qnav_policy_prob_default(&p);
    assert_int_equal(qnav_policy_write("/nonexistent_qnav_dir/p.policy", &p, NULL, err,
                                       sizeof err),
                     QNAV_POLICY_IO_E_IO);
    assert_non_null(strstr(err, "/nonexistent_qnav_dir/p.policy: cannot create"));
}

static void test_long_and_multiline_comments_still_round_trip(void **state)
{
    char comment[QNAV_POLICY_COMMENT_MAX + 1];
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    qnav_policy_t q;
    size_t len;
    size_t i;
    char *text;
    (void)state;
    for (i = 0; i < sizeof comment - 1; ++i) {
        comment[i] = (i % 300u == 299u) ? '\n' : (i % 7u == 0u ? '\x01' : 'c');
    }
    comment[sizeof comment - 1] = '\0';
    qnav_policy_net_zero(&p, 5);
    text = render(&p, NULL, comment, &len);
    assert_int_equal(qnav_policy_parse(text, len, "c", &q, err, sizeof err), 0);
    assert_true(qnav_policy_equal(&p, &q));
    free(text);
    comment[0] = 'x';
    {
        char big[QNAV_POLICY_COMMENT_MAX + 2];
        memset(big, 'y', sizeof big - 1);
        big[sizeof big - 1] = '\0';
        assert_int_equal(qnav_policy_format(&p, NULL, big, NULL, 0, err, sizeof err), QNAV_POLICY_IO_E_INVALID);
        assert_non_null(strstr(err, "comment longer than"));
    }
}

static void test_meta_set_refuses_values_that_would_not_round_trip(void **state)
{
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    char big[QNAV_POLICY_META_VALUE_MAX + 2];
    int i;
    (void)state;
    qnav_policy_meta_clear(&meta);
    assert_int_equal(qnav_policy_meta_set(&meta, "fitness", "1 # 2", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_non_null(strstr(err, "contains '#'"));
    assert_int_equal(qnav_policy_meta_set(&meta, "fitness", " 1", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_int_equal(qnav_policy_meta_set(&meta, "fitness", "a\nb", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_int_equal(qnav_policy_meta_set(&meta, "fit ness", "1", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_int_equal(qnav_policy_meta_set(&meta, "", "1", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    memset(big, 'v', sizeof big - 1);
    big[sizeof big - 1] = '\0';
    assert_int_equal(qnav_policy_meta_set(&meta, "long", big, err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_int_equal(meta.count, 0);
    for (i = 0; i < QNAV_POLICY_META_MAX; ++i) {
        char name[16];
        (void)snprintf(name, sizeof name, "k%d", i);
        assert_int_equal(qnav_policy_meta_set(&meta, name, "v", err, sizeof err), 0);
    }
    assert_int_equal(qnav_policy_meta_set(&meta, "k3", "replaced", err, sizeof err), 0);
    assert_string_equal(qnav_policy_meta_get(&meta, "k3"), "replaced");
    assert_int_equal(qnav_policy_meta_set(&meta, "one_more", "v", err, sizeof err), QNAV_POLICY_IO_E_INVALID);
    assert_int_equal(meta.count, QNAV_POLICY_META_MAX);
}

/* ---- refusals with their line -------------------------------------------------------- */

static void test_reader_names_the_line_of_each_problem(void **state)
{
    (void)state;
    assert_refused("", "t.policy:1: ", "empty file");
    assert_refused("qnav-policy 1\nkind network\nqformat Q8.8\nhidden 1\n"
                   "unit 0 1 2 3\nb_out 0\nend\n",
                   "t.policy:5: ", "expected 4 weights");
    assert_refused("qnav-policy 1\n\n\n# c\nkind network\nqformat Q8.8\nhidden 1\n"
                   "unit 0 1 2 3 4\nhidden 1\nb_out 0\nend\n",
                   "t.policy:9: ", "duplicate 'hidden' (first on line 7)");
    assert_refused("qnav-policy 1\nkind network\nqformat Q8.8\nhidden 2\nunit 0 1 2 3 4\n"
                   "b_out 0\n\n# c\nend\n",
                   "t.policy:9: ", "missing unit 1 (hidden 2 needs units 0..1)");
    assert_refused("qnav-policy 1\nkind probabilistic\nqformat Q8.8\nk_goal 1\nk_safe 1\n"
                   "end\nk_goal 3\n",
                   "t.policy:7: ", "content after 'end' (line 6)");
    assert_refused("qnav-policy 1\nkind probabilistic\r\n\rqformat Q8.8\n", "t.policy:3: ",
                   "carriage return");
    assert_refused("qnav-policy 1\nkind probabilistic\nqformat Q8.8\nk_goal 1\nk_safe 1\n"
                   "end\r",
                   "t.policy:6: ", "carriage return not followed by a line feed");
    assert_refused("qnav-policy 1\nkind probabilistic\nqformat Q8.8\nk_goal 1\nk_safe 1\n",
                   "t.policy:5: ", "truncated: no 'end' line");
    assert_refused("qnav-policy 1 # c\n", "t.policy:1: ", "two tokens, found 4");
    assert_refused("qnav-policy 1\nkind network\nqformat Q8.8\nhidden 1\n"
                   "unit 0 1 2 3 -\nb_out 0\nend\n",
                   "t.policy:5: ", "'-' is not an integer");
}

static void test_line_of_exactly_the_limit_is_accepted_and_one_more_refused(void **state)
{
    char text[600];
    char line[QNAV_POLICY_LINE_MAX + 2];
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    (void)state;
    memset(line, 'x', sizeof line);
    line[0] = '#';
    line[QNAV_POLICY_LINE_MAX] = '\0';
    (void)snprintf(text, sizeof text,
                   "qnav-policy 1\n%s\nkind probabilistic\nqformat Q8.8\nk_goal 1\n"
                   "k_safe 1\nend\n",
                   line);
    assert_int_equal(parse_str(text, &p, err), 0);
    line[QNAV_POLICY_LINE_MAX] = 'x';
    line[QNAV_POLICY_LINE_MAX + 1] = '\0';
    (void)snprintf(text, sizeof text,
                   "qnav-policy 1\n%s\nkind probabilistic\nqformat Q8.8\nk_goal 1\n"
                   "k_safe 1\nend\n",
                   line);
    assert_refused(text, "t.policy:2: ", "line longer than 256 bytes");
}

static void test_reader_agrees_with_ctrl_init_on_every_probabilistic_parameter(void **state)
{
    int32_t k;
    qnav_ctrl_config_t cfg;
    (void)state;
    qnav_ctrl_config_default(&cfg);
    for (k = -32768; k <= 32767; k += (k > -300 && k < 300) || (k > 16000 && k < 16700) ? 1 : 97) {
        char text[200];
        char err[QNAV_POLICY_IO_ERRLEN] = "";
        qnav_policy_t p;
        qnav_policy_t direct;
        qnav_ctrl_t ctrl;
        int file_ok;
        int init_ok;
        (void)snprintf(text, sizeof text,
                       "qnav-policy 1\nkind probabilistic\nqformat Q8.8\nk_goal %ld\n"
                       "k_safe 256\nend\n",
                       (long)k);
        file_ok = parse_str(text, &p, err) == 0;
        qnav_policy_prob_default(&direct);
        direct.u.prob.k_goal = (qnav_q8_8_t)k;
        direct.u.prob.k_safe = 256;
        init_ok = qnav_ctrl_init(&ctrl, &cfg, &direct) == QNAV_OK;
        if (file_ok != init_ok) {
            fail_msg("k_goal %ld: file %s, qnav_ctrl_init %s (%s)", (long)k,
                     file_ok ? "accepted" : "refused", init_ok ? "accepted" : "refused", err);
        }
    }
}

/* ---- the corpus of bad files --------------------------------------------------------- */

static void test_every_bad_file_is_refused_with_its_expected_line_and_message(void **state)
{
    char table[512];
    FILE *f;
    char row[512];
    int rows = 0;
    DIR *d;
    struct dirent *e;
    int files = 0;
    (void)state;
    (void)snprintf(table, sizeof table, "%s/expected.tsv", QNAV_POLICYIO_BAD_DIR);
    f = fopen(table, "r");
    assert_non_null(f);
    while (fgets(row, sizeof row, f) != NULL) {
        char *name;
        char *line;
        char *frag;
        char path[512];
        char prefix[600];
        char err[QNAV_POLICY_IO_ERRLEN] = "";
        qnav_policy_t p;
        row[strcspn(row, "\n")] = '\0';
        if (row[0] == '#' || row[0] == '\0') {
            continue;
        }
        name = strtok(row, "\t");
        line = strtok(NULL, "\t");
        frag = strtok(NULL, "");
        assert_non_null(name);
        assert_non_null(line);
        assert_non_null(frag);
        (void)snprintf(path, sizeof path, "%s/%s", QNAV_POLICYIO_BAD_DIR, name);
        (void)snprintf(prefix, sizeof prefix, "%s:%s: ", path, line);
        if (qnav_policy_read(path, &p, err, sizeof err) != QNAV_POLICY_IO_E_PARSE) {
            fail_msg("%s was accepted", name);
        }
        if (strncmp(err, prefix, strlen(prefix)) != 0 || strstr(err, frag) == NULL) {
            fail_msg("%s: got '%s', want prefix '%s' and '%s'", name, err, prefix, frag);
        }
        assert_null(strchr(err, '\n'));
        rows++;
    }
    fclose(f);
    /* every file in the folder is in the table: none goes untested */
    d = opendir(QNAV_POLICYIO_BAD_DIR);
    assert_non_null(d);
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n > 7 && strcmp(e->d_name + n - 7, ".policy") == 0) {
            files++;
        }
    }
    closedir(d);
    assert_true(rows >= 20);
    assert_int_equal(files, rows);
}

/* The list every message and the tool's help print names each kind once, from the kinds'
 * own table, and a short buffer cuts it safely. */
static void test_kind_list_names_every_kind_once(void **state)
{
    char buf[80];
    char small[8];
    char quoted[40];
    unsigned k;
    size_t named = 0;
    size_t quotes = 0;
    const char *c;
    (void)state;
    assert_ptr_equal(qnav_policy_kind_list(buf, sizeof buf, "'", ", ", " or "), buf);
    for (k = 0; k < 256u; ++k) {
        const char *n = qnav_policy_kind_name((uint8_t)k);
        if (n != NULL) {
            (void)snprintf(quoted, sizeof quoted, "'%s'", n);
            assert_non_null(strstr(buf, quoted));
            ++named;
        }
    }
    for (c = buf; *c != '\0'; ++c) {
        quotes += *c == '\'';
    }
    assert_true(named >= 2);
    assert_int_equal(quotes, 2 * named);
    assert_non_null(strstr(buf, " or "));
    assert_int_equal(strlen(qnav_policy_kind_list(small, sizeof small, "", "|", "|")),
                     sizeof small - 1);
}

static void test_every_status_has_its_own_text(void **state)
{
    static const qnav_policy_io_status_t all[] = {
        QNAV_POLICY_IO_OK,          QNAV_POLICY_IO_E_NULL,  QNAV_POLICY_IO_E_IO,
        QNAV_POLICY_IO_E_PARSE,     QNAV_POLICY_IO_E_INVALID, QNAV_POLICY_IO_E_NAME,
        QNAV_POLICY_IO_E_NOMEM};
    size_t i;
    size_t k;
    (void)state;
    for (i = 0; i < sizeof all / sizeof all[0]; ++i) {
        assert_true(i == 0 ? all[i] == 0 : all[i] < 0);
        for (k = 0; k < i; ++k) {
            assert_string_not_equal(qnav_policy_io_status_str(all[i]),
                                    qnav_policy_io_status_str(all[k]));
        }
    }
    assert_string_equal(qnav_policy_io_status_str((qnav_policy_io_status_t)-99),
                        "unknown policyio status");
}

static void test_missing_file_is_reported_with_its_name(void **state)
{
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    (void)state;
    assert_int_equal(qnav_policy_read("/nonexistent/x.policy", &p, err, sizeof err), QNAV_POLICY_IO_E_IO);
    assert_non_null(strstr(err, "/nonexistent/x.policy: cannot open ("));
    assert_int_equal(qnav_policy_read("/tmp", &p, err, sizeof err), QNAV_POLICY_IO_E_IO);
    assert_non_null(strstr(err, "/tmp: read error ("));
}

static void test_oversized_file_is_refused(void **state)
{
    size_t n = (size_t)QNAV_POLICY_FILE_MAX + 10u;
    char *big = malloc(n);
    char err[QNAV_POLICY_IO_ERRLEN] = "";
    qnav_policy_t p;
    (void)state;
    assert_non_null(big);
    memset(big, '\n', n);
    assert_int_equal(qnav_policy_parse(big, n, "big", &p, err, sizeof err), QNAV_POLICY_IO_E_PARSE);
    assert_non_null(strstr(err, "big:1: file larger than"));
    free(big);
}

/* ---- mutations: never crash, always a policy or one line ----------------------------- */

/* Parse buf[0..len) from an exact-size heap copy; on success the policy must be one that
 * the controller accepts, on failure the message must be one line naming the file. */
static int parse_mutant(const char *buf, size_t len)
{
    char *copy = malloc(len > 0 ? len : 1);
    char err[QNAV_POLICY_IO_ERRLEN];
    qnav_policy_t p;
    int rc;
    assert_non_null(copy);
    if (len > 0) {
        memcpy(copy, buf, len);
    }
    err[0] = '\0';
    rc = qnav_policy_parse(copy, len, "m.policy", &p, err, sizeof err);
    free(copy);
    if (rc == 0) {
        qnav_ctrl_t ctrl;
        qnav_ctrl_config_t cfg;
        qnav_ctrl_config_default(&cfg);
        assert_int_equal(qnav_policy_check(&p, err, sizeof err), 0);
        assert_int_equal(qnav_ctrl_init(&ctrl, &cfg, &p), QNAV_OK);
    } else {
        assert_int_equal(rc, QNAV_POLICY_IO_E_PARSE);
        assert_true(strncmp(err, "m.policy:", 9) == 0);
        assert_true(strlen(err) > 12);
        assert_null(strchr(err, '\n'));
    }
    return rc;
}

static void test_truncating_a_good_file_at_every_byte_never_crashes(void **state)
{
    qnav_policy_t p;
    qnav_policy_meta_t meta;
    char err[QNAV_POLICY_IO_ERRLEN];
    size_t len;
    size_t cut;
    size_t accepted = 0;
    char *text;
    (void)state;
    rng_state = 7;
    qnav_policy_net_zero(&p, 12);
    for (cut = 0; cut < QNAV_NET_WEIGHTS(12); ++cut) {
        *qnav_net_weight(&p.u.net, (uint16_t)cut) = (qnav_q8_8_t)((int)(rng_next() % 5121u) - 2560);
    }
    qnav_policy_meta_clear(&meta);
    assert_int_equal(qnav_policy_meta_set(&meta, "source", "mutation test", err, sizeof err), 0);
    text = render(&p, &meta, "a comment", &len);
    for (cut = 0; cut <= len; ++cut) {
        accepted += parse_mutant(text, cut) == 0;
    }
    /* only cuts inside or after the final "end\n" can still be whole files */
    assert_int_equal(accepted, 2);
    free(text);
}

static void test_flipping_bytes_of_good_files_never_crashes(void **state)
{
    int round;
    size_t changed_but_accepted = 0;
    size_t refused = 0;
    (void)state;
    rng_state = 12345;
    for (round = 0; round < 8; ++round) {
        qnav_policy_t p;
        size_t len;
        size_t i;
        char *text;
        random_policy(&p);
        text = render(&p, NULL, "flip", &len);
        for (i = 0; i < len; ++i) {
            int k;
            for (k = 0; k < 3; ++k) {
                static const unsigned char special[] = {0x00, '\n', '\r', '#', ' ', '-', '9',
                                                        0xFF, 0x7F, 'x'};
                char saved = text[i];
                unsigned char v = (k == 0) ? special[rng_next() % sizeof special]
                                           : (unsigned char)(rng_next() & 0xFFu);
                text[i] = (char)v;
                if (parse_mutant(text, len) == 0) {
                    changed_but_accepted += text[i] != saved;
                } else {
                    refused++;
                }
                text[i] = saved;
            }
        }
        free(text);
    }
    /* most single-byte corruptions are caught; some (a digit in a weight) are not */
    assert_true(refused > changed_but_accepted);
    assert_true(refused > 1000);
}

static void test_random_garbage_never_crashes(void **state)
{
    int i;
    (void)state;
    rng_state = 5;
    for (i = 0; i < 3000; ++i) {
        char buf[300];
        size_t len = (size_t)(rng_next() % sizeof buf);
        size_t k;
        static const char *const words[] = {"qnav-policy 1\n", "kind ", "network\n",
                                            "probabilistic\n", "hidden ", "unit ", "b_out ",
                                            "k_goal ", "k_safe ", "end\n", "meta ", "qformat Q8.8\n",
                                            "1 ", "-32768 ", "\n", "# c\n", "\r\n"};
        size_t used = 0;
        /* half pure noise, half shuffled tokens of the format */
        if (i % 2 == 0) {
            for (k = 0; k < len; ++k) {
                buf[k] = (char)(rng_next() & 0xFFu);
            }
            used = len;
        } else {
            while (used < len) {
                const char *w = words[rng_next() % (sizeof words / sizeof words[0])];
                size_t wl = strlen(w);
                if (used + wl > len) {
                    break;
                }
                memcpy(buf + used, w, wl);
                used += wl;
            }
        }
        (void)parse_mutant(buf, used);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reader_accepts_documented_network_file),
        cmocka_unit_test(test_version_2_file_with_three_inputs_reads_and_writes_back_the_same),
        cmocka_unit_test(test_two_input_network_is_still_written_as_version_1),
        cmocka_unit_test(test_reader_accepts_crlf_line_endings),
        cmocka_unit_test(test_reader_accepts_missing_final_newline_after_end),
        cmocka_unit_test(test_reader_leaves_output_untouched_on_error),
        cmocka_unit_test(test_random_policies_round_trip_exactly_through_text),
        cmocka_unit_test(test_write_then_read_gives_the_same_policy_and_leaves_no_temp_file),
        cmocka_unit_test(test_writer_refuses_invalid_policy_and_keeps_old_file),
        cmocka_unit_test(test_writer_reports_unwritable_directory),
        cmocka_unit_test(test_long_and_multiline_comments_still_round_trip),
        cmocka_unit_test(test_meta_set_refuses_values_that_would_not_round_trip),
        cmocka_unit_test(test_reader_names_the_line_of_each_problem),
        cmocka_unit_test(test_line_of_exactly_the_limit_is_accepted_and_one_more_refused),
        cmocka_unit_test(test_reader_agrees_with_ctrl_init_on_every_probabilistic_parameter),
        cmocka_unit_test(test_every_bad_file_is_refused_with_its_expected_line_and_message),
        cmocka_unit_test(test_every_status_has_its_own_text),
        cmocka_unit_test(test_kind_list_names_every_kind_once),
        cmocka_unit_test(test_missing_file_is_reported_with_its_name),
        cmocka_unit_test(test_oversized_file_is_refused),
        cmocka_unit_test(test_truncating_a_good_file_at_every_byte_never_crashes),
        cmocka_unit_test(test_flipping_bytes_of_good_files_never_crashes),
        cmocka_unit_test(test_random_garbage_never_crashes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
