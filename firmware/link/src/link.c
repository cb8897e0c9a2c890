/*
 * The serial link codec (qnav/link.h): CRC-16, streaming COBS encoder, byte-at-a-time
 * decoder with drop counters, little-endian message packing and chunked policy upload.
 * Shared unchanged by the board firmware and navbridge. No heap, integers only, no
 * file-scope writable state; every buffer belongs to the caller.
 */
#include "qnav/link.h"

#include <stddef.h>

enum { RX_IDLE = 0, RX_IN_FRAME = 1, RX_DISCARD = 2 };

/* ---- little-endian helpers ---- */

static void put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

static void put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

static uint16_t get_u16(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
           ((uint32_t)p[3] << 24);
}

/* Two's complement reinterpretation without relying on implementation-defined casts. */
static int16_t as_i16(uint16_t v)
{
    return (v & 0x8000u) ? (int16_t)(-(int16_t)(uint16_t)(~v) - 1) : (int16_t)v;
}

static uint16_t as_u16(int16_t v)
{
    return (uint16_t)v;
}

static int32_t as_i32(uint32_t v)
{
    return (v & 0x80000000UL) ? (int32_t)(-(int32_t)(~v) - 1) : (int32_t)v;
}

/* ---- CRC-16/CCITT-FALSE, nibble table (32 bytes: small enough for any MCU) ---- */

static const uint16_t crc_nibble[16] = {
    0x0000u, 0x1021u, 0x2042u, 0x3063u, 0x4084u, 0x50A5u, 0x60C6u, 0x70E7u,
    0x8108u, 0x9129u, 0xA14Au, 0xB16Bu, 0xC18Cu, 0xD1ADu, 0xE1CEu, 0xF1EFu,
};

uint16_t qnav_link_crc16(uint16_t crc, const uint8_t *data, uint16_t len)
{
    uint16_t i;
    if (data == NULL) {
        return crc;
    }
    for (i = 0; i < len; ++i) {
        crc = (uint16_t)((uint16_t)(crc << 4) ^
                         crc_nibble[((crc >> 12) ^ (uint16_t)(data[i] >> 4)) & 0x0Fu]);
        crc = (uint16_t)((uint16_t)(crc << 4) ^
                         crc_nibble[((crc >> 12) ^ (uint16_t)(data[i] & 0x0Fu)) & 0x0Fu]);
    }
    return crc;
}

/* ---- message lengths ---- */

uint16_t qnav_link_min_payload(uint8_t msg_id)
{
    switch (msg_id) {
    case QNAV_LINK_MSG_SCAN: return (uint16_t)(QNAV_LINK_SCAN_HEADER_BYTES + 2u);
    case QNAV_LINK_MSG_GOAL: return QNAV_LINK_GOAL_BYTES;
    case QNAV_LINK_MSG_COMMAND: return QNAV_LINK_COMMAND_BYTES;
    case QNAV_LINK_MSG_POLICY_CHUNK: return (uint16_t)(QNAV_LINK_POLICY_CHUNK_HEADER_BYTES + 1u);
    case QNAV_LINK_MSG_POLICY_COMMIT: return QNAV_LINK_POLICY_COMMIT_BYTES;
    case QNAV_LINK_MSG_POLICY_ACK: return QNAV_LINK_POLICY_ACK_BYTES;
    case QNAV_LINK_MSG_HEARTBEAT: return QNAV_LINK_HEARTBEAT_V1_BYTES;
    case QNAV_LINK_MSG_POSE: return QNAV_LINK_POSE_BYTES;
    case QNAV_LINK_MSG_CONFIG: return 1u;
    default: return 0;
    }
}

/* Whether len is a valid payload length for msg_id (the decoder's length check). */
static uint8_t length_ok(uint8_t msg_id, uint16_t len)
{
    uint16_t n;
    switch (msg_id) {
    case QNAV_LINK_MSG_SCAN:
        if (len < QNAV_LINK_SCAN_HEADER_BYTES + 2u || (len & 1u) != 0u) {
            return 0;
        }
        n = (uint16_t)((len - QNAV_LINK_SCAN_HEADER_BYTES) / 2u);
        return (uint8_t)(n <= QNAV_LINK_MAX_SECTORS);
    case QNAV_LINK_MSG_POLICY_CHUNK:
        return (uint8_t)(len > QNAV_LINK_POLICY_CHUNK_HEADER_BYTES &&
                         len <= QNAV_LINK_CHUNK_MAX_BYTES);
    case QNAV_LINK_MSG_CONFIG:
        return (uint8_t)(len >= 1u && len <= QNAV_LINK_CONFIG_MAX_BYTES && (len - 1u) % 5u == 0u);
    case QNAV_LINK_MSG_HEARTBEAT:
        /* every version's, so that a peer of another version is heard and refused */
        return (uint8_t)(len >= QNAV_LINK_HEARTBEAT_V1_BYTES &&
                         len <= QNAV_LINK_HEARTBEAT_MAX_BYTES);
    default:
        return (uint8_t)(len == qnav_link_min_payload(msg_id) && len != 0u);
    }
}

/* ---- decoder ---- */

void qnav_link_rx_init(qnav_link_rx_t *rx)
{
    uint8_t i;
    if (rx == NULL) {
        return;
    }
    rx->n = 0;
    rx->code = 0;
    rx->left = 0;
    rx->state = RX_IDLE;
    rx->have_seq = 0;
    rx->last_seq = 0;
    rx->stats.frames_ok = 0;
    rx->stats.seq_gaps = 0;
    for (i = 0; i < QNAV_LINK_DROP_REASONS; ++i) {
        rx->stats.dropped[i] = 0;
    }
}

void qnav_link_rx_reset_seq(qnav_link_rx_t *rx)
{
    if (rx != NULL) {
        rx->have_seq = 0;
    }
}

uint32_t qnav_link_rx_dropped_total(const qnav_link_rx_t *rx)
{
    uint32_t sum = 0;
    uint8_t i;
    if (rx == NULL) {
        return 0;
    }
    for (i = 0; i < QNAV_LINK_DROP_REASONS; ++i) {
        sum += rx->stats.dropped[i];
    }
    return sum;
}

static void drop(qnav_link_rx_t *rx, qnav_link_drop_t why)
{
    rx->stats.dropped[why]++;
}

/* A delimiter arrived: judge the frame collected so far. */
static uint8_t finish_frame(qnav_link_rx_t *rx, qnav_link_frame_t *frame)
{
    uint16_t crc_rx;
    uint16_t crc_calc;
    uint16_t plen;
    uint16_t seq;
    uint16_t ahead;
    uint8_t id;

    if (rx->left != 0u) {
        drop(rx, QNAV_LINK_DROP_COBS); /* block promised more bytes than arrived */
        return 0;
    }
    if (rx->n < QNAV_LINK_FRAME_OVERHEAD) {
        drop(rx, QNAV_LINK_DROP_SHORT);
        return 0;
    }
    plen = (uint16_t)(rx->n - QNAV_LINK_FRAME_OVERHEAD);
    crc_rx = get_u16(&rx->buf[rx->n - 2u]);
    crc_calc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, rx->buf, (uint16_t)(rx->n - 2u));
    if (crc_rx != crc_calc) {
        drop(rx, QNAV_LINK_DROP_CRC);
        return 0;
    }
    id = rx->buf[0];
    if (qnav_link_min_payload(id) == 0u) {
        drop(rx, QNAV_LINK_DROP_UNKNOWN);
        return 0;
    }
    if (!length_ok(id, plen)) {
        drop(rx, QNAV_LINK_DROP_LENGTH);
        return 0;
    }
    seq = get_u16(&rx->buf[1]);
    if (rx->have_seq) {
        ahead = (uint16_t)(seq - rx->last_seq);
        if (ahead == 0u || ahead > 0x7FFFu) {
            drop(rx, QNAV_LINK_DROP_SEQ);
            return 0;
        }
        if (ahead > 1u) {
            rx->stats.seq_gaps++;
        }
    }
    rx->have_seq = 1;
    rx->last_seq = seq;
    rx->stats.frames_ok++;
    frame->msg_id = id;
    frame->seq = seq;
    frame->payload = &rx->buf[3];
    frame->len = plen;
    return 1;
}

uint8_t qnav_link_rx_feed(qnav_link_rx_t *rx, uint8_t byte, qnav_link_frame_t *frame)
{
    uint8_t got = 0;
    if (rx == NULL || frame == NULL) {
        return 0;
    }
    if (byte == 0u) {
        if (rx->state == RX_IN_FRAME) {
            got = finish_frame(rx, frame);
        }
        /* an empty frame (two delimiters in a row) is just idle line: not counted */
        rx->state = RX_IDLE;
        rx->n = 0;
        rx->left = 0;
        rx->code = 0;
        return got;
    }
    if (rx->state == RX_DISCARD) {
        return 0;
    }
    if (rx->state == RX_IDLE) {
        rx->state = RX_IN_FRAME;
        rx->code = byte;
        rx->left = (uint8_t)(byte - 1u);
        return 0;
    }
    if (rx->left == 0u) {
        /* a new code byte; the block before it ends in an implied zero unless it was a
         * full 254-byte block (code 0xFF) */
        if (rx->code != 0xFFu) {
            if (rx->n >= QNAV_LINK_MAX_FRAME) {
                drop(rx, QNAV_LINK_DROP_OVERFLOW);
                rx->state = RX_DISCARD;
                return 0;
            }
            rx->buf[rx->n++] = 0u;
        }
        rx->code = byte;
        rx->left = (uint8_t)(byte - 1u);
        return 0;
    }
    if (rx->n >= QNAV_LINK_MAX_FRAME) {
        drop(rx, QNAV_LINK_DROP_OVERFLOW);
        rx->state = RX_DISCARD;
        return 0;
    }
    rx->buf[rx->n++] = byte;
    rx->left--;
    return 0;
}

/* ---- encoder ---- */

void qnav_link_tx_init(qnav_link_tx_t *tx)
{
    if (tx != NULL) {
        tx->next_seq = 0;
        tx->frames_sent = 0;
    }
}

/* Streaming COBS writer over the caller's buffer. */
typedef struct {
    uint8_t *out;
    uint16_t cap;
    uint16_t pos;      /* next unused byte */
    uint16_t code_at;  /* where the current block's code byte goes */
    uint8_t code;      /* current block code (1 + data bytes in block) */
    uint8_t full;      /* 1 when out of space */
} cobs_writer_t;

static void cobs_start(cobs_writer_t *w)
{
    w->code_at = w->pos;
    w->code = 1;
    if (w->pos < w->cap) {
        w->pos++;
    } else {
        w->full = 1;
    }
}

static void cobs_put(cobs_writer_t *w, uint8_t b)
{
    if (w->full) {
        return;
    }
    if (b == 0u) {
        w->out[w->code_at] = w->code;
        cobs_start(w);
        return;
    }
    if (w->pos >= w->cap) {
        w->full = 1;
        return;
    }
    w->out[w->pos++] = b;
    w->code++;
    if (w->code == 0xFFu) {
        w->out[w->code_at] = w->code;
        cobs_start(w);
    }
}

int32_t qnav_link_encode(qnav_link_tx_t *tx, uint8_t msg_id, const uint8_t *payload,
                         uint16_t len, uint8_t *out, uint16_t cap)
{
    cobs_writer_t w;
    uint8_t head[3];
    uint8_t tail[2];
    uint16_t crc;
    uint16_t i;

    if (tx == NULL || out == NULL || (payload == NULL && len != 0u)) {
        return QNAV_LINK_E_NULL;
    }
    if (len > QNAV_LINK_MAX_PAYLOAD) {
        return QNAV_LINK_E_LENGTH;
    }
    if (cap < 3u) {
        return QNAV_LINK_E_SPACE;
    }
    head[0] = msg_id;
    put_u16(&head[1], tx->next_seq);
    crc = qnav_link_crc16(QNAV_LINK_CRC16_INIT, head, 3u);
    crc = qnav_link_crc16(crc, payload, len);
    put_u16(tail, crc);

    w.out = out;
    w.cap = (uint16_t)(cap - 1u); /* keep room for the trailing delimiter */
    w.pos = 0;
    w.full = 0;
    out[w.pos++] = 0u;            /* leading delimiter: ends any line noise before us */
    cobs_start(&w);
    for (i = 0; i < 3u; ++i) {
        cobs_put(&w, head[i]);
    }
    for (i = 0; i < len; ++i) {
        cobs_put(&w, payload[i]);
    }
    cobs_put(&w, tail[0]);
    cobs_put(&w, tail[1]);
    if (w.full) {
        return QNAV_LINK_E_SPACE;
    }
    out[w.code_at] = w.code;
    out[w.pos++] = 0u;
    tx->next_seq = (uint16_t)(tx->next_seq + 1u);
    tx->frames_sent++;
    return (int32_t)w.pos;
}

/* ---- messages ---- */

int32_t qnav_link_scan_pack(const qnav_link_scan_t *m, uint8_t *out, uint16_t cap)
{
    uint16_t need;
    uint16_t k;
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (m->n_sectors < 1u || m->n_sectors > QNAV_LINK_MAX_SECTORS) {
        return QNAV_LINK_E_VALUE;
    }
    need = (uint16_t)(QNAV_LINK_SCAN_HEADER_BYTES + 2u * m->n_sectors);
    if (cap < need) {
        return QNAV_LINK_E_SPACE;
    }
    put_u32(&out[0], m->board_ms);
    put_u16(&out[4], as_u16(m->goal_bearing_cdeg));
    put_u16(&out[6], m->max_range_mm);
    put_u16(&out[8], m->n_sectors);
    put_u16(&out[10], m->goal_id);
    for (k = 0; k < m->n_sectors; ++k) {
        put_u16(&out[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k], m->ranges_mm[k]);
    }
    return (int32_t)need;
}

int32_t qnav_link_scan_unpack(const uint8_t *p, uint16_t len, qnav_link_scan_t *m)
{
    uint16_t n;
    uint16_t k;
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len < QNAV_LINK_SCAN_HEADER_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    n = get_u16(&p[8]);
    if (n < 1u || n > QNAV_LINK_MAX_SECTORS) {
        return QNAV_LINK_E_VALUE;
    }
    if (len != QNAV_LINK_SCAN_HEADER_BYTES + 2u * n) {
        return QNAV_LINK_E_LENGTH;
    }
    m->board_ms = get_u32(&p[0]);
    m->goal_bearing_cdeg = as_i16(get_u16(&p[4]));
    m->max_range_mm = get_u16(&p[6]);
    m->n_sectors = n;
    m->goal_id = get_u16(&p[10]);
    for (k = 0; k < n; ++k) {
        m->ranges_mm[k] = get_u16(&p[QNAV_LINK_SCAN_HEADER_BYTES + 2u * k]);
    }
    return QNAV_LINK_OK;
}

int32_t qnav_link_goal_pack(const qnav_link_goal_t *m, uint8_t *out, uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_GOAL_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    put_u16(&out[0], m->goal_id);
    put_u16(&out[2], as_u16(m->bearing_cdeg));
    put_u32(&out[4], m->distance_mm);
    out[8] = m->kind;
    put_u32(&out[9], (uint32_t)m->x_mm);
    put_u32(&out[13], (uint32_t)m->y_mm);
    return (int32_t)QNAV_LINK_GOAL_BYTES;
}

int32_t qnav_link_goal_unpack(const uint8_t *p, uint16_t len, qnav_link_goal_t *m)
{
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len != QNAV_LINK_GOAL_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    m->goal_id = get_u16(&p[0]);
    m->bearing_cdeg = as_i16(get_u16(&p[2]));
    m->distance_mm = get_u32(&p[4]);
    m->kind = p[8];
    m->x_mm = as_i32(get_u32(&p[9]));
    m->y_mm = as_i32(get_u32(&p[13]));
    if (m->kind != QNAV_LINK_GOAL_BEARING && m->kind != QNAV_LINK_GOAL_POSITION) {
        return QNAV_LINK_E_VALUE;
    }
    return QNAV_LINK_OK;
}

int32_t qnav_link_command_pack(const qnav_link_command_t *m, uint8_t *out, uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_COMMAND_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    if (m->speed < 0 || m->heading_deg < -180 || m->heading_deg > 180) {
        return QNAV_LINK_E_VALUE;
    }
    put_u16(&out[0], m->scan_seq);
    put_u16(&out[2], as_u16(m->heading_deg));
    put_u16(&out[4], as_u16(m->speed));
    put_u16(&out[6], as_u16(m->quality));
    out[8] = m->flags;
    out[9] = 0u;
    return (int32_t)QNAV_LINK_COMMAND_BYTES;
}

int32_t qnav_link_command_unpack(const uint8_t *p, uint16_t len, qnav_link_command_t *m)
{
    qnav_link_command_t c;
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len != QNAV_LINK_COMMAND_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    c.scan_seq = get_u16(&p[0]);
    c.heading_deg = as_i16(get_u16(&p[2]));
    c.speed = as_i16(get_u16(&p[4]));
    c.quality = as_i16(get_u16(&p[6]));
    c.flags = p[8];
    c.reserved = p[9];
    if (c.speed < 0 || c.heading_deg < -180 || c.heading_deg > 180) {
        return QNAV_LINK_E_VALUE;
    }
    *m = c;
    return QNAV_LINK_OK;
}

int32_t qnav_link_policy_chunk_pack(const qnav_link_policy_chunk_t *m, uint8_t *out,
                                    uint16_t cap)
{
    uint16_t need;
    uint8_t i;
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (m->len < 1u || m->len > QNAV_LINK_CHUNK_BYTES) {
        return QNAV_LINK_E_VALUE;
    }
    need = (uint16_t)(QNAV_LINK_POLICY_CHUNK_HEADER_BYTES + m->len);
    if (cap < need) {
        return QNAV_LINK_E_SPACE;
    }
    put_u16(&out[0], m->offset);
    put_u16(&out[2], m->total);
    for (i = 0; i < m->len; ++i) {
        out[QNAV_LINK_POLICY_CHUNK_HEADER_BYTES + i] = m->data[i];
    }
    return (int32_t)need;
}

int32_t qnav_link_policy_chunk_unpack(const uint8_t *p, uint16_t len,
                                      qnav_link_policy_chunk_t *m)
{
    uint16_t n;
    uint16_t i;
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len <= QNAV_LINK_POLICY_CHUNK_HEADER_BYTES || len > QNAV_LINK_CHUNK_MAX_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    n = (uint16_t)(len - QNAV_LINK_POLICY_CHUNK_HEADER_BYTES);
    m->offset = get_u16(&p[0]);
    m->total = get_u16(&p[2]);
    m->len = (uint8_t)n;
    for (i = 0; i < n; ++i) {
        m->data[i] = p[QNAV_LINK_POLICY_CHUNK_HEADER_BYTES + i];
    }
    return QNAV_LINK_OK;
}

int32_t qnav_link_policy_commit_pack(const qnav_link_policy_commit_t *m, uint8_t *out,
                                     uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_POLICY_COMMIT_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    put_u16(&out[0], m->total);
    put_u16(&out[2], m->crc);
    return (int32_t)QNAV_LINK_POLICY_COMMIT_BYTES;
}

int32_t qnav_link_policy_commit_unpack(const uint8_t *p, uint16_t len,
                                       qnav_link_policy_commit_t *m)
{
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len != QNAV_LINK_POLICY_COMMIT_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    m->total = get_u16(&p[0]);
    m->crc = get_u16(&p[2]);
    return QNAV_LINK_OK;
}

int32_t qnav_link_policy_ack_pack(const qnav_link_policy_ack_t *m, uint8_t *out,
                                  uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_POLICY_ACK_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    out[0] = (uint8_t)m->status;
    out[1] = 0u;
    put_u16(&out[2], m->crc);
    return (int32_t)QNAV_LINK_POLICY_ACK_BYTES;
}

int32_t qnav_link_policy_ack_unpack(const uint8_t *p, uint16_t len,
                                    qnav_link_policy_ack_t *m)
{
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len != QNAV_LINK_POLICY_ACK_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    m->status = (int8_t)((p[0] & 0x80u) ? (int16_t)p[0] - 256 : (int16_t)p[0]);
    m->reserved = p[1];
    m->crc = get_u16(&p[2]);
    return QNAV_LINK_OK;
}

int32_t qnav_link_heartbeat_pack(const qnav_link_heartbeat_t *m, uint8_t *out, uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_HEARTBEAT_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    put_u32(&out[0], m->uptime_ms);
    out[4] = m->mode;
    out[5] = m->state;
    put_u16(&out[6], m->rx_ok);
    put_u16(&out[8], m->rx_dropped);
    put_u16(&out[10], m->policy_crc);
    out[12] = (uint8_t)QNAV_LINK_PROTOCOL_VERSION;
    return (int32_t)QNAV_LINK_HEARTBEAT_BYTES;
}

int32_t qnav_link_heartbeat_unpack(const uint8_t *p, uint16_t len, qnav_link_heartbeat_t *m)
{
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len < QNAV_LINK_HEARTBEAT_V1_BYTES || len > QNAV_LINK_HEARTBEAT_MAX_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    m->uptime_ms = get_u32(&p[0]);
    m->mode = p[4];
    m->state = p[5];
    m->rx_ok = get_u16(&p[6]);
    m->rx_dropped = get_u16(&p[8]);
    m->policy_crc = get_u16(&p[10]);
    m->protocol = len == QNAV_LINK_HEARTBEAT_V1_BYTES ? 1u : p[12];
    return QNAV_LINK_OK;
}

int32_t qnav_link_pose_pack(const qnav_link_pose_t *m, uint8_t *out, uint16_t cap)
{
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (cap < QNAV_LINK_POSE_BYTES) {
        return QNAV_LINK_E_SPACE;
    }
    if (m->escape_clear > 1u) {
        return QNAV_LINK_E_VALUE;
    }
    put_u32(&out[0], m->board_ms);
    put_u32(&out[4], (uint32_t)m->x_mm);
    put_u32(&out[8], (uint32_t)m->y_mm);
    put_u16(&out[12], as_u16(m->heading_cdeg));
    put_u16(&out[14], m->goal_id);
    put_u32(&out[16], m->goal_distance_mm);
    out[20] = m->escape_clear;
    put_u16(&out[21], m->escape_grow_mm);
    return (int32_t)QNAV_LINK_POSE_BYTES;
}

int32_t qnav_link_pose_unpack(const uint8_t *p, uint16_t len, qnav_link_pose_t *m)
{
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len != QNAV_LINK_POSE_BYTES) {
        return QNAV_LINK_E_LENGTH;
    }
    m->board_ms = get_u32(&p[0]);
    m->x_mm = as_i32(get_u32(&p[4]));
    m->y_mm = as_i32(get_u32(&p[8]));
    m->heading_cdeg = as_i16(get_u16(&p[12]));
    m->goal_id = get_u16(&p[14]);
    m->goal_distance_mm = get_u32(&p[16]);
    m->escape_clear = p[20];
    m->escape_grow_mm = get_u16(&p[21]);
    return m->escape_clear > 1u ? QNAV_LINK_E_VALUE : QNAV_LINK_OK;
}

/* ---- policy blobs ---- */

/* Byte 1 of a network blob: hidden units in bits 0..5, bit 7 set for the third input. */
#define BLOB_NET_PREV 0x80u
#define BLOB_NET_HIDDEN 0x3Fu

static int32_t net_to_blob(const qnav_net_t *src, uint8_t *out, uint16_t cap)
{
    qnav_net_t net = *src; /* qnav_net_weight() takes a mutable net: use a copy */
    uint16_t nw = qnav_net_weight_count(&net);
    uint16_t need = (uint16_t)(2u + 2u * nw);
    uint16_t k;
    if (cap < need) {
        return QNAV_LINK_E_SPACE;
    }
    out[0] = QNAV_POLICY_NET;
    out[1] = (uint8_t)(net.hidden | (net.inputs == QNAV_NET_INPUTS_PREV ? BLOB_NET_PREV : 0u));
    for (k = 0; k < nw; ++k) {
        put_u16(&out[2u + 2u * k], as_u16(*qnav_net_weight(&net, k)));
    }
    return (int32_t)need;
}

/* A blob's length without carried shapes, from its first two bytes (0: not a blob). */
static uint16_t blob_weights_len(const uint8_t *blob)
{
    switch ((qnav_policy_kind_t)blob[0]) {
    case QNAV_POLICY_PROB:
        return 6u;
    case QNAV_POLICY_NET:
        return (uint16_t)(2u + 2u * QNAV_NET_WEIGHTS_IN(
                                        (uint16_t)(blob[1] & BLOB_NET_HIDDEN),
                                        (blob[1] & BLOB_NET_PREV) != 0u ? 3u : 2u));
    }
    return 0u;
}

/* Carried shapes may follow only a 2-input network's weights. */
static uint8_t blob_may_carry(const uint8_t *blob)
{
    return (uint8_t)(blob[0] == (uint8_t)QNAV_POLICY_NET && (blob[1] & BLOB_NET_PREV) == 0u);
}

int32_t qnav_link_policy_to_blob_carried(const qnav_policy_t *policy, const uint8_t *shapes,
                                         uint8_t *out, uint16_t cap)
{
    int32_t n = qnav_link_policy_to_blob(policy, out, cap);
    uint16_t k;
    if (n <= 0 || shapes == NULL) {
        return n;
    }
    if (!blob_may_carry(out)) {
        return QNAV_LINK_E_VALUE;
    }
    if ((uint32_t)n + QNAV_SHAPES_BYTES > cap) {
        return QNAV_LINK_E_SPACE;
    }
    for (k = 0; k < QNAV_SHAPES_BYTES; ++k) {
        out[(uint16_t)n + k] = shapes[k];
    }
    return n + (int32_t)QNAV_SHAPES_BYTES;
}

const uint8_t *qnav_link_blob_shapes(const uint8_t *blob, uint16_t len)
{
    uint16_t w;
    if (blob == NULL || len < 2u || !blob_may_carry(blob)) {
        return NULL;
    }
    w = blob_weights_len(blob);
    return len == (uint32_t)w + QNAV_SHAPES_BYTES ? &blob[w] : NULL;
}

int32_t qnav_link_policy_to_blob(const qnav_policy_t *policy, uint8_t *out, uint16_t cap)
{
    if (policy == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (qnav_policy_validate(policy) != QNAV_POLICY_OK) {
        return QNAV_LINK_E_VALUE;
    }
    switch ((qnav_policy_kind_t)policy->kind) {
    case QNAV_POLICY_PROB:
        if (cap < 6u) {
            return QNAV_LINK_E_SPACE;
        }
        out[0] = QNAV_POLICY_PROB;
        out[1] = 0u;
        put_u16(&out[2], as_u16(policy->u.prob.k_goal));
        put_u16(&out[4], as_u16(policy->u.prob.k_safe));
        return 6;
    case QNAV_POLICY_NET:
        return net_to_blob(&policy->u.net, out, cap);
    }
    return QNAV_LINK_E_VALUE;
}

static int32_t net_from_blob(const uint8_t *blob, uint16_t len, qnav_policy_t *p)
{
    uint8_t hidden = (uint8_t)(blob[1] & BLOB_NET_HIDDEN);
    uint16_t nw;
    uint16_t k;
    if ((blob[1] & (uint8_t)~(BLOB_NET_HIDDEN | BLOB_NET_PREV)) != 0u || hidden < 1u ||
        hidden > QNAV_MAX_HIDDEN) {
        return QNAV_LINK_E_VALUE;
    }
    qnav_policy_net_zero_inputs(p, hidden, (blob[1] & BLOB_NET_PREV) != 0u
                                               ? (uint8_t)QNAV_NET_INPUTS_PREV
                                               : (uint8_t)QNAV_NET_INPUTS_PAPER);
    nw = qnav_net_weight_count(&p->u.net);
    if (len != 2u + 2u * nw &&
        !(blob_may_carry(blob) && len == 2u + 2u * nw + QNAV_SHAPES_BYTES)) {
        return QNAV_LINK_E_LENGTH;
    }
    for (k = 0; k < nw; ++k) {
        *qnav_net_weight(&p->u.net, k) = as_i16(get_u16(&blob[2u + 2u * k]));
    }
    return QNAV_LINK_OK;
}

int32_t qnav_link_policy_from_blob(const uint8_t *blob, uint16_t len, qnav_policy_t *policy)
{
    qnav_policy_t p;
    int32_t rc = QNAV_LINK_E_VALUE;

    if (blob == NULL || policy == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len < 2u) {
        return QNAV_LINK_E_LENGTH;
    }
    switch ((qnav_policy_kind_t)blob[0]) {
    case QNAV_POLICY_PROB:
        if (len != 6u) {
            return QNAV_LINK_E_LENGTH;
        }
        if (blob[1] != 0u) {
            return QNAV_LINK_E_VALUE;
        }
        qnav_policy_prob_default(&p);
        p.u.prob.k_goal = as_i16(get_u16(&blob[2]));
        p.u.prob.k_safe = as_i16(get_u16(&blob[4]));
        rc = QNAV_LINK_OK;
        break;
    case QNAV_POLICY_NET:
        rc = net_from_blob(blob, len, &p);
        break;
    }
    if (rc != QNAV_LINK_OK) {
        return rc;
    }
    /* the writer's rule (qnav_link_policy_to_blob), so a blob the writer refuses is refused
     * here too: a probabilistic k_goal or k_safe outside (0, 64] */
    if (qnav_policy_validate(&p) != QNAV_POLICY_OK) {
        return QNAV_LINK_E_VALUE;
    }
    *policy = p;
    return QNAV_LINK_OK;
}

const char *qnav_link_status_str(int32_t status)
{
    switch (status) {
    case QNAV_LINK_OK:
        return "ok";
    case QNAV_LINK_E_NULL:
        return "a required pointer was null";
    case QNAV_LINK_E_SPACE:
        return "the output buffer is too small";
    case QNAV_LINK_E_LENGTH:
        return "payload length wrong for the message";
    case QNAV_LINK_E_VALUE:
        return "a field is out of its range";
    default:
        return status > 0 ? "ok (bytes written)" : "unknown link status";
    }
}

void qnav_link_upload_init(qnav_link_upload_t *up)
{
    if (up != NULL) {
        up->total = 0;
        up->received = 0;
    }
}

int32_t qnav_link_upload_chunk(qnav_link_upload_t *up, const qnav_link_policy_chunk_t *c)
{
    uint8_t i;
    if (up == NULL || c == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (c->offset == 0u) {
        up->total = 0;
        up->received = 0;
    }
    if (c->total == 0u || c->total > QNAV_LINK_POLICY_MAX_BYTES || c->len < 1u ||
        c->len > QNAV_LINK_CHUNK_BYTES || (up->received != 0u && c->total != up->total) ||
        c->offset != up->received || (uint32_t)c->offset + c->len > c->total) {
        qnav_link_upload_init(up);
        return QNAV_LINK_E_VALUE;
    }
    up->total = c->total;
    for (i = 0; i < c->len; ++i) {
        up->blob[c->offset + i] = c->data[i];
    }
    up->received = (uint16_t)(up->received + c->len);
    return QNAV_LINK_OK;
}

int8_t qnav_link_upload_commit(qnav_link_upload_t *up, const qnav_link_policy_commit_t *c,
                               qnav_policy_t *policy)
{
    int8_t result;
    if (up == NULL || c == NULL || policy == NULL) {
        return QNAV_LINK_ACK_BAD_POLICY;
    }
    if (up->total == 0u || c->total != up->total || up->received != up->total) {
        result = QNAV_LINK_ACK_BAD_LENGTH;
    } else if (qnav_link_crc16(QNAV_LINK_CRC16_INIT, up->blob, up->total) != c->crc) {
        result = QNAV_LINK_ACK_BAD_CRC;
    } else if (qnav_link_policy_from_blob(up->blob, up->total, policy) != QNAV_LINK_OK) {
        result = QNAV_LINK_ACK_BAD_POLICY;
    } else {
        result = QNAV_LINK_ACK_OK;
    }
    qnav_link_upload_init(up);
    return result;
}

int32_t qnav_link_send(qnav_link_tx_t *tx, uint8_t msg_id, const uint8_t *payload,
                       int32_t len, uint8_t *wire, uint16_t cap, qnav_link_write_fn write,
                       void *user)
{
    int32_t n;
    if (len < 0) {
        return len;
    }
    if (write == NULL) {
        return QNAV_LINK_E_NULL;
    }
    n = qnav_link_encode(tx, msg_id, payload, (uint16_t)len, wire, cap);
    if (n > 0) {
        write(user, wire, (uint16_t)n);
    }
    return n;
}

uint16_t qnav_link_policy_crc(const qnav_policy_t *policy)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n = qnav_link_policy_to_blob(policy, blob, (uint16_t)sizeof blob);
    return n > 0 ? qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, (uint16_t)n) : 0u;
}

int32_t qnav_link_config_append(uint8_t *out, uint16_t cap, uint8_t key, int32_t value)
{
    uint16_t at;
    if (out == NULL || cap < 1u) {
        return out == NULL ? QNAV_LINK_E_NULL : QNAV_LINK_E_SPACE;
    }
    if (out[0] >= QNAV_LINK_CONFIG_MAX_FIELDS) {
        return QNAV_LINK_E_VALUE;
    }
    at = (uint16_t)(1u + 5u * out[0]);
    if (cap < at + 5u) {
        return QNAV_LINK_E_SPACE;
    }
    out[at] = key;
    put_u32(&out[at + 1u], (uint32_t)value);
    out[0]++;
    return (int32_t)(at + 5u);
}

int32_t qnav_link_config_pack(const qnav_link_config_t *m, uint8_t *out, uint16_t cap)
{
    uint8_t k;
    int32_t len = 1;
    if (m == NULL || out == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (m->n > QNAV_LINK_CONFIG_MAX_FIELDS) {
        return QNAV_LINK_E_VALUE;
    }
    if (cap < (uint16_t)(1u + 5u * m->n)) {
        return QNAV_LINK_E_SPACE;
    }
    out[0] = 0;
    for (k = 0; k < m->n; ++k) {
        len = qnav_link_config_append(out, cap, m->key[k], m->value[k]);
    }
    return len;
}

int32_t qnav_link_config_unpack(const uint8_t *p, uint16_t len, qnav_link_config_t *m)
{
    uint8_t k;
    if (p == NULL || m == NULL) {
        return QNAV_LINK_E_NULL;
    }
    if (len < 1u || len > QNAV_LINK_CONFIG_MAX_BYTES || len != 1u + 5u * (uint16_t)p[0]) {
        return QNAV_LINK_E_LENGTH;
    }
    m->n = p[0];
    for (k = 0; k < m->n; ++k) {
        m->key[k] = p[1u + 5u * k];
        m->value[k] = (int32_t)get_u32(&p[2u + 5u * k]);
    }
    return QNAV_LINK_OK;
}
