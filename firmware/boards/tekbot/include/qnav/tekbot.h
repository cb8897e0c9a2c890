/*
 * The TekBot board application: a 10 Hz loop that reads the sonar and heading, talks to
 * navbridge over the serial link and drives the two motors. In onboard mode it runs
 * libqnav itself (the hand-tuned policy until a policy is uploaded); in offboard mode it
 * sends scans and applies navbridge's commands. The motors stop whenever the link goes
 * quiet, a stop is commanded, or there is no goal. Hardware comes in through
 * qnav_board_hal_t, so the same code runs on the ATmega128 and in host tests.
 *
 * Use: qnav_tekbot_config_default() -> edit -> qnav_tekbot_init() -> call
 * qnav_tekbot_poll() as often as possible (it drains the UART and runs a tick every
 * tick_ms).
 */
#ifndef QNAV_TEKBOT_H
#define QNAV_TEKBOT_H

#include <stdint.h>

#include "qnav/board_hal.h"
#include "qnav/ctrl.h"
#include "qnav/nav.h"
#include "qnav/link.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    QNAV_TEKBOT_OK = 0,
    QNAV_TEKBOT_E_NULL = -1,     /* a required pointer or HAL function was null */
    QNAV_TEKBOT_E_CONFIG = -2,   /* a config field is out of range */
    QNAV_TEKBOT_E_CTRL = -3      /* no such controller, or it refused the default policy */
} qnav_tekbot_status_t;

typedef struct {
    uint16_t n_sectors;          /* sonar sectors the HAL delivers, 1..QNAV_LINK_MAX_SECTORS */
    qnav_mm_t max_range_mm;      /* sonar maximum range, mm (> 0) */
    uint16_t tick_ms;            /* control period, ms (100 = 10 Hz) */
    uint16_t link_timeout_ms;    /* motors stop after this long without a good frame, ms */
    qnav_deg_t spin_deg;         /* at or beyond this |heading| the robot turns in place,
                                    deg (1..180) */
    qnav_mm_t body_radius_mm;    /* centre to the farthest point of the body, mm: the
                                    controller's obstacle enlargement (docs/architecture.md) */
    qnav_mm_t safety_mm;         /* safety distance added to the radius, mm */
    qnav_mm_t sonar_offset_mm;   /* centre to the transducers, mm (ranges start there) */
    uint16_t v_max_mm_s;         /* speed at full command, mm/s (speed guard) */
    uint16_t decel_mm_s2;        /* braking deceleration, mm/s^2; 0: no speed guard */
    const char *controller;      /* a name in libqnav's controller table (qnav/nav.h):
                                    "body" (default), "literal", "vfh" */
} qnav_tekbot_config_t;

/* Counters for tests and the debugger. */
typedef struct {
    uint32_t ticks;              /* control ticks run */
    uint32_t stopped_ticks;      /* ticks with the motors held at 0 */
    uint32_t link_lost;          /* transitions into link-quiet */
    uint32_t uploads_ok;         /* policies accepted */
    uint32_t uploads_refused;    /* policy commits refused */
} qnav_tekbot_stats_t;

/* The application; caller-owned (one static on the MCU). Fields are private. */
typedef struct {
    qnav_tekbot_config_t cfg;
    qnav_board_hal_t hal;
    qnav_link_rx_t rx;
    qnav_link_tx_t tx;
    qnav_link_upload_t upload;
    qnav_nav_t nav;              /* the chosen controller (cfg.controller) and its state */
    qnav_policy_t policy;        /* the policy nav was made from (if it takes one) */
    qnav_cdeg_t decided_cdeg;    /* last decision's heading in the world (compass), 0.01 deg */
    uint8_t have_decision;       /* decided_cdeg is set */
    uint16_t policy_crc;
    uint8_t ctrl_ready;
    uint8_t mode;                /* QNAV_LINK_MODE_* last requested by the bridge (0 none) */
    uint8_t hold_stop;           /* a stop was commanded and not yet cleared */
    uint8_t link_ok;             /* a good frame arrived within link_timeout_ms */
    uint8_t have_goal;
    qnav_link_goal_t goal;
    qnav_link_command_t cmd;     /* last offboard command */
    uint32_t cmd_ms;             /* when it arrived */
    uint32_t last_rx_ms;         /* last good frame */
    uint8_t heard;               /* any good frame since start */
    uint32_t next_tick_ms;
    qnav_mm_t ranges[QNAV_LINK_MAX_SECTORS];
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    qnav_tekbot_stats_t stats;
} qnav_tekbot_t;

/* Defaults: 8 sectors, 5000 mm, 100 ms tick, 300 ms link timeout, spin beyond 60 deg; the
 * body of data/robots/tekbot.toml (radius 120 mm with the sonar on its rim, safety 50 mm,
 * 500 mm/s, braking 2000 mm/s^2). */
void qnav_tekbot_config_default(qnav_tekbot_config_t *cfg);

/* Check cfg and hal, start the link and the controller with the hand-tuned probabilistic
 * policy; motors are set to 0. Returns QNAV_TEKBOT_OK, _E_NULL, _E_CONFIG or _E_CTRL. */
qnav_tekbot_status_t qnav_tekbot_init(qnav_tekbot_t *bot, const qnav_tekbot_config_t *cfg,
                                      const qnav_board_hal_t *hal);

/* Drain the UART and act on frames; run a control tick when tick_ms has passed. */
void qnav_tekbot_poll(qnav_tekbot_t *bot);

/* One control tick now (qnav_tekbot_poll calls it on schedule). */
void qnav_tekbot_tick(qnav_tekbot_t *bot);

/* Differential drive from a decision: forward part falls linearly to 0 at spin_deg, the
 * turn part is proportional to heading and saturates at 90 deg. Outputs Q1.15, signed. */
void qnav_tekbot_mix(qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_deg_t spin_deg,
                     qnav_q1_15_t *left, qnav_q1_15_t *right);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_TEKBOT_H */
