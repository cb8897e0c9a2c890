/*
 * The serial link between a robot board and navbridge (DESIGN.md §5). One codec, C99, no
 * heap, integers only, no file-scope state: the board and the bridge link the same code. A
 * frame is [msg id u8][sequence u16][payload][CRC-16/CCITT-FALSE u16], all little endian,
 * COBS-encoded and delimited by 0x00 bytes. The decoder is fed one byte at a time and
 * hands out only frames whose CRC, message id, payload length and sequence number are all
 * good; every other frame is dropped and counted by reason. Message payloads are packed
 * and unpacked by the qnav_link_<msg>_pack/_unpack functions below. docs/hil.md describes
 * the wire format byte by byte.
 */
#ifndef QNAV_LINK_H
#define QNAV_LINK_H

#include <stdint.h>

#include "qnav/fixed.h"
#include "qnav/ctrl.h"
#include "qnav/policy.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Compile-time knobs (override with -D) ------------------------------------------ */

/* Most sonar sectors a scan frame may carry. A scan payload is 12 + 2*N bytes. The AVR
 * default keeps the decoder's buffer small (ATmega128: 4 KiB RAM). */
#ifndef QNAV_LINK_MAX_SECTORS
#if defined(__AVR__)
#define QNAV_LINK_MAX_SECTORS 32
#else
#define QNAV_LINK_MAX_SECTORS 360
#endif
#endif

/* Bytes of policy data per upload chunk. */
#ifndef QNAV_LINK_CHUNK_BYTES
#define QNAV_LINK_CHUNK_BYTES 48
#endif

#if QNAV_LINK_MAX_SECTORS < 1 || QNAV_LINK_MAX_SECTORS > 360
#error "QNAV_LINK_MAX_SECTORS must be in 1..360"
#endif
#if QNAV_LINK_CHUNK_BYTES < 8 || QNAV_LINK_CHUNK_BYTES > 200
#error "QNAV_LINK_CHUNK_BYTES must be in 8..200"
#endif

/* ---- Wire constants ------------------------------------------------------------------ */

/* The link protocol this codec speaks, carried in every heartbeat (the handshake: each
 * side refuses a peer of another version). Version 1 (before issue 10) had a 12-byte
 * heartbeat without the version byte and bearing-only goals; version 2 adds the version
 * byte, position goals and the board's POSE; version 3 (issue 17) adds the board's CONFIG
 * report, so that a bridge refuses a board built for another robot; version 4 (issue 18)
 * adds to the POSE what the board's map did to the escape memory this tick, so that an
 * offboard controller keeps its memory as the onboard one does; version 5 adds the board's map
 * to its CONFIG report (up to 26 fields), so that a bridge refuses a board whose map is not
 * its robot's; version 6 adds where its drive's mixer turns at full wheel speed
 * (turn_full_deg, up to 28 fields), so that a bridge refuses a board that turns other than
 * its robot's profile. */
#define QNAV_LINK_PROTOCOL_VERSION 6u

/* Message ids. Direction: B->H board to host (navbridge), H->B host to board. */
typedef enum {
    QNAV_LINK_MSG_SCAN = 0x01,          /* B->H sonar ranges + goal bearing, every tick */
    QNAV_LINK_MSG_GOAL = 0x02,          /* H->B destination bearing in the heading frame */
    QNAV_LINK_MSG_COMMAND = 0x03,       /* H->B offboard command; B->H onboard telemetry */
    QNAV_LINK_MSG_POLICY_CHUNK = 0x04,  /* H->B part of a policy blob */
    QNAV_LINK_MSG_POLICY_COMMIT = 0x05, /* H->B end of upload: total length and CRC */
    QNAV_LINK_MSG_POLICY_ACK = 0x06,    /* B->H result of a commit */
    QNAV_LINK_MSG_HEARTBEAT = 0x07,     /* both ways, every tick; carries the protocol version */
    QNAV_LINK_MSG_POSE = 0x08,          /* B->H dead-reckoned pose in the odometry frame */
    QNAV_LINK_MSG_CONFIG = 0x09         /* B->H the robot configuration the board runs */
} qnav_link_msg_t;

/* Payload sizes in bytes (the scan's is 12 + 2 * n_sectors). */
#define QNAV_LINK_SCAN_HEADER_BYTES 12u
#define QNAV_LINK_GOAL_BYTES 17u
#define QNAV_LINK_COMMAND_BYTES 10u
#define QNAV_LINK_POLICY_CHUNK_HEADER_BYTES 4u
#define QNAV_LINK_POLICY_COMMIT_BYTES 4u
#define QNAV_LINK_POLICY_ACK_BYTES 4u
#define QNAV_LINK_HEARTBEAT_BYTES 13u     /* this version's; any version's is >= 12 */
#define QNAV_LINK_HEARTBEAT_V1_BYTES 12u  /* version 1's (no version byte) */
#define QNAV_LINK_HEARTBEAT_MAX_BYTES 32u /* longest a later version may send */
#define QNAV_LINK_POSE_BYTES 23u
/* CONFIG: [count u8] then count x ([key u8][value i32]); at most this many fields. */
#define QNAV_LINK_CONFIG_MAX_FIELDS 28u
#define QNAV_LINK_CONFIG_MAX_BYTES (1u + 5u * QNAV_LINK_CONFIG_MAX_FIELDS)

/* Largest payload this build accepts: a full scan or a full chunk, whichever is larger. */
#define QNAV_LINK_SCAN_MAX_BYTES (QNAV_LINK_SCAN_HEADER_BYTES + 2u * QNAV_LINK_MAX_SECTORS)
#define QNAV_LINK_CHUNK_MAX_BYTES (QNAV_LINK_POLICY_CHUNK_HEADER_BYTES + QNAV_LINK_CHUNK_BYTES)
#define QNAV_LINK_MAX2_(a, b) ((a) > (b) ? (a) : (b))
#define QNAV_LINK_MAX_PAYLOAD                                                               \
    QNAV_LINK_MAX2_(QNAV_LINK_MAX2_(QNAV_LINK_SCAN_MAX_BYTES, QNAV_LINK_CHUNK_MAX_BYTES),    \
                    QNAV_LINK_CONFIG_MAX_BYTES)
/* Frame before COBS: id + sequence + payload + CRC. */
#define QNAV_LINK_FRAME_OVERHEAD 5u
#define QNAV_LINK_MAX_FRAME (QNAV_LINK_MAX_PAYLOAD + QNAV_LINK_FRAME_OVERHEAD)
/* Largest encoded frame on the wire: leading and trailing 0x00, one COBS code byte per
 * 254 data bytes (rounded up), the data. Size transmit buffers with this. */
#define QNAV_LINK_MAX_WIRE(payload_bytes)                                                   \
    (2u + ((payload_bytes) + QNAV_LINK_FRAME_OVERHEAD) +                                    \
     ((payload_bytes) + QNAV_LINK_FRAME_OVERHEAD) / 254u + 1u)

/* Command flags on the wire (COMMAND.flags): low bits are the controller's QNAV_FLAG_*. */
#define QNAV_LINK_CMD_STOP 0x80u    /* stop now: watchdog, shutdown or operator */

/* Heartbeat modes and state bits. */
#define QNAV_LINK_MODE_OFFBOARD 1u  /* the host runs libqnav and sends commands */
#define QNAV_LINK_MODE_ONBOARD 2u   /* the board runs libqnav */
#define QNAV_LINK_STATE_LINK_OK 0x01u   /* the sender hears its peer */
#define QNAV_LINK_STATE_MOVING 0x02u    /* motors commanded non-zero */
#define QNAV_LINK_STATE_POLICY 0x04u    /* a policy is loaded and the controller is ready */
#define QNAV_LINK_STATE_STOPPED 0x08u   /* holding a stop (STOP command or link lost) */
#define QNAV_LINK_STATE_STORED 0x10u    /* board: the running policy is an uploaded one (from
                                           non-volatile storage or just committed); clear:
                                           the built-in policy runs */
#define QNAV_LINK_STATE_TABLE 0x20u     /* board: the controller reads the policy's key table
                                           compiled into the board's table area (table
                                           mode: a step cost no policy can raise) */

/* Goal kinds (GOAL.kind). */
#define QNAV_LINK_GOAL_BEARING 0u   /* a fixed bearing in the board's heading frame */
#define QNAV_LINK_GOAL_POSITION 1u  /* a point (x, y) in the board's odometry frame */

/* Policy upload results (POLICY_ACK.status). */
#define QNAV_LINK_ACK_OK 0
#define QNAV_LINK_ACK_BAD_LENGTH (-1)  /* bytes received differ from the committed length */
#define QNAV_LINK_ACK_BAD_CRC (-2)     /* blob CRC differs from the committed one */
#define QNAV_LINK_ACK_BAD_POLICY (-3)  /* blob does not decode to a policy */
#define QNAV_LINK_ACK_REJECTED (-4)    /* the controller refused it (qnav_ctrl_init) */

/* Largest policy blob without carried row shapes: kind, hidden, then up to 5H+1 weights of
 * 2 bytes (3 inputs). The board's policy store keeps such blobs (qnav/board.h). */
#define QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES \
    (2u + 2u * QNAV_NET_WEIGHTS_IN(QNAV_MAX_HIDDEN, QNAV_NET_INPUTS_PREV))
/* Largest policy blob: a 2-input network's 4H+1 weights and its carried row shapes
 * (QNAV_SHAPES_BYTES), longer than any blob without them. */
#define QNAV_LINK_POLICY_MAX_BYTES \
    (2u + 2u * QNAV_NET_WEIGHTS(QNAV_MAX_HIDDEN) + QNAV_SHAPES_BYTES)

/* ---- Statuses and counters ----------------------------------------------------------- */

typedef enum {
    QNAV_LINK_OK = 0,
    QNAV_LINK_E_NULL = -1,      /* a required pointer was null */
    QNAV_LINK_E_SPACE = -2,     /* the output buffer is too small */
    QNAV_LINK_E_LENGTH = -3,    /* payload length wrong for the message */
    QNAV_LINK_E_VALUE = -4      /* a field is out of its range */
} qnav_link_result_t;

/* Why the decoder dropped a frame. */
typedef enum {
    QNAV_LINK_DROP_COBS = 0,     /* malformed COBS (a block runs past the delimiter) */
    QNAV_LINK_DROP_SHORT = 1,    /* shorter than id + sequence + CRC (truncated) */
    QNAV_LINK_DROP_OVERFLOW = 2, /* longer than QNAV_LINK_MAX_FRAME */
    QNAV_LINK_DROP_CRC = 3,      /* CRC mismatch (corrupted or truncated) */
    QNAV_LINK_DROP_UNKNOWN = 4,  /* message id not known */
    QNAV_LINK_DROP_LENGTH = 5,   /* payload length wrong for its message id */
    QNAV_LINK_DROP_SEQ = 6,      /* sequence not newer than the last accepted (replay) */
    QNAV_LINK_DROP_REASONS = 7
} qnav_link_drop_t;

typedef struct {
    uint32_t frames_ok;                          /* frames accepted */
    uint32_t dropped[QNAV_LINK_DROP_REASONS];    /* frames dropped, by qnav_link_drop_t */
    uint32_t seq_gaps;                           /* accepted frames that skipped sequence
                                                    numbers (frames lost on the way) */
} qnav_link_stats_t;

/* ---- Decoder -------------------------------------------------------------------------- */

/* An accepted frame, valid until the next qnav_link_rx_feed() call. */
typedef struct {
    uint8_t msg_id;             /* a qnav_link_msg_t */
    uint16_t seq;               /* sender's sequence number */
    const uint8_t *payload;     /* points into the decoder's buffer */
    uint16_t len;               /* payload bytes */
} qnav_link_frame_t;

/* Incremental decoder state; caller-owned, fields private. */
typedef struct {
    uint8_t buf[QNAV_LINK_MAX_FRAME];
    uint16_t n;          /* decoded bytes in buf */
    uint8_t code;        /* current COBS block code */
    uint8_t left;        /* data bytes left in the current block */
    uint8_t state;       /* 0 = idle/between frames, 1 = in frame, 2 = discarding */
    uint8_t have_seq;    /* 1 once a frame was accepted since init or reset */
    uint16_t last_seq;   /* sequence number of the last accepted frame */
    qnav_link_stats_t stats;
} qnav_link_rx_t;

/* Start a decoder: empty buffer, zero counters, any first sequence number accepted. */
void qnav_link_rx_init(qnav_link_rx_t *rx);

/* Forget the last sequence number so the next good frame is accepted whatever its number
 * (call when the link went quiet: the peer may have restarted). Counters are kept. */
void qnav_link_rx_reset_seq(qnav_link_rx_t *rx);

/*
 * Feed one received byte. Returns 1 and fills *frame when this byte completes a good
 * frame; 0 otherwise (more bytes needed, or a bad frame was dropped and counted).
 * Sequence rule: accepted when (seq - last_seq) mod 2^16 is in 1..32767.
 */
uint8_t qnav_link_rx_feed(qnav_link_rx_t *rx, uint8_t byte, qnav_link_frame_t *frame);

/* Sum of all drop counters. */
uint32_t qnav_link_rx_dropped_total(const qnav_link_rx_t *rx);

/* ---- Encoder -------------------------------------------------------------------------- */

/* Sender state: the next sequence number. Caller-owned. */
typedef struct {
    uint16_t next_seq;
    uint32_t frames_sent;
} qnav_link_tx_t;

void qnav_link_tx_init(qnav_link_tx_t *tx);

/*
 * Frame a payload: id, next sequence number, payload, CRC, COBS, delimiters, into out
 * (cap bytes; QNAV_LINK_MAX_WIRE(len) always suffices). Returns the number of bytes
 * written (> 0), or QNAV_LINK_E_NULL, QNAV_LINK_E_LENGTH (len > QNAV_LINK_MAX_PAYLOAD),
 * QNAV_LINK_E_SPACE. The sequence number advances only on success.
 */
int32_t qnav_link_encode(qnav_link_tx_t *tx, uint8_t msg_id, const uint8_t *payload,
                         uint16_t len, uint8_t *out, uint16_t cap);

/* Where qnav_link_send puts a framed message: a UART, a pty, a test's queue. */
typedef void (*qnav_link_write_fn)(void *user, const uint8_t *bytes, uint16_t n);

/*
 * Frame a payload into wire (cap bytes, QNAV_LINK_MAX_WIRE(len) suffices) and hand it to
 * write. len < 0 (a failed _pack) sends nothing. The one send path of the board core and
 * navbridge. Returns the bytes written, or the negative status of _pack/_encode.
 */
int32_t qnav_link_send(qnav_link_tx_t *tx, uint8_t msg_id, const uint8_t *payload,
                       int32_t len, uint8_t *wire, uint16_t cap, qnav_link_write_fn write,
                       void *user);

/* CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor);
 * "123456789" gives 0x29B1. Continue a running CRC by passing the previous value. */
uint16_t qnav_link_crc16(uint16_t crc, const uint8_t *data, uint16_t len);
#define QNAV_LINK_CRC16_INIT 0xFFFFu

/* Payload length a message id must have; for SCAN, for n_sectors = 1 it returns the
 * minimum. 0 for an unknown id. Used by the decoder. */
uint16_t qnav_link_min_payload(uint8_t msg_id);

/* ---- Messages ------------------------------------------------------------------------- */

typedef struct {
    uint32_t board_ms;                 /* board clock at sensing, ms (wraps) */
    qnav_cdeg_t goal_bearing_cdeg;     /* destination bearing, robot frame, 0.01 deg, CCW */
    qnav_mm_t max_range_mm;            /* sonar maximum range, mm */
    uint16_t n_sectors;                /* N, 1..QNAV_LINK_MAX_SECTORS */
    uint16_t goal_id;                  /* id of the goal the bearing refers to (0 none) */
    qnav_mm_t ranges_mm[QNAV_LINK_MAX_SECTORS]; /* sector k centred on k*360/N deg, mm */
} qnav_link_scan_t;

typedef struct {
    uint16_t goal_id;                  /* increments with each new goal; 0 = no goal */
    qnav_cdeg_t bearing_cdeg;          /* BEARING: destination bearing in the board's
                                          heading frame (0 = heading sensor zero), 0.01 deg,
                                          CCW */
    uint32_t distance_mm;              /* distance to the destination, mm (0 = unknown) */
    uint8_t kind;                      /* QNAV_LINK_GOAL_BEARING or _POSITION */
    int32_t x_mm;                      /* POSITION: destination in the odometry frame, mm */
    int32_t y_mm;
} qnav_link_goal_t;

typedef struct {
    uint32_t board_ms;                 /* board clock at the estimate, ms (wraps) */
    int32_t x_mm;                      /* odometry frame (origin and x axis = the pose at
                                          start-up), mm */
    int32_t y_mm;
    qnav_cdeg_t heading_cdeg;          /* heading in that frame, 0.01 deg, CCW */
    uint16_t goal_id;                  /* goal being driven to (0 none) */
    uint32_t goal_distance_mm;         /* POSITION goal: distance to it, mm (0 otherwise); with
                                          a map, the planned distance */
    uint8_t escape_clear;              /* 1: this tick the map's plan jumped and the escape
                                          memory was cleared (QNAV_MAP_ESCAPE_CLEARED) */
    uint16_t escape_grow_mm;           /* this tick the map's new plan was longer where the
                                          robot is: the memory grew this much
                                          (QNAV_MAP_ESCAPE_GROWN, qnav_escape_grow); 0 none */
} qnav_link_pose_t;

typedef struct {
    uint16_t scan_seq;                 /* sequence number of the scan this answers */
    qnav_deg_t heading_deg;            /* chosen path, robot frame, deg, -179..180 */
    qnav_q1_15_t speed;                /* fraction of full speed, Q1.15, [0, 1) */
    qnav_q1_15_t quality;              /* quality of the chosen path, Q1.15 */
    uint8_t flags;                     /* QNAV_FLAG_* | QNAV_LINK_CMD_STOP */
    uint8_t reserved;                  /* 0 */
} qnav_link_command_t;

typedef struct {
    uint16_t offset;                   /* byte offset of data in the blob */
    uint16_t total;                    /* blob length, bytes */
    uint8_t len;                       /* data bytes, 1..QNAV_LINK_CHUNK_BYTES */
    uint8_t data[QNAV_LINK_CHUNK_BYTES];
} qnav_link_policy_chunk_t;

typedef struct {
    uint16_t total;                    /* blob length, bytes */
    uint16_t crc;                      /* qnav_link_crc16 over the blob */
} qnav_link_policy_commit_t;

typedef struct {
    int8_t status;                     /* QNAV_LINK_ACK_* */
    uint8_t reserved;
    uint16_t crc;                      /* CRC of the policy now in use (0 none) */
} qnav_link_policy_ack_t;

typedef struct {
    uint32_t uptime_ms;                /* sender clock, ms (wraps) */
    uint8_t mode;                      /* QNAV_LINK_MODE_*: requested (host) or running */
    uint8_t state;                     /* QNAV_LINK_STATE_* bits */
    uint16_t rx_ok;                    /* sender's accepted frames (wraps) */
    uint16_t rx_dropped;               /* sender's dropped frames (wraps) */
    uint16_t policy_crc;               /* CRC of the sender's policy blob (0 none) */
    uint8_t protocol;                  /* unpack: the sender's QNAV_LINK_PROTOCOL_VERSION (1
                                          for a 12-byte heartbeat); pack always sends this
                                          codec's own version */
} qnav_link_heartbeat_t;

/* The robot configuration a board runs, as (key, value) pairs: the keys are the board
 * core's QNAV_BOARD_ROBOT_FIELDS ids (qnav/board.h), so the codec needs no change when a
 * field is added. */
typedef struct {
    uint8_t n;                                   /* pairs, 0..QNAV_LINK_CONFIG_MAX_FIELDS */
    uint8_t key[QNAV_LINK_CONFIG_MAX_FIELDS];    /* field id */
    int32_t value[QNAV_LINK_CONFIG_MAX_FIELDS];  /* its value, in the field's own unit */
} qnav_link_config_t;

/* Pack into out (cap bytes); return bytes written or QNAV_LINK_E_NULL/_SPACE/_VALUE.
 * Unpack from a payload; return QNAV_LINK_OK or QNAV_LINK_E_NULL/_LENGTH/_VALUE. */
int32_t qnav_link_scan_pack(const qnav_link_scan_t *m, uint8_t *out, uint16_t cap);
int32_t qnav_link_scan_unpack(const uint8_t *p, uint16_t len, qnav_link_scan_t *m);
int32_t qnav_link_goal_pack(const qnav_link_goal_t *m, uint8_t *out, uint16_t cap);
int32_t qnav_link_goal_unpack(const uint8_t *p, uint16_t len, qnav_link_goal_t *m);
int32_t qnav_link_command_pack(const qnav_link_command_t *m, uint8_t *out, uint16_t cap);
int32_t qnav_link_command_unpack(const uint8_t *p, uint16_t len, qnav_link_command_t *m);
int32_t qnav_link_policy_chunk_pack(const qnav_link_policy_chunk_t *m, uint8_t *out,
                                    uint16_t cap);
int32_t qnav_link_policy_chunk_unpack(const uint8_t *p, uint16_t len,
                                      qnav_link_policy_chunk_t *m);
int32_t qnav_link_policy_commit_pack(const qnav_link_policy_commit_t *m, uint8_t *out,
                                     uint16_t cap);
int32_t qnav_link_policy_commit_unpack(const uint8_t *p, uint16_t len,
                                       qnav_link_policy_commit_t *m);
int32_t qnav_link_policy_ack_pack(const qnav_link_policy_ack_t *m, uint8_t *out,
                                  uint16_t cap);
int32_t qnav_link_policy_ack_unpack(const uint8_t *p, uint16_t len,
                                    qnav_link_policy_ack_t *m);
int32_t qnav_link_heartbeat_pack(const qnav_link_heartbeat_t *m, uint8_t *out, uint16_t cap);
/* Any version's heartbeat unpacks (its fields are the first 12 bytes of every version);
 * check m->protocol before acting on it. */
int32_t qnav_link_heartbeat_unpack(const uint8_t *p, uint16_t len, qnav_link_heartbeat_t *m);
int32_t qnav_link_pose_pack(const qnav_link_pose_t *m, uint8_t *out, uint16_t cap);
int32_t qnav_link_pose_unpack(const uint8_t *p, uint16_t len, qnav_link_pose_t *m);
int32_t qnav_link_config_pack(const qnav_link_config_t *m, uint8_t *out, uint16_t cap);
int32_t qnav_link_config_unpack(const uint8_t *p, uint16_t len, qnav_link_config_t *m);
/* Append (key, value) to a CONFIG payload packed in out (cap bytes; start with out[0] = 0,
 * no pairs): the payload's length after it, or QNAV_LINK_E_NULL, QNAV_LINK_E_VALUE (it holds
 * QNAV_LINK_CONFIG_MAX_FIELDS pairs already) or QNAV_LINK_E_SPACE. For a board that packs
 * its report without a qnav_link_config_t on its stack. */
int32_t qnav_link_config_append(uint8_t *out, uint16_t cap, uint8_t key, int32_t value);

/* ---- Policy blobs (what an upload carries) -------------------------------------------- */

/*
 * Serialize a policy: [kind u8][shape u8][weights i16 LE]: PROB shape 0, k_goal, k_safe;
 * NET shape = H, plus 0x80 with the previous-decision input, then the 4H+1 (5H+1)
 * weights in qnav_net_weight() order. Returns bytes written or QNAV_LINK_E_NULL / _VALUE
 * (policy refused by qnav_policy_validate) / _SPACE.
 */
QNAV_CHECK_RESULT int32_t qnav_link_policy_to_blob(const qnav_policy_t *policy, uint8_t *out, uint16_t cap);

/*
 * The same with a 2-input network's carried row shapes appended (QNAV_SHAPES_BYTES from
 * qnav_ctrl_shapes_save, copied as they are: the board's init checks them). shapes null:
 * qnav_link_policy_to_blob. QNAV_LINK_E_VALUE for shapes with any other policy.
 */
QNAV_CHECK_RESULT int32_t qnav_link_policy_to_blob_carried(const qnav_policy_t *policy,
                                                           const uint8_t *shapes,
                                                           uint8_t *out, uint16_t cap);

/* The carried row shapes inside a blob that qnav_link_policy_from_blob accepts: a pointer
 * to its QNAV_SHAPES_BYTES, or null when it has none (or len is no blob's length). */
const uint8_t *qnav_link_blob_shapes(const uint8_t *blob, uint16_t len);

/* The CRC-16 of a policy's blob without carried shapes: what heartbeats, acks and
 * commands call the policy's CRC, whether or not an upload carried shapes (0 when it
 * cannot be serialised). */
uint16_t qnav_link_policy_crc(const qnav_policy_t *policy);

/* Parse a blob back, with or without carried shapes (their bytes are not looked at here:
 * qnav_link_blob_shapes finds them, init checks them); QNAV_LINK_OK or QNAV_LINK_E_NULL /
 * _LENGTH / _VALUE (also for a policy qnav_policy_validate refuses, as the writer does);
 * *policy untouched on error. */
QNAV_CHECK_RESULT
int32_t qnav_link_policy_from_blob(const uint8_t *blob, uint16_t len, qnav_policy_t *policy);

/* One line of text for a QNAV_LINK_* status (a positive value is a byte count); never
 * null. */
const char *qnav_link_status_str(int32_t status);

/* Receiver of a chunked upload; caller-owned. */
typedef struct {
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    uint16_t total;     /* announced blob length (0 = no upload under way) */
    uint16_t received;  /* contiguous bytes received from offset 0 */
} qnav_link_upload_t;

void qnav_link_upload_init(qnav_link_upload_t *up);

/* Take a chunk. Chunks must arrive in order from offset 0 (a chunk at offset 0 restarts
 * the upload); an out-of-order or oversized chunk aborts the upload. Returns QNAV_LINK_OK
 * or QNAV_LINK_E_VALUE. */
int32_t qnav_link_upload_chunk(qnav_link_upload_t *up, const qnav_link_policy_chunk_t *c);

/* Finish: check length and CRC and decode. Returns QNAV_LINK_ACK_OK with *policy, or
 * QNAV_LINK_ACK_BAD_LENGTH / _BAD_CRC / _BAD_POLICY. The upload is reset either way; its
 * bytes stay in up->blob until the next chunk (qnav_link_blob_shapes(up->blob, c->total)). */
int8_t qnav_link_upload_commit(qnav_link_upload_t *up, const qnav_link_policy_commit_t *c,
                               qnav_policy_t *policy);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_LINK_H */
