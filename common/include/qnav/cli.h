/*
 * The command-line conventions shared by qnav's C programs (navbridge, qnav-sil-robot,
 * qnav-simavr-board, qnav-policy); docs/cli.md. Exit statuses: 0 success, 1 failure at run
 * time, 2 bad usage or bad input. `--version` prints one line: "PROG (qnav) VERSION".
 */
#ifndef QNAV_CLI_H
#define QNAV_CLI_H

#ifndef QNAV_VERSION
#error "QNAV_VERSION is set by the qnav::cli target (from the VERSION file)"
#endif

#define QNAV_EXIT_OK 0
#define QNAV_EXIT_FAILURE 1
#define QNAV_EXIT_USAGE 2

/* The --version line of program prog (a string literal). */
#define QNAV_CLI_VERSION_LINE(prog) prog " (qnav) " QNAV_VERSION "\n"

#endif
