/*
 * The qnav board core: the one board application that runs on every robot and in the
 * software-in-the-loop simulator. A 10 Hz loop reads the sonar, heading and wheel
 * encoders through qnav_board_hal_t, dead-reckons the pose, talks to navbridge over the
 * serial link (heartbeat with the protocol version, the robot configuration it runs,
 * scan, pose, goal, command, policy upload and commit) and drives. In onboard mode it runs libqnav itself (the built-in
 * hand-tuned policy, or an uploaded one that a commit also writes to non-volatile storage
 * and the next start-up loads); in offboard mode it sends scans and applies navbridge's
 * commands. The drive stops whenever the link goes quiet, a stop is commanded, the peer
 * speaks another protocol version, or there is no goal.
 *
 * Use: qnav_board_config_default() (or a robot's generated one, qnav/robots.h)
 * -> edit -> qnav_board_init() -> call qnav_board_poll() as often as possible (it drains
 * the UART and runs a tick every tick_ms). A platform with its own clock (the SIL robot)
 * calls qnav_board_receive() and qnav_board_tick() itself.
 *
 * Odometry frame: origin = the robot centre at start-up, x axis = heading 0 of the heading
 * sensor, y axis 90 deg counter-clockwise of it, millimetres. The pose integrates the mean
 * of the two wheels' travel along the mid-tick heading (docs/hil.md: units and drift).
 */
#ifndef QNAV_BOARD_H
#define QNAV_BOARD_H

#include <stdint.h>

#include "qnav/board_hal.h"
#include "qnav/ctrl.h"
#include "qnav/check.h"
#include "qnav/nav.h"
#include "qnav/link.h"
#include "qnav/map.h"
#include "qnav/trig.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    QNAV_BOARD_OK = 0,
    QNAV_BOARD_E_NULL = -1,     /* a required pointer or HAL function was null */
    QNAV_BOARD_E_CONFIG = -2,   /* a config field is out of range */
    QNAV_BOARD_E_CTRL = -3      /* the controller refused the built-in policy */
} qnav_board_status_t;

/* Where the running policy came from (heartbeat: QNAV_LINK_STATE_STORED when not BUILTIN). */
typedef enum {
    QNAV_BOARD_POLICY_BUILTIN = 0,  /* the hand-tuned probabilistic policy compiled in */
    QNAV_BOARD_POLICY_STORED = 1,   /* loaded from non-volatile storage at start-up */
    QNAV_BOARD_POLICY_UPLOADED = 2  /* committed over the link since start-up */
} qnav_board_policy_source_t;

/* A board's configuration. Everything a robot's profile (data/robots/NAME.toml) decides is
 * generated from it (docs/hil.md, "One robot description"): ctrl whole, tick_ms, track_mm
 * and um_per_count; the rest belongs to the board core. */
typedef struct {
    qnav_ctrl_config_t ctrl;     /* the controller's configuration: sonar sectors (the HAL
                                    delivers them, 1..QNAV_LINK_MAX_SECTORS), range, body,
                                    safety distance, speed guard, ... (qnav/ctrl.h) */
    uint16_t tick_ms;            /* control period, ms (100 = 10 Hz) */
    uint16_t link_timeout_ms;    /* the drive stops after this long without a good frame, ms */
    uint16_t track_mm;           /* distance between the drive wheels, mm (the HAL's heading
                                    from encoder counts; reported, not used by the core) */
    uint16_t um_per_count;       /* wheel travel per encoder count, micrometres (> 0) */
    uint16_t turn_full_deg;      /* where the drive's mixer turns at full wheel speed, deg
                                    (qnav_drive_mix; reported, not used by the core) */
    uint16_t nvm_offset;         /* first byte of the policy store in the HAL's storage;
                                    it takes QNAV_BOARD_STORE_BYTES bytes */
    const char *controller;      /* a name in libqnav's controller table (qnav/nav.h;
                                    default "body") */
} qnav_board_config_t;

/*
 * The fields of a board configuration that a robot profile decides, one X(key, name,
 * member) each: id is the field's key in the link's CONFIG report (never reused), name
 * what messages call it, member the qnav_board_config_t member. The board reports them,
 * the header generator (qnav-sim robot-header) writes them and navbridge compares them, all
 * from this one list: a field added to qnav_ctrl_config_t needs one line here.
 */
#define QNAV_BOARD_ROBOT_FIELDS(X)                                                          \
    X(1, n_sectors, ctrl.n_sectors)                                                         \
    X(2, max_range_mm, ctrl.max_range_mm)                                                   \
    X(3, full_speed_quality, ctrl.full_speed_quality)                                       \
    X(4, body_radius_mm, ctrl.body_radius_mm)                                               \
    X(5, safety_mm, ctrl.safety_mm)                                                         \
    X(6, sensor_offset_mm, ctrl.sensor_offset_mm)                                           \
    X(7, v_max_mm_s, ctrl.v_max_mm_s)                                                       \
    X(8, decel_mm_s2, ctrl.decel_mm_s2)                                                     \
    X(9, rank, ctrl.rank)                                                                   \
    X(10, wedge_pct, ctrl.wedge_pct)                                                        \
    X(11, wedge_near_mm, ctrl.wedge_near_mm)                                                \
    X(12, escape_stall_ticks, ctrl.escape_stall_ticks)                                      \
    X(13, escape_follow_mm, ctrl.escape_follow_mm)                                          \
    X(14, escape_follow_s, ctrl.escape_follow_s)                                            \
    X(15, keep_pct, ctrl.keep_pct)                                                          \
    X(16, range_min_mm, ctrl.range_min_mm)                                                  \
    X(17, pass_mm, ctrl.pass_mm)                                                            \
    X(18, quality_full_speed, ctrl.quality_full_speed)                                      \
    X(32, tick_ms, tick_ms)                                                                 \
    X(33, track_mm, track_mm)                                                               \
    X(34, um_per_count, um_per_count)                                                       \
    X(35, turn_full_deg, turn_full_deg)

/* The policy store: two slots, each [magic 'Q' 'P'][format 1][sequence u8][blob length
 * u16][CRC-16 u16 over format, sequence, length and blob][blob]. A commit writes the slot
 * not in use (magic erased first, written last), so a power cut mid-write leaves the other
 * slot, and the newest whole slot is loaded at start-up. A slot keeps the policy without
 * its carried row shapes: 198 more bytes would cost 1.7 s of EEPROM writes a commit, more
 * than the init they save; start-up computes them (docs/hil.md, "Limits"). */
#define QNAV_BOARD_STORE_FORMAT 1u
#define QNAV_BOARD_STORE_HEADER_BYTES 8u
#define QNAV_BOARD_STORE_SLOT_BYTES \
    (QNAV_BOARD_STORE_HEADER_BYTES + QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES)
#define QNAV_BOARD_STORE_BYTES (2u * QNAV_BOARD_STORE_SLOT_BYTES)

/*
 * Table mode on the board (docs/hil.md, "Table mode on the board"). When the HAL has a
 * table area and the running policy is a 2-input network, the core compiles the policy
 * into the area, QNAV_BOARD_TABLE_KEYS_PER_WORK keys or one full page's write per call of
 * qnav_board_table_work() (qnav_board_poll() calls it while that fits before the next
 * tick), then switches the controller to table mode:
 * the same decisions (table and network mode are bit identical), at a cost that no
 * policy can raise. Until then the network step runs. Layout: QNAV_QTABLE_ENTRIES keys
 * (native int16, level-major, as qnav_ctrl_build_table() writes them), then the record,
 * four native u16: QNAV_BOARD_TABLE_MAGIC, format | rank << 8, the policy's CRC and the
 * CRC-16 (qnav_link_crc16) of the key bytes. The record lies in the last page written,
 * and at start-up the area is used only when the record names the running policy and
 * rank, the keys' CRC matches, and one key of every level equals the network's own.
 */
#define QNAV_BOARD_TABLE_MAGIC 0x5451u
#define QNAV_BOARD_TABLE_FORMAT 1u
#define QNAV_BOARD_TABLE_KEY_BYTES ((uint16_t)(2u * QNAV_QTABLE_ENTRIES))
#define QNAV_BOARD_TABLE_RECORD_BYTES 8u
#define QNAV_BOARD_TABLE_BYTES ((uint16_t)(QNAV_BOARD_TABLE_KEY_BYTES + QNAV_BOARD_TABLE_RECORD_BYTES))
#define QNAV_BOARD_TABLE_PAGE_MAX 256u
/* Keys made per qnav_board_table_work() call, and the time before the next tick that
 * qnav_board_poll() leaves free when it makes them or writes a full page (ATmega128: 4 keys
 * take about 0.8 ms at H = 12 and 1 ms at H = 16; a page's erase and write about 9 ms).
 * A step of the worst network (65 ms) and the tick's frames (about 23 ms at 57 600 baud)
 * still leave room for both in every tick or two. */
#define QNAV_BOARD_TABLE_KEYS_PER_WORK 4u
#define QNAV_BOARD_TABLE_KEYS_MS 3u
#define QNAV_BOARD_TABLE_WRITE_MS 12u

/* Where the table area stands. */
typedef enum {
    QNAV_BOARD_TABLE_NONE = 0,     /* not used: no area, or a policy it does not take */
    QNAV_BOARD_TABLE_BUILDING = 1, /* being compiled; the network step runs meanwhile */
    QNAV_BOARD_TABLE_IN_USE = 2    /* the controller reads it (table mode) */
} qnav_board_table_state_t;

/* Counters for tests and the debugger. */
typedef struct {
    uint32_t ticks;              /* control ticks run */
    uint32_t stopped_ticks;      /* ticks with the drive held at 0 */
    uint32_t link_lost;          /* transitions into link-quiet */
    uint32_t uploads_ok;         /* policies accepted */
    uint32_t uploads_refused;    /* policy commits refused */
    uint32_t store_writes_failed;/* commits whose storage write failed (runs from RAM) */
    uint32_t peer_refused;       /* heartbeats of another protocol version, ignored */
    uint8_t peer_protocol;       /* version of the last heartbeat heard (0 none) */
    uint32_t commands;           /* offboard commands received */
    uint16_t last_command_seq;   /* scan_seq of the newest of them */
    uint16_t last_scan_seq;      /* link sequence number of the last scan sent */
    uint32_t tables_built;       /* key tables compiled into the HAL's area */
    uint32_t tables_reused;      /* new controllers whose table the area already held */
    uint32_t table_writes_failed;/* builds given up on a failed page write (network runs) */
} qnav_board_stats_t;

/* Dead-reckoned pose. */
typedef struct {
    int32_t x_um;                /* odometry frame, micrometres (+-2147 m) */
    int32_t y_um;
    qnav_cdeg_t heading_cdeg;    /* the heading sensor's, 0.01 deg */
} qnav_board_pose_t;

/* The application; caller-owned (one static on the MCU). Fields are private. */
typedef struct {
    qnav_board_config_t cfg;
    qnav_board_hal_t hal;
    qnav_link_rx_t rx;
    qnav_link_tx_t tx;
    /* An upload's chunks and the page a table build fills share one buffer, never in use
     * together: a build owns it while table_state is BUILDING (qnav_board_table_start drops
     * an upload under way), an upload's chunk stops a build, and a build so stopped starts
     * again when the upload ends (a commit, refused or not, or the link lost). The 256
     * bytes so saved are the TekBot's map's (docs/hil.md, "RAM on the ATmega128"). */
    union {
        qnav_link_upload_t upload;
        uint8_t table_page[QNAV_BOARD_TABLE_PAGE_MAX]; /* the page being built */
    } buf;
    qnav_nav_t nav;              /* the chosen controller (cfg.controller) and its state */
    qnav_policy_t policy;        /* the policy nav was made from (if it takes one) */
    qnav_ctrl_carry_t carry;     /* the escape memory (cleared with every new goal) and the
                                    last decision, carried from tick to tick as navbridge
                                    and its replay carry them (qnav_ctrl_carry_input) */
    qnav_map_t *map;             /* the map in use (qnav_board_set_map, or placed), or NULL */
    qnav_map_t *place_map;       /* placed afresh for each position goal
                                    (qnav_board_place_maps), or NULL */
    const qnav_map_config_t *place_cfg;
    void *place_buf;
    size_t place_len;
    uint16_t placed_goal;        /* the goal id the map was placed for (0: none yet) */
    /* a tick's map work, set by qnav_board_set_map / qnav_board_place_maps (NULL: none),
     * so that a firmware calling neither links no map code */
    void (*map_tick)(void *bot, qnav_ctrl_input_t *in, uint32_t *dist_mm, qnav_link_pose_t *esc);
    uint16_t policy_crc;
    uint8_t policy_source;       /* qnav_board_policy_source_t */
    uint8_t store_slot;          /* slot the running stored policy is in (0/1), 0xFF none */
    uint8_t store_seq;           /* its sequence number */
    uint8_t ctrl_ready;
    uint8_t table_state;         /* qnav_board_table_state_t */
    uint16_t table_at;           /* the next byte of the area the build makes */
    uint16_t table_done;         /* bytes of the area written so far */
    uint16_t table_crc;          /* CRC-16 of the key bytes built so far */
    uint8_t table_stopped;       /* an upload stopped the build: it starts again when the
                                    upload ends */
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
    qnav_board_pose_t pose;
    int32_t odo_left, odo_right; /* encoder counts at the last tick */
    qnav_q1_15_t rolling;        /* forward speed over the last tick, Q1.15 of v_max (0
                                    without encoders): the HAL's drive brakes on it */
    qnav_mm_t ranges[QNAV_LINK_MAX_SECTORS];
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    qnav_board_stats_t stats;
} qnav_board_t;

/* Defaults: qnav_ctrl_config_default()'s controller (16 sectors, 5000 mm, a TekBot-class
 * body), 100 ms tick, 300 ms link timeout, 180 mm track, 1000 um per count, store at byte
 * 0, controller "body". A robot's board starts from its generated configuration instead
 * (qnav/robots.h). */
void qnav_board_config_default(qnav_board_config_t *cfg);

/* The CONFIG report of cfg: every QNAV_BOARD_ROBOT_FIELDS field as (key, value). */
void qnav_board_config_report(const qnav_board_config_t *cfg, qnav_link_config_t *m);

/*
 * The map a board runs, as its CONFIG report gives it after the robot fields (link
 * protocol 5): whether it has one, the bytes it places it in at each goal (0: a map the
 * caller laid out, qnav_board_set_map), the cell, the readings' reach, the layout, and a
 * CRC-16 over every qnav_map_config_t field (qnav_board_map_info), so that a bridge
 * refuses a board whose map is not its profile's, naming the field or the CRC.
 */
typedef struct {
    uint8_t on;
    uint32_t bytes;
    uint16_t cell_mm;
    uint16_t reach_mm;
    uint8_t compact;
    uint16_t crc;
} qnav_board_map_info_t;

#define QNAV_BOARD_MAP_FIELDS(X)                                                            \
    X(48, map_on, on)                                                                       \
    X(49, map_bytes, bytes)                                                                 \
    X(50, map_cell_mm, cell_mm)                                                             \
    X(51, map_reach_mm, reach_mm)                                                           \
    X(52, map_compact, compact)                                                             \
    X(53, map_config_crc, crc)

/* info of the map cfg (NULL: no map) placed in bytes (0: laid out by the caller). */
void qnav_board_map_info(const qnav_map_config_t *cfg, uint32_t bytes,
                         qnav_board_map_info_t *info);

/* Append info's QNAV_BOARD_MAP_FIELDS to the report m (as far as it has room). */
void qnav_board_map_report(const qnav_board_map_info_t *info, qnav_link_config_t *m);

/* Check cfg and hal, start the link, load the newest whole policy from storage (the
 * built-in policy when there is none or it is corrupt), start the controller; the drive
 * is set to 0. Returns QNAV_BOARD_OK, _E_NULL, _E_CONFIG or _E_CTRL. */
QNAV_CHECK_RESULT qnav_board_status_t qnav_board_init(qnav_board_t *bot, const qnav_board_config_t *cfg,
                                    const qnav_board_hal_t *hal);


/*
 * Reach position goals through a map of what the sonar has seen (qnav/map.h;
 * docs/architecture.md, "A map and a plan"): each tick marks the map from the pose and
 * gives the controller the plan's sub-goal and planned distance (also reported as the
 * POSE frame's goal distance). The caller initialises the map over the part of the
 * odometry frame the robot may reach, in memory it keeps (qnav_map_size(): 8 bytes a
 * cell, more than an ATmega128 has for any useful area, or half a byte in the compact
 * layout), and resets it for a new world.
 * NULL turns it off. Bearing goals are never planned. Returns 1 (0 for a NULL bot). A
 * firmware that calls neither this nor qnav_board_place_maps links no map code.
 */
int qnav_board_set_map(qnav_board_t *bot, qnav_map_t *map);

/*
 * A map the core places itself, for a board that knows neither its room nor its goals
 * beforehand: at each new position goal it starts map afresh (qnav_map_init with cfg, in
 * the len bytes at buf, all the caller's and kept by it) over the largest square of cfg's
 * cells those bytes hold, centred midway between the robot and the goal, or reaching toward
 * a goal too far for it (qnav_map_place), and moves it with the robot each tick
 * (qnav_map_follow). 512 bytes hold 32 x 32 compact cells: 11.2 m at 0.35 m. map NULL
 * turns it off;
 * qnav_board_set_map() and this replace each other. Returns 1, or 0 (and places nothing)
 * with a NULL argument besides map.
 */
int qnav_board_place_maps(qnav_board_t *bot, qnav_map_t *map, const qnav_map_config_t *cfg,
                          void *buf, size_t len);

/* Drain the UART (qnav_board_receive), run a control tick when tick_ms has passed, and
 * do one piece of a table build when it fits before the next tick. */
void qnav_board_poll(qnav_board_t *bot);

/* Read and act on at most 128 waiting UART bytes. */
void qnav_board_receive(qnav_board_t *bot);

/* One control tick now: odometry, sense, decide, drive, report (scan, heartbeat, pose,
 * onboard decision). */
void qnav_board_tick(qnav_board_t *bot);

/* One step of a table build (qnav/board.h, "Table mode on the board"):
 * QNAV_BOARD_TABLE_KEYS_PER_WORK keys into the page being built, or, when it is full, its
 * write; after the last page, the switch to table mode. Returns 1 while a build remains,
 * else 0. qnav_board_poll() calls it; a platform that runs qnav_board_tick() itself calls
 * it between ticks, when qnav_board_table_need_ms() fits. */
uint8_t qnav_board_table_work(qnav_board_t *bot);

/* The ms the next qnav_board_table_work() call may take (QNAV_BOARD_TABLE_KEYS_MS or
 * QNAV_BOARD_TABLE_WRITE_MS); 0 when no build is under way. */
uint16_t qnav_board_table_need_ms(const qnav_board_t *bot);

/* Where the table area stands (qnav_board_table_state_t). */
qnav_board_table_state_t qnav_board_table_state(const qnav_board_t *bot);

/* Counters and the pose (read-only views). */
const qnav_board_stats_t *qnav_board_stats(const qnav_board_t *bot);
const qnav_board_pose_t *qnav_board_pose(const qnav_board_t *bot);
qnav_board_policy_source_t qnav_board_policy_source(const qnav_board_t *bot);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_BOARD_H */
