/*
 * The fake board of the end-to-end tests (fakeboard.h): pty, child process, link frames.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include "fakeboard.h"
#include "test_proc.h"
#include "qnav/clock.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

int64_t fakeboard_ms(void)
{
    return qnav_mono_ms();
}

int fakeboard_start(fakeboard_t *fb, const char *exe, const char *dir,
                    const char *const *args)
{
    struct termios tio;
    const char *argv[32];
    int n = 0, k;
    char *name;

    memset(fb, 0, sizeof *fb);
    fb->master = posix_openpt(O_RDWR | O_NOCTTY);
    if (fb->master < 0 || grantpt(fb->master) != 0 || unlockpt(fb->master) != 0) {
        return -1;
    }
    name = ptsname(fb->master);
    if (name == NULL) {
        return -1;
    }
    snprintf(fb->slave_path, sizeof fb->slave_path, "%s", name);
    fb->slave_keep = open(fb->slave_path, O_RDWR | O_NOCTTY);
    if (fb->slave_keep < 0 || tcgetattr(fb->slave_keep, &tio) != 0) {
        return -1;
    }
    cfmakeraw(&tio); /* no echo from the start: navbridge sets the same again */
    tcsetattr(fb->slave_keep, TCSANOW, &tio);
    fcntl(fb->master, F_SETFL, fcntl(fb->master, F_GETFL) | O_NONBLOCK);
    qnav_link_tx_init(&fb->tx);
    qnav_link_rx_init(&fb->rx);
    snprintf(fb->stderr_path, sizeof fb->stderr_path, "%s/navbridge.%d.err", dir,
             (int)fakeboard_ms() % 100000);

    argv[n++] = exe;
    argv[n++] = "--device";
    argv[n++] = fb->slave_path;
    for (k = 0; args != NULL && args[k] != NULL && n < 30; ++k) {
        argv[n++] = args[k];
    }
    argv[n] = NULL;
    fb->pid = fork();
    if (fb->pid < 0) {
        return -1;
    }
    if (fb->pid == 0) {
        int e = open(fb->stderr_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (e >= 0) {
            dup2(e, 2);
        }
        close(fb->master);
        close(fb->slave_keep);
        execv(exe, (char *const *)argv);
        _exit(127);
    }
    return 0;
}

int fakeboard_send(fakeboard_t *fb, uint8_t msg_id, const uint8_t *payload, uint16_t len)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t n = qnav_link_encode(&fb->tx, msg_id, payload, len, wire, sizeof wire);
    int32_t done = 0;
    if (n <= 0) {
        return -1;
    }
    while (done < n) {
        ssize_t w = write(fb->master, wire + done, (size_t)(n - done));
        if (w > 0) {
            done += (int32_t)w;
        } else if (w < 0 && errno != EAGAIN && errno != EINTR) {
            return -1;
        }
    }
    return 0;
}

int fakeboard_wait(fakeboard_t *fb, uint8_t msg_id, int timeout_ms, uint8_t *out,
                   uint16_t cap, uint16_t *seq)
{
    int64_t end = fakeboard_ms() + timeout_ms;
    for (;;) {
        /* bytes already read come first: frames arrive back to back */
        while (fb->pend_i < fb->pend_n) {
            qnav_link_frame_t f;
            if (qnav_link_rx_feed(&fb->rx, fb->pend[fb->pend_i++], &f) &&
                (msg_id == 0 || f.msg_id == msg_id)) {
                uint16_t n = f.len < cap ? f.len : cap;
                memcpy(out, f.payload, n);
                if (seq != NULL) {
                    *seq = f.seq;
                }
                fb->last_id = f.msg_id;
                return f.len;
            }
        }
        int64_t left = end - fakeboard_ms();
        struct pollfd p;
        ssize_t r;
        if (left <= 0) {
            return -1;
        }
        p.fd = fb->master;
        p.events = POLLIN;
        p.revents = 0;
        if (poll(&p, 1, (int)left) <= 0) {
            continue;
        }
        r = read(fb->master, fb->pend, sizeof fb->pend);
        fb->pend_i = 0;
        fb->pend_n = r > 0 ? (int)r : 0;
    }
}

int fakeboard_signal_and_wait(fakeboard_t *fb, int sig, int timeout_ms)
{
    int64_t end = fakeboard_ms() + timeout_ms;
    int status = 0;
    if (fb->pid <= 0) {
        return -1;
    }
    if (sig != 0) {
        kill(fb->pid, sig);
    }
    while (fakeboard_ms() < end) {
        pid_t w = waitpid(fb->pid, &status, WNOHANG);
        if (w == fb->pid) {
            fb->pid = 0;
            if (WIFEXITED(status)) {
                return WEXITSTATUS(status);
            }
            return 256 + WTERMSIG(status);
        }
        usleep(5000);
    }
    kill(fb->pid, SIGKILL);
    waitpid(fb->pid, &status, 0);
    fb->pid = 0;
    return -1;
}

void fakeboard_close(fakeboard_t *fb)
{
    if (fb->pid > 0) {
        (void)fakeboard_signal_and_wait(fb, SIGKILL, 2000);
    }
    if (fb->master >= 0) {
        close(fb->master);
    }
    if (fb->slave_keep >= 0) {
        close(fb->slave_keep);
    }
    fb->master = -1;
    fb->slave_keep = -1;
}

int wait_exit_within(pid_t pid, int timeout_ms)
{
    int64_t end = fakeboard_ms() + timeout_ms;
    int status = 0;
    while (fakeboard_ms() < end) {
        if (waitpid(pid, &status, WNOHANG) == pid) {
            return WIFEXITED(status) ? WEXITSTATUS(status) : 256 + WTERMSIG(status);
        }
        usleep(5000);
    }
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    return -1;
}

int run_program(const char *const *argv, const char *out_path, const char *err_path)
{
    pid_t pid = qnav_test_spawn(argv, out_path, err_path);
    return pid < 0 ? -1 : qnav_test_wait_exit(pid);
}

int read_text(const char *path, char *buf, int cap)
{
    FILE *f = fopen(path, "r");
    size_t n;
    if (f == NULL) {
        return -1;
    }
    n = fread(buf, 1, (size_t)cap - 1u, f);
    buf[n] = '\0';
    fclose(f);
    return (int)n;
}
