/*
 * Tests of the qnav-policy command line: each subcommand's success path and its error
 * paths (exit status 1 for bad input, 2 for bad usage, one line on stderr naming the file
 * and line or the option). The tool is run as a child process with fork/exec; its output
 * goes to files in a private temporary folder.
 */
#define _POSIX_C_SOURCE 200809L

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

#include "qnav/policy_io.h"
#include "test_proc.h"

#ifndef QNAV_POLICY_TOOL
#error "QNAV_POLICY_TOOL must name the qnav-policy binary"
#endif

static char tmpdir[64];
static char out_text[65536];
static char err_text[4096];

static void read_all(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    size_t n = 0;
    if (f != NULL) {
        n = fread(buf, 1, cap - 1, f);
        fclose(f);
    }
    buf[n] = '\0';
}

/* Run qnav-policy with the given arguments (NULL-terminated); returns its exit status
 * and fills out_text / err_text. */
static int run_tool(const char *arg0, ...)
{
    const char *argv[16];
    int argc = 0;
    va_list ap;
    const char *a;
    char outp[128];
    char errp[128];
    pid_t pid;
    int status;
    argv[argc++] = QNAV_POLICY_TOOL;
    va_start(ap, arg0);
    for (a = arg0; a != NULL && argc < 15; a = va_arg(ap, const char *)) {
        argv[argc++] = a;
    }
    va_end(ap);
    argv[argc] = NULL;
    (void)snprintf(outp, sizeof outp, "%s/stdout", tmpdir);
    (void)snprintf(errp, sizeof errp, "%s/stderr", tmpdir);
    pid = qnav_test_spawn(argv, outp, errp);
    assert_true(pid > 0);
    status = qnav_test_wait_exit(pid);
    assert_true(status >= 0 && status < 256); /* exited, not killed by a signal */
    read_all(outp, out_text, sizeof out_text);
    read_all(errp, err_text, sizeof err_text);
    return status;
}

static const char *tmp_path(const char *name)
{
    static char buf[4][256];
    static int k;
    k = (k + 1) % 4;
    (void)snprintf(buf[k], sizeof buf[k], "%s/%s", tmpdir, name);
    return buf[k];
}

/* stderr holds exactly one line that starts with prefix and contains fragment. */
static void assert_one_line_error(const char *prefix, const char *fragment)
{
    size_t n = strlen(err_text);
    if (strncmp(err_text, prefix, strlen(prefix)) != 0 || strstr(err_text, fragment) == NULL ||
        n == 0 || err_text[n - 1] != '\n' || strchr(err_text, '\n') != err_text + n - 1) {
        fail_msg("stderr '%s' is not one line starting '%s' with '%s'", err_text, prefix,
                 fragment);
    }
}

static int setup(void **state)
{
    (void)state;
    return qnav_test_tmpdir_make(tmpdir, sizeof tmpdir, "qnav_cli");
}

static int teardown(void **state)
{
    (void)state;
    return qnav_test_tmpdir_remove(tmpdir);
}

static void test_cli_check_accepts_good_file_silently(void **state)
{
    (void)state;
    assert_int_equal(run_tool("check", QNAV_POLICYIO_GOOD_DIR "/net12.policy", NULL), 0);
    assert_string_equal(err_text, "");
    assert_string_equal(out_text, "");
}

static void test_cli_check_refuses_bad_file_with_file_and_line(void **state)
{
    (void)state;
    assert_int_equal(run_tool("check", QNAV_POLICYIO_BAD_DIR "/unit_three_weights.policy", NULL),
                     2);
    assert_one_line_error(QNAV_POLICYIO_BAD_DIR "/unit_three_weights.policy:6: ",
                          "expected 4 weights");
    assert_int_equal(run_tool("check", tmp_path("missing.policy"), NULL), 2);
    assert_one_line_error(tmp_path("missing.policy"), ": cannot open (");
}

static void test_cli_rejects_unknown_command_and_wrong_arguments_as_usage(void **state)
{
    (void)state;
    assert_int_equal(run_tool("frobnicate", NULL), 2);
    assert_one_line_error("qnav-policy: ", "frobnicate: unknown subcommand (known: check, show, new, header)");
    assert_int_equal(run_tool("--frobnicate", NULL), 2);
    assert_one_line_error("qnav-policy: ", "--frobnicate: unknown option");
    assert_int_equal(run_tool("--version", NULL), 0);
    assert_string_equal(out_text, "qnav-policy (qnav) " QNAV_VERSION "\n");
    assert_int_equal(run_tool("check", NULL), 2);
    assert_one_line_error("qnav-policy: ", "check: expected exactly one FILE");
    assert_int_equal(run_tool(NULL), 2);
    assert_non_null(strstr(err_text, "usage: qnav-policy"));
    assert_int_equal(run_tool("--help", NULL), 0);
    assert_non_null(strstr(out_text, "usage: qnav-policy"));
}

static void test_cli_new_writes_files_that_check_accepts(void **state)
{
    qnav_policy_t p;
    char err[QNAV_POLICY_IO_ERRLEN];
    (void)state;
    assert_int_equal(run_tool("new", "--kind", "probabilistic", tmp_path("p.policy"), NULL), 0);
    assert_int_equal(qnav_policy_read(tmp_path("p.policy"), &p, err, sizeof err), 0);
    assert_int_equal(p.kind, QNAV_POLICY_PROB);
    {
        qnav_policy_t d;
        qnav_policy_prob_default(&d);
        assert_int_equal(p.u.prob.k_goal, d.u.prob.k_goal);
        assert_int_equal(p.u.prob.k_safe, d.u.prob.k_safe);
    }
    assert_int_equal(run_tool("new", "--kind", "network", "--hidden", "5", "--seed", "9",
                              tmp_path("n.policy"), NULL),
                     0);
    assert_int_equal(qnav_policy_read(tmp_path("n.policy"), &p, err, sizeof err), 0);
    assert_int_equal(p.kind, QNAV_POLICY_NET);
    assert_int_equal(p.u.net.hidden, 5);
    assert_true(p.u.net.w_theta[0] >= -512 && p.u.net.w_theta[0] <= 512);
    assert_int_equal(run_tool("check", tmp_path("n.policy"), NULL), 0);
}

static void test_cli_new_is_reproducible_from_its_seed(void **state)
{
    char a[8192];
    char b[8192];
    (void)state;
    assert_int_equal(run_tool("new", "--kind=network", "--seed=3", tmp_path("n.policy"), NULL),
                     0);
    assert_int_equal(run_tool("new", "--seed", "3", "--kind", "network", tmp_path("n2.policy"),
                              NULL),
                     0);
    read_all(tmp_path("n.policy"), a, sizeof a);
    read_all(tmp_path("n2.policy"), b, sizeof b);
    assert_string_equal(a, b);
    assert_non_null(strstr(a, "hidden 12\n"));
    assert_int_equal(run_tool("new", "--kind", "network", "--seed", "4", tmp_path("n2.policy"),
                              NULL),
                     0);
    read_all(tmp_path("n2.policy"), b, sizeof b);
    assert_true(strcmp(a, b) != 0);
}

static void test_cli_new_refuses_bad_options(void **state)
{
    (void)state;
    assert_int_equal(run_tool("new", "--kind", "tree", tmp_path("x.policy"), NULL), 2);
    assert_one_line_error("qnav-policy: ", "--kind 'tree'");
    assert_int_equal(run_tool("new", "--kind", "network", "--hidden", "33", tmp_path("x.policy"),
                              NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "--hidden '33' must be an integer in 1..32");
    assert_int_equal(run_tool("new", "--kind", "network", "--hidden", "4x", tmp_path("x.policy"),
                              NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "--hidden '4x'");
    assert_int_equal(run_tool("new", "--kind", "network", "--seed", "-1", tmp_path("x.policy"),
                              NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "--seed '-1'");
    assert_int_equal(run_tool("new", "--kind", "probabilistic", "--hidden", "3",
                              tmp_path("x.policy"), NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "apply to --kind network only");
    assert_int_equal(run_tool("new", "--colour", "red", tmp_path("x.policy"), NULL), 2);
    assert_one_line_error("qnav-policy: ", "unknown option '--colour'");
    assert_int_equal(run_tool("new", "--kind", NULL), 2);
    assert_one_line_error("qnav-policy: ", "option '--kind' needs a value");
    assert_int_equal(run_tool("new", "--kind", "network", NULL), 2);
    assert_one_line_error("qnav-policy: ", "expected exactly one OUT file");
    assert_int_equal(access(tmp_path("x.policy"), F_OK), -1);
    assert_int_equal(run_tool("new", "--kind", "network", "/nonexistent_dir/x.policy", NULL), 1);
    assert_one_line_error("/nonexistent_dir/x.policy: ", "cannot create");
}

static void test_cli_show_prints_weights_as_real_numbers(void **state)
{
    (void)state;
    assert_int_equal(run_tool("show", QNAV_POLICYIO_GOOD_DIR "/net12.policy", NULL), 0);
    assert_non_null(strstr(out_text, "kind: network\nhidden: 12\n"));
    /* unit 0 of the file: -1536 1536 0 2048 raw */
    assert_non_null(strstr(out_text, "   0           -6.0            6.0            0.0            8.0\n"));
    assert_non_null(strstr(out_text, "b_out: -4.0\n"));
    assert_int_equal(run_tool("show", QNAV_POLICYIO_GOOD_DIR "/prob.policy", NULL), 0);
    assert_non_null(strstr(out_text, "k_goal: 2.0 "));
    assert_non_null(strstr(out_text, "k_safe: 6.0 "));
    assert_int_equal(run_tool("show", QNAV_POLICYIO_BAD_DIR "/hidden_zero.policy", NULL), 2);
    assert_one_line_error(QNAV_POLICYIO_BAD_DIR "/hidden_zero.policy:4: ", "hidden 0");
    assert_string_equal(out_text, "");
}

static void test_cli_header_writes_commented_header(void **state)
{
    char h[65536];
    (void)state;
    assert_int_equal(run_tool("header", "--mode", "network", "--name", "my_net",
                              QNAV_POLICYIO_GOOD_DIR "/net12.policy", tmp_path("h.h"), NULL),
                     0);
    read_all(tmp_path("h.h"), h, sizeof h);
    assert_non_null(strstr(h, " * Source: " QNAV_POLICYIO_GOOD_DIR "/net12.policy\n"));
    assert_non_null(strstr(h, " * Command: qnav-policy header --mode network --name my_net "));
    assert_non_null(strstr(h, "static const qnav_policy_t my_net = {"));
    assert_non_null(strstr(h, ".w_theta = {-1536, "));
    assert_non_null(strstr(h, "#if QNAV_MAX_HIDDEN < 12\n"));
    assert_int_equal(run_tool("header", "--mode", "table", "--name", "my_table",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", tmp_path("t.h"), NULL),
                     0);
    read_all(tmp_path("t.h"), h, sizeof h);
    assert_non_null(strstr(h, "#if QNAV_DIST_LEVELS != 32"));
    assert_non_null(
        strstr(h, "static QNAV_FLASH const qnav_qkey_t my_table[QNAV_QTABLE_ENTRIES] = {"));
}

static void test_cli_header_refuses_bad_requests_without_writing(void **state)
{
    (void)state;
    assert_int_equal(run_tool("header", "--mode", "probabilistic", "--name", "p",
                              QNAV_POLICYIO_GOOD_DIR "/net12.policy", tmp_path("x.h"), NULL),
                     2);
    assert_one_line_error(QNAV_POLICYIO_GOOD_DIR "/net12.policy: ",
                          "kind is network but --mode probabilistic");
    assert_int_equal(run_tool("header", "--mode", "network", "--name", "p",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", tmp_path("x.h"), NULL),
                     2);
    assert_one_line_error(QNAV_POLICYIO_GOOD_DIR "/prob.policy: ",
                          "kind is probabilistic but --mode network");
    assert_int_equal(run_tool("header", "--mode", "table", "--name", "p",
                              QNAV_POLICYIO_BAD_DIR "/missing_end.policy", tmp_path("x.h"), NULL),
                     2);
    assert_one_line_error(QNAV_POLICYIO_BAD_DIR "/missing_end.policy:8: ", "truncated");
    assert_int_equal(run_tool("header", "--mode", "table", "--name", "2fast",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", tmp_path("x.h"), NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "--name must be a C identifier");
    assert_int_equal(run_tool("header", "--mode", "table", "--name", "int",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", tmp_path("x.h"), NULL),
                     2);
    assert_int_equal(run_tool("header", "--mode", "lookup", "--name", "p",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", tmp_path("x.h"), NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "--mode must be probabilistic, network or table");
    assert_int_equal(run_tool("header", "--mode", "table", "--name", "p",
                              QNAV_POLICYIO_GOOD_DIR "/prob.policy", NULL),
                     2);
    assert_one_line_error("qnav-policy: ", "expected IN and OUT.h");
    assert_int_equal(access(tmp_path("x.h"), F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cli_check_accepts_good_file_silently),
        cmocka_unit_test(test_cli_check_refuses_bad_file_with_file_and_line),
        cmocka_unit_test(test_cli_rejects_unknown_command_and_wrong_arguments_as_usage),
        cmocka_unit_test(test_cli_new_writes_files_that_check_accepts),
        cmocka_unit_test(test_cli_new_is_reproducible_from_its_seed),
        cmocka_unit_test(test_cli_new_refuses_bad_options),
        cmocka_unit_test(test_cli_show_prints_weights_as_real_numbers),
        cmocka_unit_test(test_cli_header_writes_commented_header),
        cmocka_unit_test(test_cli_header_refuses_bad_requests_without_writing),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
