/*
 * A fake robot board for end-to-end tests: it owns the master side of a pseudo-terminal,
 * starts the real navbridge program on the slave side, and speaks the link codec: send
 * scans and heartbeats, wait for the frames navbridge answers with.
 */
#ifndef QNAV_TESTS_FAKEBOARD_H
#define QNAV_TESTS_FAKEBOARD_H

#include <stdint.h>
#include <sys/types.h>

#include "qnav/link.h"

typedef struct {
    int master;                 /* board side of the pty */
    int slave_keep;             /* slave kept open so the pty survives navbridge's exit */
    char slave_path[128];
    pid_t pid;                  /* navbridge, 0 when not running */
    char stderr_path[256];      /* navbridge's stderr */
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    uint8_t pend[4096];         /* bytes read but not yet fed to rx */
    int pend_n, pend_i;
    uint8_t last_id;            /* message id of the frame fakeboard_wait returned */
} fakeboard_t;

/* Open a pty and start navbridge --device <slave> with the extra args (NULL-ended).
 * Returns 0 or -1. */
int fakeboard_start(fakeboard_t *fb, const char *exe, const char *dir,
                    const char *const *args);

/* Send one framed message; 0 or -1. */
int fakeboard_send(fakeboard_t *fb, uint8_t msg_id, const uint8_t *payload, uint16_t len);

/* Wait up to timeout_ms for an accepted frame with id msg_id (0 = any); copies the payload
 * into out (cap bytes). Returns the payload length, or -1 on timeout. *seq gets its
 * sequence number when seq is not NULL. */
int fakeboard_wait(fakeboard_t *fb, uint8_t msg_id, int timeout_ms, uint8_t *out,
                   uint16_t cap, uint16_t *seq);

/* Send a signal to navbridge and wait for it to exit (up to timeout_ms). Returns its exit
 * status (0..255), 256 + signal if killed by one, or -1 on timeout (then it is killed). */
int fakeboard_signal_and_wait(fakeboard_t *fb, int sig, int timeout_ms);

/* Close the pty (navbridge must have exited). */
void fakeboard_close(fakeboard_t *fb);

/* Monotonic milliseconds. */
int64_t fakeboard_ms(void);

/* Wait up to timeout_ms for pid to exit; its status (0..255, 256 + signal), or -1 after
 * killing it when it did not exit in time. */
int wait_exit_within(pid_t pid, int timeout_ms);

/* Run a program to completion, stdout and stderr into files; returns exit status or -1. */
int run_program(const char *const *argv, const char *out_path, const char *err_path);

/* Read a whole small text file into buf (NUL-terminated); number of bytes or -1. */
int read_text(const char *path, char *buf, int cap);

#endif /* QNAV_TESTS_FAKEBOARD_H */
