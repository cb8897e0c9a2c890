/*
 * The software-in-the-loop robot's hardware: qnav_board_hal_t over the Box2D simulator
 * (sonar = the simulated scan, heading = the true heading since the start as an IMU would
 * give it, odometry = wheel encoder counts from the simulated motion, drive = the
 * simulator's command), the pty master as the UART, the wall clock, and a file as the
 * non-volatile storage. With a recorded scan stream instead of the simulator (playback),
 * the sonar replays the recording and the robot does not move. The board core
 * (qnav/board.h) runs on it unchanged.
 */
#ifndef QNAV_NAVBRIDGE_SIL_HAL_H
#define QNAV_NAVBRIDGE_SIL_HAL_H

#include <stddef.h>
#include <stdint.h>

#include "qnav/board_hal.h"
#include "qnav/sim.h"

#define SIL_HAL_NVM_BYTES 4096u   /* like the ATmega128's EEPROM */
#define SIL_HAL_MAX_PLAYBACK 4096 /* scans a playback holds */

typedef struct {
    uint16_t n_sectors;
    qnav_mm_t max_range_mm;
    qnav_mm_t ranges_mm[QNAV_MAX_SECTORS];
} sil_hal_scan_t;

typedef struct {
    qnav_sim_t *sim;              /* NULL in playback */
    int fd;                       /* pty master (non-blocking) */
    int64_t start_ms;             /* wall clock at start, ms */
    uint8_t rx[512];              /* bytes read from the pty, not yet handed out */
    int rx_n, rx_i;
    /* odometry: the start pose, the last pose, wheel travel so far */
    double x0, y0, h0, last_x, last_y, last_h;
    double track_m;               /* wheel separation */
    double um_per_count;
    double left_um, right_um;
    double odo_noise;             /* wheel slip: each step's travel * (1 + p * n), n ~ N(0,1)
                                     per wheel (the simulator's noise level p; 0 = exact) */
    uint64_t rng;                 /* xorshift64 state of that noise (seeded, reproducible) */
    /* the drive */
    qnav_deg_t drive_heading;
    qnav_q1_15_t drive_speed;
    /* storage */
    const char *nvm_path;         /* NULL: RAM only (lost at exit) */
    uint8_t nvm[SIL_HAL_NVM_BYTES];
    /* playback */
    sil_hal_scan_t *playback;     /* NULL: the simulator */
    size_t playback_n, playback_i;
} sil_hal_t;

/* Fill hal over s. s->sim (or s->playback), fd, track_m, um_per_count and nvm_path must
 * be set; the storage file is read now (absent = erased). 0, or -1 with "PATH: problem"
 * in err when the storage file cannot be read or has another size. */
int sil_hal_init(sil_hal_t *s, qnav_board_hal_t *hal, char *err, size_t errlen);

/* Take the simulator's pose as the start of the odometry frame (after qnav_sim_reset). */
void sil_hal_start_odometry(sil_hal_t *s);

/* Wait up to wait_ms for bytes from the pty (they are handed out by uart_read). Returns
 * -1 when the pty was hung up, else 0. */
int sil_hal_wait_rx(sil_hal_t *s, int wait_ms);

/* Read the QNAV_SCAN events of an LCM log into s->playback (allocated; free with
 * sil_hal_free). 0, or -1 with "PATH: problem" in err. */
int sil_hal_load_playback(sil_hal_t *s, const char *path, char *err, size_t errlen);
void sil_hal_free(sil_hal_t *s);

/* A simulator world point (m) in the odometry frame (mm). */
void sil_hal_world_to_odometry(const sil_hal_t *s, double x_m, double y_m, double *x_mm,
                               double *y_mm);

#endif /* QNAV_NAVBRIDGE_SIL_HAL_H */
