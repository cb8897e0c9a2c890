/*
 * The software-in-the-loop robot's hardware (sil_hal.h).
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include "sil_hal.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <lcm/eventlog.h>

#include "qnav/clock.h"
#include "qnav_scan_t.h"
#include "serial.h"

static double wrap_rad(double a)
{
    while (a > M_PI) {
        a -= 2.0 * M_PI;
    }
    while (a <= -M_PI) {
        a += 2.0 * M_PI;
    }
    return a;
}

static uint32_t hal_millis(void *ctx)
{
    return (uint32_t)(qnav_mono_ms() - ((sil_hal_t *)ctx)->start_ms);
}

static uint16_t hal_sonar(void *ctx, qnav_mm_t *ranges, uint16_t max)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    static qnav_sim_scan_t scan; /* one robot per process; too large for the stack */
    const qnav_mm_t *src;
    uint16_t n;
    if (s->playback != NULL) {
        const sil_hal_scan_t *p =
            &s->playback[s->playback_i < s->playback_n ? s->playback_i : s->playback_n - 1];
        src = p->ranges_mm;
        n = p->n_sectors;
    } else {
        if (qnav_sim_scan(s->sim, &scan) != QNAV_SIM_OK) {
            return 0;
        }
        src = scan.ranges_mm;
        n = scan.n_sectors;
    }
    n = n < max ? n : max;
    memcpy(ranges, src, n * sizeof ranges[0]);
    return n;
}

static qnav_cdeg_t hal_heading(void *ctx)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    qnav_sim_state_t st;
    double cdeg;
    if (s->sim == NULL || qnav_sim_state(s->sim, &st) != QNAV_SIM_OK) {
        return 0;
    }
    cdeg = wrap_rad(st.heading_rad - s->h0) * 18000.0 / M_PI;
    return (qnav_cdeg_t)(cdeg >= 17999.5 ? -18000 : lround(cdeg));
}

/* A standard normal sample (Box-Muller over xorshift64). */
static double gauss(uint64_t *state)
{
    double u1, u2;
    uint64_t x = *state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    u1 = ((double)(x >> 11) + 1.0) / 9007199254740993.0;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    u2 = (double)(x >> 11) / 9007199254740992.0;
    *state = x;
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}

/* Wheel travel since the last call from the simulated motion: the displacement along the
 * mid-step heading plus the turn times half the track on each side, each wheel's slipping
 * by the noise level. */
static void hal_odometry(void *ctx, int32_t *left, int32_t *right)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    qnav_sim_state_t st;
    if (s->sim != NULL && qnav_sim_state(s->sim, &st) == QNAV_SIM_OK) {
        double dh = wrap_rad(st.heading_rad - s->last_h);
        double hm = s->last_h + dh / 2.0;
        double ds = (st.x_m - s->last_x) * cos(hm) + (st.y_m - s->last_y) * sin(hm);
        double sl = 1.0, sr = 1.0;
        if (s->odo_noise > 0.0) {
            sl += s->odo_noise * gauss(&s->rng);
            sr += s->odo_noise * gauss(&s->rng);
        }
        s->left_um += (ds - dh * s->track_m / 2.0) * sl * 1e6;
        s->right_um += (ds + dh * s->track_m / 2.0) * sr * 1e6;
        s->last_x = st.x_m;
        s->last_y = st.y_m;
        s->last_h = st.heading_rad;
    }
    *left = (int32_t)(int64_t)floor(s->left_um / s->um_per_count);
    *right = (int32_t)(int64_t)floor(s->right_um / s->um_per_count);
}

/* The simulator mixes the decision with its own wheels' speed (the profile's [drive] model),
 * so the board's encoder-measured rolling speed is not needed here. */
static void hal_drive(void *ctx, qnav_deg_t heading, qnav_q1_15_t speed, qnav_q1_15_t rolling)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    (void)rolling;
    s->drive_heading = heading;
    s->drive_speed = speed;
}

static int16_t hal_uart_read(void *ctx)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    if (s->rx_i >= s->rx_n) {
        ssize_t n = read(s->fd, s->rx, sizeof s->rx);
        s->rx_i = 0;
        s->rx_n = n > 0 ? (int)n : 0;
        if (s->rx_n == 0) {
            return -1;
        }
    }
    return s->rx[s->rx_i++];
}

static void hal_uart_write(void *ctx, const uint8_t *bytes, uint16_t n)
{
    /* a port nobody reads drops the frame, like a UART with no listener */
    (void)qnav_serial_write_all(((sil_hal_t *)ctx)->fd, bytes, n);
}

static uint8_t hal_nvm_read(void *ctx, uint16_t addr, uint8_t *out, uint16_t n)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    if ((uint32_t)addr + n > SIL_HAL_NVM_BYTES) {
        return 0;
    }
    memcpy(out, &s->nvm[addr], n);
    return 1;
}

/* Written through to the file at once, so that a killed robot keeps what it wrote. */
static uint8_t hal_nvm_write(void *ctx, uint16_t addr, const uint8_t *bytes, uint16_t n)
{
    sil_hal_t *s = (sil_hal_t *)ctx;
    int fd;
    int ok;
    if ((uint32_t)addr + n > SIL_HAL_NVM_BYTES) {
        return 0;
    }
    memcpy(&s->nvm[addr], bytes, n);
    if (s->nvm_path == NULL) {
        return 1;
    }
    fd = open(s->nvm_path, O_WRONLY | O_CREAT, 0644);
    if (fd < 0) {
        return 0;
    }
    ok = pwrite(fd, bytes, n, (off_t)addr) == (ssize_t)n && fsync(fd) == 0;
    close(fd);
    return (uint8_t)ok;
}

int sil_hal_init(sil_hal_t *s, qnav_board_hal_t *hal, char *err, size_t errlen)
{
    memset(s->nvm, 0xFF, sizeof s->nvm);
    s->rx_n = s->rx_i = 0;
    s->start_ms = qnav_mono_ms();
    if (s->nvm_path != NULL) {
        FILE *f = fopen(s->nvm_path, "rb");
        if (f != NULL) {
            size_t got = fread(s->nvm, 1, sizeof s->nvm, f);
            int extra = fgetc(f);
            fclose(f);
            if (got != sizeof s->nvm || extra != EOF) {
                snprintf(err, errlen, "--nvm %s: not a %u-byte storage file of this robot",
                         s->nvm_path, SIL_HAL_NVM_BYTES);
                return -1;
            }
        } else if (errno != ENOENT) {
            snprintf(err, errlen, "--nvm %s: %s", s->nvm_path, strerror(errno));
            return -1;
        } else {
            /* a new store: an erased EEPROM, all 0xFF */
            int fd = open(s->nvm_path, O_WRONLY | O_CREAT | O_EXCL, 0644);
            if (fd < 0 || write(fd, s->nvm, sizeof s->nvm) != (ssize_t)sizeof s->nvm) {
                snprintf(err, errlen, "--nvm %s: %s", s->nvm_path, strerror(errno));
                if (fd >= 0) {
                    close(fd);
                }
                return -1;
            }
            close(fd);
        }
    }
    memset(hal, 0, sizeof *hal);
    hal->ctx = s;
    hal->millis = hal_millis;
    hal->sonar_read = hal_sonar;
    hal->heading_cdeg = hal_heading;
    hal->odometry_read = hal_odometry;
    hal->drive = hal_drive;
    hal->uart_read = hal_uart_read;
    hal->uart_write = hal_uart_write;
    hal->nvm_read = hal_nvm_read;
    hal->nvm_write = hal_nvm_write;
    hal->nvm_bytes = SIL_HAL_NVM_BYTES;
    return 0;
}

void sil_hal_start_odometry(sil_hal_t *s)
{
    qnav_sim_state_t st;
    if (s->sim != NULL && qnav_sim_state(s->sim, &st) == QNAV_SIM_OK) {
        s->x0 = s->last_x = st.x_m;
        s->y0 = s->last_y = st.y_m;
        s->h0 = s->last_h = st.heading_rad;
    }
    s->left_um = s->right_um = 0.0;
}

int sil_hal_wait_rx(sil_hal_t *s, int wait_ms)
{
    struct pollfd p = {s->fd, POLLIN, 0};
    if (s->rx_i < s->rx_n) {
        return 0;
    }
    if (poll(&p, 1, wait_ms < 0 ? 0 : wait_ms) > 0 && (p.revents & POLLHUP) &&
        !(p.revents & POLLIN)) {
        return -1;
    }
    return 0;
}

int sil_hal_load_playback(sil_hal_t *s, const char *path, char *err, size_t errlen)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    if (log == NULL) {
        snprintf(err, errlen, "--playback %s: %s", path, strerror(errno));
        return -1;
    }
    s->playback = calloc(SIL_HAL_MAX_PLAYBACK, sizeof *s->playback);
    s->playback_n = s->playback_i = 0;
    if (s->playback == NULL) {
        lcm_eventlog_destroy(log);
        snprintf(err, errlen, "--playback %s: out of memory", path);
        return -1;
    }
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL &&
           s->playback_n < SIL_HAL_MAX_PLAYBACK) {
        qnav_scan_t m;
        if (strcmp(ev->channel, "QNAV_SCAN") == 0 &&
            qnav_scan_t_decode(ev->data, 0, ev->datalen, &m) >= 0) {
            sil_hal_scan_t *p = &s->playback[s->playback_n++];
            int k;
            p->n_sectors = (uint16_t)(m.n_sectors < 1 || m.n_sectors > QNAV_MAX_SECTORS
                                          ? 1 : m.n_sectors);
            p->max_range_mm = (qnav_mm_t)m.max_range_mm;
            for (k = 0; k < p->n_sectors; ++k) {
                p->ranges_mm[k] = (qnav_mm_t)m.ranges_mm[k];
            }
            qnav_scan_t_decode_cleanup(&m);
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    if (s->playback_n == 0) {
        snprintf(err, errlen, "--playback %s: no QNAV_SCAN events in this LCM log", path);
        sil_hal_free(s);
        return -1;
    }
    return 0;
}

void sil_hal_free(sil_hal_t *s)
{
    free(s->playback);
    s->playback = NULL;
    s->playback_n = 0;
}

void sil_hal_world_to_odometry(const sil_hal_t *s, double x_m, double y_m, double *x_mm,
                               double *y_mm)
{
    double dx = x_m - s->x0;
    double dy = y_m - s->y0;
    *x_mm = (dx * cos(s->h0) + dy * sin(s->h0)) * 1000.0;
    *y_mm = (-dx * sin(s->h0) + dy * cos(s->h0)) * 1000.0;
}
