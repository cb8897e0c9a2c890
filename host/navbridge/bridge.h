/*
 * navbridge's core, free of any I/O: it takes bytes from the serial port, LCM goals and the
 * clock, and answers with bytes for the serial port and LCM messages. main.c wires it to a
 * real serial port and LCM bus; tests drive it directly. Offboard mode runs libqnav on the
 * board's scans and returns commands; onboard mode relays goals, heartbeats and policy
 * uploads while the board runs libqnav. Both publish everything they see on LCM. A
 * watchdog commands a stop when the board's scans (offboard) or heartbeats (onboard) stop
 * for longer than the timeout.
 */
#ifndef QNAV_NAVBRIDGE_BRIDGE_H
#define QNAV_NAVBRIDGE_BRIDGE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <lcm/lcm.h>
#include <lcm/eventlog.h>

#include "qnav/ctrl.h"
#include "qnav/check.h"
#include "qnav/nav.h"
#include "qnav/link.h"
#include "qnav_command_t.h"
#include "qnav_goal_t.h"
#include "qnav_nav_input_t.h"
#include "qnav_scan_t.h"
#include "qnav_waypoints_t.h"

#ifdef __cplusplus
extern "C" {
#endif

/* LCM channels. */
#define QNAV_CH_SCAN "QNAV_SCAN"
#define QNAV_CH_GOAL "QNAV_GOAL"
#define QNAV_CH_COMMAND "QNAV_COMMAND"
#define QNAV_CH_QUALITIES "QNAV_QUALITIES"
#define QNAV_CH_POSE "QNAV_POSE"
#define QNAV_CH_LINK_STATUS "QNAV_LINK_STATUS"
#define QNAV_CH_WAYPOINTS "QNAV_WAYPOINTS"
#define QNAV_CH_ODOMETRY "QNAV_ODOMETRY"
#define QNAV_CH_NAV_INPUT "QNAV_NAV_INPUT"

/* Goals and routes from LCM are taken only on these channels followed by the run's token
 * (QNAV_GOAL_<token>, QNAV_WAYPOINTS_<token>), and only when the operator asked for it
 * (navbridge --lcm-goals). Plain QNAV_GOAL and QNAV_WAYPOINTS are never obeyed: anyone
 * who can put a datagram on the bus can publish there (docs/hil.md, "Who may move the
 * robot"). */
#define QNAV_BRIDGE_TOKEN_HEX 32      /* hex digits of a run token made by navbridge (128 bits) */
#define QNAV_BRIDGE_TOKEN_MAX 40      /* longest token qnav_bridge_subscribe takes, characters */
#define QNAV_BRIDGE_CHANNEL_MAX 64    /* LCM's channel name limit (63) plus the terminator */

/* Most waypoints in a route (waypoints_t). */
#define QNAV_BRIDGE_MAX_WAYPOINTS 16

/* command_t.stop_reason and .source values. */
#define QNAV_STOP_NONE 0
#define QNAV_STOP_WATCHDOG 1
#define QNAV_STOP_SHUTDOWN 2
#define QNAV_STOP_BOARD 3
#define QNAV_SOURCE_BRIDGE 1
#define QNAV_SOURCE_BOARD 2

/* link_status_t.last_upload_status besides the board's QNAV_LINK_ACK_* answers. */
#define QNAV_BRIDGE_UPLOAD_NONE_YET 1
#define QNAV_BRIDGE_UPLOAD_NO_ANSWER (-5) /* QNAV_BRIDGE_UPLOAD_TRIES tries,
                                              QNAV_BRIDGE_UPLOAD_WAIT_MS apart, never acked */

/* An upload is sent at most this many times: again when no answer came, or when the board
 * answered that it arrived damaged (QNAV_LINK_ACK_BAD_LENGTH / _BAD_CRC). A policy the board
 * refuses (_BAD_POLICY / _REJECTED) is not sent again. */
#define QNAV_BRIDGE_UPLOAD_TRIES 3

/* How long a policy upload's answer is awaited before the upload is sent again. The board
 * answers after initialising the new controller (a 2-input network's init copies the row
 * shapes the upload carries; a board that ignores them evaluates every row of keys: up to
 * 1.2 s on a 16 MHz ATmega128 at H = 16, docs/performance.md) and committing it to EEPROM
 * (about 1.1 s): 3 s leaves room for both even then. */
#define QNAV_BRIDGE_UPLOAD_WAIT_MS 3000

/* Writes bytes to the serial port; returns 0 or -1. */
typedef int (*qnav_bridge_write_fn)(void *user, const uint8_t *bytes, size_t n);

/* The controller navbridge runs when none is named: a row of qnav/nav.h's table. */
#define QNAV_BRIDGE_DEFAULT_CONTROLLER "body"

typedef struct {
    uint8_t mode;                 /* QNAV_LINK_MODE_OFFBOARD or _ONBOARD */
    uint32_t timeout_ms;          /* watchdog: stop after this long without scans
                                     (offboard) or heartbeats (onboard), ms */
    uint32_t heartbeat_ms;        /* bridge heartbeat period, ms (100) */
    uint32_t status_ms;           /* link status publish period, ms (500) */
    qnav_ctrl_config_t ctrl;      /* n_sectors is taken from each scan */
    const char *controller;       /* a name in libqnav's controller table (qnav/nav.h);
                                     null: QNAV_BRIDGE_DEFAULT_CONTROLLER */
    qnav_policy_t policy;         /* offboard: drives the robot; onboard: qualities shown */
    int upload;                   /* onboard: upload policy to the board */
    /* --robot: checks each CONFIG report of the board against the robot's profile; 0 when
     * it matches, else 1 with "FIELD REPORTED != EXPECTED" in line. NULL: no check. With a
     * check, offboard commands wait for the first matching report. */
    int (*check_config)(void *user, const qnav_link_config_t *m, char *line, size_t len);
    void *check_user;
} qnav_bridge_config_t;

/* The controller step of the bridge, shared with the replay: re-initialises when the
 * scan's sector count or range changes; carries the escape memory and the last decision
 * from scan to scan as the board core does (qnav_ctrl_carry_t). */
typedef struct {
    qnav_nav_t nav;
    const qnav_nav_method_t *method; /* the controller (null: unknown name, never ready) */
    qnav_ctrl_config_t cfg;
    qnav_policy_t policy;
    int ready;                    /* qnav_nav_init succeeded for cfg */
    uint16_t policy_crc;          /* CRC-16 of the policy blob */
    uint16_t config_crc;          /* qnav_bridge_config_crc of cfg and the controller */
    qnav_ctrl_carry_t carry;      /* escape memory and last decision */
} qnav_bridge_ctrl_t;

/* controller: a name of the table in qnav/nav.h (null: QNAV_BRIDGE_DEFAULT_CONTROLLER). */
void qnav_bridge_ctrl_init(qnav_bridge_ctrl_t *bc, const qnav_ctrl_config_t *cfg,
                           const char *controller, const qnav_policy_t *policy);
/* What the controller is given for scan besides the scan, into rec (the QNAV_NAV_INPUT
 * record): range_mm to the destination (0: bearing-only goal or unknown: no escape), the
 * previous heading (from the robot's heading yaw_cdeg, the board's pose report of the
 * scan's tick; 0 when unknown), the configuration's CRC. */
void qnav_bridge_ctrl_input(qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan, uint32_t range_mm,
                            qnav_cdeg_t yaw_cdeg, qnav_nav_input_t *rec);
/* Run the controller on an LCM scan with rec (qnav_bridge_ctrl_input's, or a logged one;
 * its escape_clear and escape_grow_mm, what the board's map did to the escape memory this
 * tick, applied to the carried memory as the board's map applies them onboard);
 * fills cmd (integer and float fields, source BRIDGE) and qualities (360 Q1.15 values, may
 * be NULL). */
void qnav_bridge_ctrl_step(qnav_bridge_ctrl_t *bc, const qnav_scan_t *scan,
                           const qnav_nav_input_t *rec, qnav_command_t *cmd,
                           int16_t *qualities);
/* CRC-16 of a controller configuration (every field but n_sectors and max_range_mm, which
 * come with each scan) and the controller's name (null: the default): what
 * QNAV_NAV_INPUT's config_crc records. */
uint16_t qnav_bridge_config_crc(const qnav_ctrl_config_t *cfg, const char *controller);
/* CRC-16 of a policy's link blob (0 if it cannot be serialised). */
uint16_t qnav_bridge_policy_crc(const qnav_policy_t *policy);
/* The blob an upload sends: the policy's, with a 2-input network's row shapes for the
 * rank of controller (null: QNAV_BRIDGE_DEFAULT_CONTROLLER) under cfg appended, computed
 * here (0.2 ms) so that the board's init copies them (docs/hil.md, "Policy blob"). Bytes
 * written, or a negative QNAV_LINK_E_* status. */
int32_t qnav_bridge_upload_blob(const qnav_ctrl_config_t *cfg, const char *controller,
                                const qnav_policy_t *policy, uint8_t *out, uint16_t cap);

/* Where an onboard policy upload stands. */
typedef enum {
    QNAV_BRIDGE_UPLOAD_IDLE = 0,  /* no upload asked for */
    QNAV_BRIDGE_UPLOAD_WAITING,   /* asked for: sent once the board's first heartbeat is in */
    QNAV_BRIDGE_UPLOAD_SENT,      /* chunks and commit sent, waiting for the board's ack */
    QNAV_BRIDGE_UPLOAD_DONE       /* acked, refused, or given up (last_upload_status) */
} qnav_bridge_upload_state_t;

typedef struct {
    qnav_bridge_config_t cfg;
    lcm_t *lcm;                   /* may be NULL (no publishing) */
    lcm_eventlog_t *log;          /* may be NULL: also write every publish here */
    qnav_bridge_write_fn write;
    void *write_user;

    qnav_link_rx_t rx;
    qnav_link_tx_t tx;
    qnav_bridge_ctrl_t bc;

    int64_t now_ms;               /* monotonic clock given to the last call, ms */
    int64_t started_ms;
    int64_t last_scan_ms;         /* -1 never */
    int64_t last_heartbeat_ms;    /* -1 never */
    int64_t last_rx_ms;           /* any good frame, -1 never */
    int64_t next_heartbeat_ms;
    int64_t next_status_ms;
    int64_t next_stop_repeat_ms;
    int watchdog_stop;            /* holding a stop because the link went quiet */
    int shutting_down;

    qnav_link_heartbeat_t board_hb;   /* last heartbeat from the board */
    qnav_link_goal_t goal;            /* last goal relayed (goal_id 0 none) */
    int goal_cleared;                 /* the goal was cleared (sent again until the board
                                         reports no goal) */
    uint16_t last_goal_id;            /* goal ids handed out so far (route goals) */
    uint8_t refused_protocol;         /* a board of this other protocol version was heard
                                         (0 none): the bridge must stop (main exits) */
    int heard_board;                  /* a heartbeat of our version came */
    int config_ok;                    /* the board's last CONFIG report passed check_config */
    int config_refused;               /* one did not (main exits): config_diff says why */
    char config_diff[96];
    uint8_t board_stored;             /* last reported QNAV_LINK_STATE_STORED bit */
    uint8_t board_table;              /* last reported QNAV_LINK_STATE_TABLE bit */
    uint16_t board_crc_reported;

    /* the route (waypoints): goal k of n in the odometry frame, mm */
    int32_t route_id;
    int route_n, route_k;
    int32_t route_x_mm[QNAV_BRIDGE_MAX_WAYPOINTS];
    int32_t route_y_mm[QNAV_BRIDGE_MAX_WAYPOINTS];
    int32_t route_radius_mm;

    /* policy upload (onboard) */
    qnav_bridge_upload_state_t upload_state;
    int upload_tries;
    int64_t upload_sent_ms;
    int8_t last_upload_status;    /* QNAV_LINK_ACK_* or QNAV_BRIDGE_UPLOAD_NONE_YET/_NO_ANSWER */

    qnav_goal_t_subscription_t *goal_sub;         /* qnav_bridge_subscribe's */
    qnav_waypoints_t_subscription_t *route_sub;
    char goal_channel[QNAV_BRIDGE_CHANNEL_MAX];   /* QNAV_GOAL_<token> ("" not subscribed) */
    char route_channel[QNAV_BRIDGE_CHANNEL_MAX];  /* QNAV_WAYPOINTS_<token> */

    /* the board's last pose report (sent before its scan each tick): the escape's goal
     * distance */
    int have_pose;
    uint16_t scan_seq;                /* the board's last scan: its link sequence number */
    qnav_cdeg_t scan_yaw_cdeg;        /* and the robot's heading its tick's pose reported */
    uint16_t pose_goal_id;
    uint32_t pose_goal_distance_mm;
    qnav_cdeg_t pose_heading_cdeg;    /* the robot's heading (the previous heading's frame) */
    uint32_t pose_board_ms;           /* its board clock: the scan of the same tick has it */
    uint8_t pose_escape_clear;        /* what the board's map did to the escape memory that */
    uint16_t pose_escape_grow_mm;     /* tick (qnav_link_pose_t), until a scan takes it */

    uint64_t rx_bytes;
    FILE *diag;                   /* one-line notices (upload result, link lost), or NULL */
} qnav_bridge_t;

void qnav_bridge_config_default(qnav_bridge_config_t *cfg);

/* Start a bridge at monotonic time now_ms. lcm and log may be NULL. */
void qnav_bridge_init(qnav_bridge_t *b, const qnav_bridge_config_t *cfg, lcm_t *lcm,
                      lcm_eventlog_t *log, qnav_bridge_write_fn write, void *write_user,
                      int64_t now_ms);

/* Bytes read from the serial port at now_ms. */
void qnav_bridge_on_bytes(qnav_bridge_t *b, const uint8_t *bytes, size_t n, int64_t now_ms);

/* A goal from LCM: relayed to the board and remembered (sent again after every board scan
 * that still reports another goal id). */
void qnav_bridge_on_goal(qnav_bridge_t *b, const qnav_goal_t *goal, int64_t now_ms);

/* A route from LCM (or the command line): the first waypoint becomes the board's goal at
 * once; the bridge advances when the board's pose is within radius_m. Returns 0, or -1
 * with "FIELD: problem" in err for a route it cannot take (n out of 0..16, radius <= 0,
 * a point that is not finite or beyond +-2000 km); n = 0 clears the goal. */
QNAV_CHECK_RESULT int qnav_bridge_on_waypoints(qnav_bridge_t *b, const qnav_waypoints_t *w, int64_t now_ms,
                             char *err, size_t errlen);

/* A fresh run token: QNAV_BRIDGE_TOKEN_HEX lower-case hex digits of the kernel's random
 * source and a terminator into hex (len >= QNAV_BRIDGE_TOKEN_HEX + 1). 0, or -1 when no
 * random bytes could be had. */
QNAV_CHECK_RESULT int qnav_bridge_token_make(char *hex, size_t len);

/* Take goals and routes from b's LCM on QNAV_GOAL_<token> and QNAV_WAYPOINTS_<token> (a
 * refused route is reported on b->diag). token: 1..QNAV_BRIDGE_TOKEN_MAX characters of
 * [0-9a-zA-Z]. 0, or -1 (nothing subscribed) for a bad token or no LCM. */
QNAV_CHECK_RESULT int qnav_bridge_subscribe(qnav_bridge_t *b, const char *token);
void qnav_bridge_unsubscribe(qnav_bridge_t *b);

/* Periodic work (call at least every 20 ms): heartbeats, watchdog, status, upload. */
void qnav_bridge_poll(qnav_bridge_t *b, int64_t now_ms);

/* Stop the robot before exiting: sends stop commands (and a stopped heartbeat). */
void qnav_bridge_shutdown(qnav_bridge_t *b, int64_t now_ms);

/* Publish one encoded LCM message on channel, to the bus and the log. */
void qnav_bridge_publish(qnav_bridge_t *b, const char *channel, const void *data, int len);

/* Microseconds since the epoch, for utime fields. */
int64_t qnav_bridge_utime(void);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_NAVBRIDGE_BRIDGE_H */
