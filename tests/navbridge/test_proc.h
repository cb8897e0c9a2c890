/*
 * Child processes and scratch folders for the tests that run qnav programs (navbridge, the
 * SIL robot, the simavr board, qnav-policy): start one with its output in files, wait for
 * its exit status or for the pty link it makes, make and remove a private folder under /tmp.
 */
#ifndef QNAV_TEST_PROC_H
#define QNAV_TEST_PROC_H

#include <stddef.h>
#include <sys/types.h>

/* The limit of every wait for an event in these tests (a line printed, a process's exit),
 * ms: far above any normal run (a few seconds idle), so a loaded machine makes a test
 * slower, not red; it only ends a run that is broken. */
#define QNAV_TEST_WAIT_MS 120000

/* Run argv (argv[0] a path, null-terminated) with stdout and stderr sent to the files
 * out and err, both emptied before the child starts. Returns the child's pid, or -1. */
pid_t qnav_test_spawn(const char *const *argv, const char *out, const char *err);

/* Wait for pid: its exit status, 256 + signal number if a signal ended it, -1 on error. */
int qnav_test_wait_exit(pid_t pid);

/* Wait up to timeout_ms for path to exist (the pty link a child makes once it is up),
 * checking every 20 ms. 0, or -1 when it did not appear. */
int qnav_test_wait_path(const char *path, int timeout_ms);

/* Wait up to timeout_ms for the file at path to contain needle (a line a child prints
 * once something happened), checking every 20 ms. 0, or -1 when it did not appear. */
int qnav_test_wait_text(const char *path, const char *needle, int timeout_ms);

/* Write text to a new file at path (a user's file that a program must not touch). 0/-1. */
int qnav_test_write_text(const char *path, const char *text);

/* The --link rule of the board programs on a user's file: writes a file at path, runs argv
 * (whose --link is path; output to dir/refuse.out and dir/refuse.err) and checks that it
 * exits 2, says "refusing to replace it" and leaves the file as it was. 0 when all hold,
 * else -1 with the failed check on stderr. */
int qnav_test_link_refused(const char *const *argv, const char *path, const char *dir);

/* Make a fresh folder /tmp/<prefix>.XXXXXX into dir (len bytes). 0 or -1. */
int qnav_test_tmpdir_make(char *dir, size_t len, const char *prefix);

/* Remove the folder and everything in it. 0 or -1. */
int qnav_test_tmpdir_remove(const char *dir);

#endif
