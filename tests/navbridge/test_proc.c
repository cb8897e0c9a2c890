/*
 * Child processes and scratch folders for the process-level tests (test_proc.h).
 */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE
#include "test_proc.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

pid_t qnav_test_spawn(const char *const *argv, const char *out, const char *err)
{
    /* the files are emptied here, before the child exists: a caller that then waits for a
     * line in them never reads what an earlier child wrote to the same path */
    int fo = open(out, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    int fe = open(err, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    pid_t pid = -1;
    if (fo >= 0 && fe >= 0) {
        fflush(NULL);
        pid = fork();
        if (pid == 0) {
            if (dup2(fo, STDOUT_FILENO) < 0 || dup2(fe, STDERR_FILENO) < 0) {
                _exit(126);
            }
            execv(argv[0], (char *const *)argv);
            _exit(127);
        }
    }
    if (fo >= 0) {
        close(fo);
    }
    if (fe >= 0) {
        close(fe);
    }
    return pid;
}

int qnav_test_wait_exit(pid_t pid)
{
    int st = 0;
    if (waitpid(pid, &st, 0) != pid) {
        return -1;
    }
    return WIFEXITED(st) ? WEXITSTATUS(st) : 256 + WTERMSIG(st);
}

int qnav_test_wait_path(const char *path, int timeout_ms)
{
    struct stat sb;
    int waited;
    for (waited = 0; lstat(path, &sb) != 0; waited += 20) {
        if (waited >= timeout_ms) {
            return -1;
        }
        usleep(20000);
    }
    return 0;
}

int qnav_test_wait_text(const char *path, const char *needle, int timeout_ms)
{
    static char buf[65536];
    int waited;
    for (waited = 0;; waited += 20) {
        FILE *f = fopen(path, "r");
        if (f != NULL) {
            size_t n = fread(buf, 1, sizeof buf - 1, f);
            fclose(f);
            buf[n] = '\0';
            if (strstr(buf, needle) != NULL) {
                return 0;
            }
        }
        if (waited >= timeout_ms) {
            return -1;
        }
        usleep(20000);
    }
}

int qnav_test_write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wx");
    int ok;
    if (f == NULL) {
        return -1;
    }
    ok = fputs(text, f) >= 0;
    return (fclose(f) == 0 && ok) ? 0 : -1;
}

/* The whole small file at path into buf (NUL-terminated); its length, or -1. */
static long read_small(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "r");
    size_t n;
    if (f == NULL) {
        return -1;
    }
    n = fread(buf, 1, cap - 1, f);
    fclose(f);
    buf[n] = '\0';
    return (long)n;
}

int qnav_test_link_refused(const char *const *argv, const char *path, const char *dir)
{
    static const char notes[] = "the user's notes\n";
    char out[512], err[512], text[1024];
    int status;
    pid_t pid;
    snprintf(out, sizeof out, "%s/refuse.out", dir);
    snprintf(err, sizeof err, "%s/refuse.err", dir);
    if (qnav_test_write_text(path, notes) != 0) {
        fprintf(stderr, "link_refused: cannot write %s\n", path);
        return -1;
    }
    pid = qnav_test_spawn(argv, out, err);
    status = pid > 0 ? qnav_test_wait_exit(pid) : -1;
    if (status != 2) {
        fprintf(stderr, "link_refused: %s exited %d, not 2\n", argv[0], status);
        return -1;
    }
    if (read_small(path, text, sizeof text) < 0 || strcmp(text, notes) != 0) {
        fprintf(stderr, "link_refused: %s was changed\n", path);
        return -1;
    }
    if (read_small(err, text, sizeof text) < 0 || strstr(text, "refusing to replace it") == NULL) {
        fprintf(stderr, "link_refused: no refusal on stderr\n");
        return -1;
    }
    return 0;
}

int qnav_test_tmpdir_make(char *dir, size_t len, const char *prefix)
{
    int n = snprintf(dir, len, "/tmp/%s.XXXXXX", prefix);
    if (n < 0 || (size_t)n >= len) {
        return -1;
    }
    return mkdtemp(dir) == NULL ? -1 : 0;
}

int qnav_test_tmpdir_remove(const char *dir)
{
    char cmd[600];
    int n = snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (n < 0 || (size_t)n >= sizeof cmd) {
        return -1;
    }
    return system(cmd) == 0 ? 0 : -1;
}
