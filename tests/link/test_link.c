/*
 * Unit tests of the serial link codec (firmware/link): CRC check value, round trips of
 * every message, each drop reason, sequence rules, chunked policy upload, and a fuzz
 * corpus (random bytes, every single bit flip, every truncation, random multi-byte
 * damage) that must never crash and never accept a frame that was not sent.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "qnav/link.h"

/* xorshift32: a fixed, seedable generator so every fuzz run sees the same corpus. */
static uint32_t rng_next(uint32_t *s)
{
    uint32_t x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *s = x;
    return x;
}

typedef struct {
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    uint16_t len;
} wire_t;

static wire_t encode(qnav_link_tx_t *tx, uint8_t id, const uint8_t *p, uint16_t n)
{
    wire_t w;
    int32_t r = qnav_link_encode(tx, id, p, n, w.wire, (uint16_t)sizeof w.wire);
    assert_true(r > 0);
    w.len = (uint16_t)r;
    return w;
}

/* Feed bytes; return how many frames were accepted; the last one lands in *last. */
static int feed(qnav_link_rx_t *rx, const uint8_t *b, size_t n, qnav_link_frame_t *last)
{
    int got = 0;
    size_t i;
    qnav_link_frame_t f;
    for (i = 0; i < n; ++i) {
        if (qnav_link_rx_feed(rx, b[i], &f)) {
            got++;
            if (last != NULL) {
                *last = f;
            }
        }
    }
    return got;
}

static uint16_t make_scan_payload(uint16_t n, uint8_t *out, uint16_t cap, uint32_t seed)
{
    qnav_link_scan_t s;
    uint16_t k;
    memset(&s, 0, sizeof s);
    s.board_ms = 123456u + seed;
    s.goal_bearing_cdeg = -4500;
    s.max_range_mm = 5000;
    s.n_sectors = n;
    s.goal_id = 3;
    for (k = 0; k < n; ++k) {
        s.ranges_mm[k] = (qnav_mm_t)(100u + 37u * k + seed); /* includes bytes of 0x00 */
    }
    return (uint16_t)qnav_link_scan_pack(&s, out, cap);
}

static void test_crc16_matches_ccitt_false_check_value(void **state)
{
    const uint8_t check[] = "123456789";
    (void)state;
    assert_int_equal(qnav_link_crc16(QNAV_LINK_CRC16_INIT, check, 9), 0x29B1);
}

static void test_codec_round_trips_scan_of_360_sectors(void **state)
{
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    qnav_link_scan_t s;
    uint16_t n;
    wire_t w;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    n = make_scan_payload(360, p, sizeof p, 0);
    assert_int_equal(n, 12 + 720);
    w = encode(&tx, QNAV_LINK_MSG_SCAN, p, n);
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(f.msg_id, QNAV_LINK_MSG_SCAN);
    assert_int_equal(f.seq, 0);
    assert_int_equal(f.len, n);
    assert_memory_equal(f.payload, p, n);
    assert_int_equal(qnav_link_scan_unpack(f.payload, f.len, &s), QNAV_LINK_OK);
    assert_int_equal(s.n_sectors, 360);
    assert_int_equal(s.goal_bearing_cdeg, -4500);
    assert_int_equal(s.ranges_mm[359], 100 + 37 * 359);
    assert_int_equal(rx.stats.frames_ok, 1);
    assert_int_equal(qnav_link_rx_dropped_total(&rx), 0);
}

static void test_codec_round_trips_every_small_message(void **state)
{
    uint8_t p[64];
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    wire_t w;
    qnav_link_goal_t g = {7, -17999, 123456u}, g2;
    qnav_link_command_t c = {42, -179, 32767, 12345, 0x81, 0}, c2;
    qnav_link_policy_commit_t pc = {260, 0xBEEF}, pc2;
    qnav_link_policy_ack_t pa = {QNAV_LINK_ACK_BAD_CRC, 0, 0x1234}, pa2;
    qnav_link_heartbeat_t hb = {0xFFFFFFF0u, QNAV_LINK_MODE_ONBOARD, 0x05, 65535, 2, 0xABCD},
                          hb2;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);

    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(qnav_link_goal_unpack(f.payload, f.len, &g2), QNAV_LINK_OK);
    assert_int_equal(g2.goal_id, 7);
    assert_int_equal(g2.bearing_cdeg, -17999);
    assert_int_equal(g2.distance_mm, 123456u);

    w = encode(&tx, QNAV_LINK_MSG_COMMAND, p,
               (uint16_t)qnav_link_command_pack(&c, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(qnav_link_command_unpack(f.payload, f.len, &c2), QNAV_LINK_OK);
    assert_int_equal(c2.scan_seq, 42);
    assert_int_equal(c2.heading_deg, -179);
    assert_int_equal(c2.speed, 32767);
    assert_int_equal(c2.quality, 12345);
    assert_int_equal(c2.flags, 0x81);

    w = encode(&tx, QNAV_LINK_MSG_POLICY_COMMIT, p,
               (uint16_t)qnav_link_policy_commit_pack(&pc, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(qnav_link_policy_commit_unpack(f.payload, f.len, &pc2), QNAV_LINK_OK);
    assert_int_equal(pc2.total, 260);
    assert_int_equal(pc2.crc, 0xBEEF);

    w = encode(&tx, QNAV_LINK_MSG_POLICY_ACK, p,
               (uint16_t)qnav_link_policy_ack_pack(&pa, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(qnav_link_policy_ack_unpack(f.payload, f.len, &pa2), QNAV_LINK_OK);
    assert_int_equal(pa2.status, QNAV_LINK_ACK_BAD_CRC);
    assert_int_equal(pa2.crc, 0x1234);

    w = encode(&tx, QNAV_LINK_MSG_HEARTBEAT, p,
               (uint16_t)qnav_link_heartbeat_pack(&hb, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(qnav_link_heartbeat_unpack(f.payload, f.len, &hb2), QNAV_LINK_OK);
    assert_int_equal(hb2.uptime_ms, 0xFFFFFFF0u);
    assert_int_equal(hb2.mode, QNAV_LINK_MODE_ONBOARD);
    assert_int_equal(hb2.state, 0x05);
    assert_int_equal(hb2.rx_ok, 65535);
    assert_int_equal(hb2.policy_crc, 0xABCD);
    assert_int_equal(f.seq, 4);
    assert_int_equal(rx.stats.frames_ok, 5);
}

static void test_codec_drops_frame_with_bad_crc(void **state)
{
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_goal_t g = {0x0101u, 0x0202, 0x01020304u}; /* no zero bytes: no COBS codes */
    wire_t w;
    (void)state;
    qnav_link_tx_init(&tx);
    tx.next_seq = 0x0101u;
    qnav_link_rx_init(&rx);
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    assert_int_equal(w.wire[6], 0x01); /* low byte of goal_id */
    w.wire[6] ^= 0x02;
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_CRC], 1);
    assert_int_equal(rx.stats.frames_ok, 0);
}

static void test_codec_drops_truncated_frame_and_takes_the_next(void **state)
{
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    qnav_link_goal_t g = {1, 100, 5000};
    wire_t a, b;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    a = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    b = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    /* first frame cut after 6 bytes, then the second frame whole */
    assert_int_equal(feed(&rx, a.wire, 6, NULL), 0);
    assert_int_equal(feed(&rx, b.wire, b.len, &f), 1);
    assert_int_equal(f.seq, 1);
    assert_int_equal(qnav_link_rx_dropped_total(&rx), 1);
}

static void test_codec_drops_replayed_frame(void **state)
{
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_goal_t g = {1, 100, 5000};
    wire_t a, b;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    a = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    b = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    assert_int_equal(feed(&rx, a.wire, a.len, NULL), 1);
    assert_int_equal(feed(&rx, b.wire, b.len, NULL), 1);
    assert_int_equal(feed(&rx, a.wire, a.len, NULL), 0); /* older */
    assert_int_equal(feed(&rx, b.wire, b.len, NULL), 0); /* same */
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_SEQ], 2);
    assert_int_equal(rx.stats.frames_ok, 2);
}

static void test_codec_accepts_sequence_wrap_and_counts_gaps(void **state)
{
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    qnav_link_goal_t g = {1, 100, 5000};
    wire_t w;
    uint16_t n;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    n = (uint16_t)qnav_link_goal_pack(&g, p, sizeof p);
    tx.next_seq = 65534u;
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, n);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 1);
    tx.next_seq = 1u; /* 65535 and 0 lost */
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, n);
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    assert_int_equal(f.seq, 1);
    assert_int_equal(rx.stats.seq_gaps, 1);
}

static void test_codec_accepts_any_sequence_after_reset(void **state)
{
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_goal_t g = {1, 100, 5000};
    wire_t w;
    uint16_t n;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    n = (uint16_t)qnav_link_goal_pack(&g, p, sizeof p);
    tx.next_seq = 1000u;
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, n);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 1);
    qnav_link_tx_init(&tx); /* peer restarted at 0 */
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, n);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 0);
    qnav_link_rx_reset_seq(&rx);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 1);
}

static void test_codec_drops_unknown_id_and_wrong_length(void **state)
{
    uint8_t p[16] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    wire_t w;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    w = encode(&tx, 0x7E, p, 4);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 0);
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, 9);
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 0);
    w = encode(&tx, QNAV_LINK_MSG_SCAN, p, 13); /* odd scan length */
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_UNKNOWN], 1);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_LENGTH], 2);
    assert_int_equal(rx.stats.frames_ok, 0);
}

static void test_codec_drops_overlong_frame_and_recovers(void **state)
{
    uint8_t noise[QNAV_LINK_MAX_FRAME + 300];
    uint8_t p[32] = {0};
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_goal_t g = {1, 100, 5000};
    wire_t w;
    (void)state;
    memset(noise, 0x11, sizeof noise);
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    assert_int_equal(feed(&rx, noise, sizeof noise, NULL), 0);
    w = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, sizeof p));
    assert_int_equal(feed(&rx, w.wire, w.len, NULL), 1); /* its leading 0x00 resyncs */
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_OVERFLOW], 1);
}

static void test_codec_drops_frame_shorter_than_header(void **state)
{
    const uint8_t tiny[] = {0x00, 0x03, 0x01, 0x02, 0x00};
    qnav_link_rx_t rx;
    (void)state;
    qnav_link_rx_init(&rx);
    assert_int_equal(feed(&rx, tiny, sizeof tiny, NULL), 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_SHORT], 1);
}

static void test_codec_drops_cobs_block_running_past_delimiter(void **state)
{
    const uint8_t bad[] = {0x00, 0x09, 0x01, 0x02, 0x00};
    qnav_link_rx_t rx;
    (void)state;
    qnav_link_rx_init(&rx);
    assert_int_equal(feed(&rx, bad, sizeof bad, NULL), 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_COBS], 1);
}

static void test_encode_refuses_small_buffer_and_keeps_sequence(void **state)
{
    uint8_t p[32] = {0};
    uint8_t out[8];
    qnav_link_tx_t tx;
    (void)state;
    qnav_link_tx_init(&tx);
    assert_int_equal(qnav_link_encode(&tx, QNAV_LINK_MSG_GOAL, p, 8, out, sizeof out),
                     QNAV_LINK_E_SPACE);
    assert_int_equal(tx.next_seq, 0);
    assert_int_equal(qnav_link_encode(&tx, QNAV_LINK_MSG_GOAL, p, QNAV_LINK_MAX_PAYLOAD + 1,
                                      out, sizeof out),
                     QNAV_LINK_E_LENGTH);
}

/* ---- fuzz corpus ---- */

static void test_fuzz_random_bytes_never_accept_a_frame(void **state)
{
    static uint8_t junk[1u << 20];
    qnav_link_rx_t rx;
    uint32_t s = 0x1234567u;
    size_t i;
    (void)state;
    for (i = 0; i < sizeof junk; ++i) {
        /* one byte in 64 is a delimiter, so the decoder sees many candidate frames */
        uint32_t r = rng_next(&s);
        junk[i] = (r & 0x3F00u) == 0u ? 0u : (uint8_t)(r & 0xFFu);
    }
    qnav_link_rx_init(&rx);
    assert_int_equal(feed(&rx, junk, sizeof junk, NULL), 0);
    assert_true(qnav_link_rx_dropped_total(&rx) > 10000u);
}

/* A few frames of every kind, the corpus for flips and truncations. */
static int build_corpus(wire_t *out, int cap)
{
    uint8_t p[QNAV_LINK_MAX_PAYLOAD];
    qnav_link_tx_t tx;
    qnav_link_goal_t g = {9, 9000, 1000};
    qnav_link_command_t c = {5, 45, 20000, 22000, 0, 0};
    qnav_link_heartbeat_t hb = {1000, 1, 1, 10, 0, 0};
    int n = 0;
    uint16_t sectors[] = {1, 8, 16, 130, 360};
    size_t k;
    qnav_link_tx_init(&tx);
    tx.next_seq = 0x00FFu; /* sequence bytes that include 0x00 and 0xFF */
    for (k = 0; k < sizeof sectors / sizeof sectors[0] && n < cap; ++k) {
        out[n++] = encode(&tx, QNAV_LINK_MSG_SCAN, p,
                          make_scan_payload(sectors[k], p, sizeof p, (uint32_t)k));
    }
    out[n++] = encode(&tx, QNAV_LINK_MSG_GOAL, p, (uint16_t)qnav_link_goal_pack(&g, p, 64));
    out[n++] = encode(&tx, QNAV_LINK_MSG_COMMAND, p,
                      (uint16_t)qnav_link_command_pack(&c, p, 64));
    out[n++] = encode(&tx, QNAV_LINK_MSG_HEARTBEAT, p,
                      (uint16_t)qnav_link_heartbeat_pack(&hb, p, 64));
    return n;
}

static void test_fuzz_every_bit_flip_is_dropped(void **state)
{
    static wire_t corpus[8];
    qnav_link_rx_t rx;
    int n, k;
    uint16_t i;
    uint8_t bit;
    uint32_t accepted = 0, tried = 0;
    (void)state;
    n = build_corpus(corpus, 8);
    for (k = 0; k < n; ++k) {
        wire_t *w = &corpus[k];
        for (i = 1; i + 1u < w->len; ++i) { /* leave the delimiters alone */
            for (bit = 0; bit < 8; ++bit) {
                uint8_t save = w->wire[i];
                w->wire[i] = (uint8_t)(save ^ (1u << bit));
                qnav_link_rx_init(&rx);
                accepted += (uint32_t)feed(&rx, w->wire, w->len, NULL);
                tried++;
                w->wire[i] = save;
            }
        }
    }
    print_message("%u single-bit flips tried\n", (unsigned)tried);
    assert_true(tried > 8000u);
    assert_int_equal(accepted, 0);
}

static void test_fuzz_every_truncation_is_dropped(void **state)
{
    static wire_t corpus[8];
    qnav_link_rx_t rx;
    int n, k;
    uint16_t cut;
    uint32_t accepted = 0;
    const uint8_t delim = 0;
    (void)state;
    n = build_corpus(corpus, 8);
    for (k = 0; k < n; ++k) {
        for (cut = 1; cut + 1u < corpus[k].len; ++cut) {
            qnav_link_rx_init(&rx);
            accepted += (uint32_t)feed(&rx, corpus[k].wire, cut, NULL);
            accepted += (uint32_t)feed(&rx, &delim, 1, NULL);
        }
    }
    assert_int_equal(accepted, 0);
}

static void test_fuzz_random_damage_never_yields_a_frame_that_was_not_sent(void **state)
{
    static wire_t corpus[8];
    static uint8_t stream[1u << 16];
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    uint32_t s = 0xC0FFEEu;
    uint32_t round, good = 0;
    int n;
    (void)state;
    n = build_corpus(corpus, 8);
    for (round = 0; round < 200u; ++round) {
        size_t len = 0;
        size_t i;
        qnav_link_rx_init(&rx);
        /* a stream of corpus frames, some damaged by 1..4 random byte writes */
        while (len + sizeof corpus[0].wire < sizeof stream) {
            const wire_t *w = &corpus[rng_next(&s) % (uint32_t)n];
            memcpy(&stream[len], w->wire, w->len);
            if ((rng_next(&s) & 1u) != 0u) {
                uint32_t hits = 1u + rng_next(&s) % 4u;
                while (hits-- > 0u) {
                    stream[len + 1u + rng_next(&s) % (uint32_t)(w->len - 2u)] =
                        (uint8_t)rng_next(&s);
                }
            }
            len += w->len;
        }
        for (i = 0; i < len; ++i) {
            if (qnav_link_rx_feed(&rx, stream[i], &f)) {
                /* anything accepted must be byte-identical to a corpus frame's content */
                int k, match = 0;
                qnav_link_rx_t check;
                for (k = 0; k < n && !match; ++k) {
                    qnav_link_frame_t g;
                    qnav_link_rx_init(&check);
                    if (feed(&check, corpus[k].wire, corpus[k].len, &g) == 1 &&
                        g.msg_id == f.msg_id && g.seq == f.seq && g.len == f.len &&
                        memcmp(g.payload, f.payload, f.len) == 0) {
                        match = 1;
                    }
                }
                assert_true(match);
                good++;
            }
        }
    }
    /* the sequence rule lets each corpus frame through at most once per round */
    assert_true(good > 0u);
    assert_true(good <= 200u * (uint32_t)n);
}

/* ---- policy blobs and upload ---- */

static void make_net(qnav_policy_t *p, uint8_t hidden)
{
    uint16_t k;
    qnav_policy_net_zero(p, hidden);
    for (k = 0; k < QNAV_NET_WEIGHTS(hidden); ++k) {
        *qnav_net_weight(&p->u.net, k) = (qnav_q8_8_t)(k * 251 - 3000);
    }
}

static void test_policy_blob_round_trips_network_and_probabilistic(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    qnav_policy_t a, b;
    int32_t n;
    (void)state;
    make_net(&a, QNAV_MAX_HIDDEN);
    n = qnav_link_policy_to_blob(&a, blob, sizeof blob);
    assert_int_equal(n, 2 + 2 * QNAV_NET_WEIGHTS(QNAV_MAX_HIDDEN));
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)n, &b), QNAV_LINK_OK);
    assert_int_equal(b.kind, QNAV_POLICY_NET);
    assert_int_equal(b.u.net.hidden, QNAV_MAX_HIDDEN);
    assert_memory_equal(b.u.net.w_out, a.u.net.w_out, sizeof a.u.net.w_out);
    assert_int_equal(b.u.net.b_out, a.u.net.b_out);

    qnav_policy_prob_default(&a);
    a.u.prob.k_goal = 777;
    n = qnav_link_policy_to_blob(&a, blob, sizeof blob);
    assert_int_equal(n, 6);
    assert_int_equal(qnav_link_policy_from_blob(blob, 6, &b), QNAV_LINK_OK);
    assert_int_equal(b.kind, QNAV_POLICY_PROB);
    assert_int_equal(b.u.prob.k_goal, 777);
    blob[0] = 9;
    assert_int_equal(qnav_link_policy_from_blob(blob, 6, &b), QNAV_LINK_E_VALUE);
}

/* A 2-input network's blob may carry QNAV_SHAPES_BYTES of row shapes after its weights
 * (not looked at by the codec: init checks them); nothing else may. */
static void test_policy_blob_carries_row_shapes_after_a_two_input_network(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES], shapes[QNAV_SHAPES_BYTES], out[6];
    qnav_policy_t a, b, prob;
    uint16_t k, w = (uint16_t)(2u + 2u * QNAV_NET_WEIGHTS(QNAV_MAX_HIDDEN));
    int32_t n;
    (void)state;
    qnav_policy_net_zero(&a, QNAV_MAX_HIDDEN);
    for (k = 0; k < qnav_net_weight_count(&a.u.net); ++k) {
        *qnav_net_weight(&a.u.net, k) = (qnav_q8_8_t)(k * 311 - 7000);
    }
    for (k = 0; k < sizeof shapes; ++k) {
        shapes[k] = (uint8_t)(k * 7u + 1u);
    }
    n = qnav_link_policy_to_blob_carried(&a, shapes, blob, sizeof blob);
    assert_int_equal(n, QNAV_LINK_POLICY_MAX_BYTES);
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)n, &b), QNAV_LINK_OK);
    assert_memory_equal(b.u.net.w_out, a.u.net.w_out, sizeof a.u.net.w_out);
    assert_ptr_equal(qnav_link_blob_shapes(blob, (uint16_t)n), &blob[w]);
    assert_memory_equal(&blob[w], shapes, sizeof shapes);
    /* without them: the same policy, no shapes; any other length is refused */
    assert_int_equal(qnav_link_policy_from_blob(blob, w, &b), QNAV_LINK_OK);
    assert_null(qnav_link_blob_shapes(blob, w));
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)(n - 1), &b), QNAV_LINK_E_LENGTH);
    assert_null(qnav_link_blob_shapes(blob, (uint16_t)(n - 1)));
    assert_int_equal(qnav_link_policy_to_blob_carried(&a, shapes, blob, (uint16_t)(n - 1)),
                     QNAV_LINK_E_SPACE);
    /* only a 2-input network carries them */
    qnav_policy_prob_default(&prob);
    assert_int_equal(qnav_link_policy_to_blob_carried(&prob, shapes, blob, sizeof blob),
                     QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_policy_to_blob_carried(&prob, NULL, out, sizeof out), 6);
    qnav_policy_net_zero_inputs(&a, 3u, QNAV_NET_INPUTS_PREV);
    assert_int_equal(qnav_link_policy_to_blob_carried(&a, shapes, blob, sizeof blob),
                     QNAV_LINK_E_VALUE);
    n = qnav_link_policy_to_blob(&a, blob, sizeof blob);
    memcpy(&blob[n], shapes, sizeof shapes);
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)(n + (int32_t)sizeof shapes), &b),
                     QNAV_LINK_E_LENGTH);
    assert_null(qnav_link_blob_shapes(blob, (uint16_t)(n + (int32_t)sizeof shapes)));
}

static void test_policy_blob_round_trips_a_three_input_network(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    qnav_policy_t a, b;
    uint16_t k;
    int32_t n;
    (void)state;
    qnav_policy_net_zero_inputs(&a, QNAV_MAX_HIDDEN, QNAV_NET_INPUTS_PREV);
    for (k = 0; k < qnav_net_weight_count(&a.u.net); ++k) {
        *qnav_net_weight(&a.u.net, k) = (qnav_q8_8_t)(k * 173 - 5000);
    }
    n = qnav_link_policy_to_blob(&a, blob, sizeof blob);
    assert_int_equal(n, QNAV_LINK_POLICY_WEIGHTS_MAX_BYTES);
    assert_int_equal(blob[1], 0x80u | QNAV_MAX_HIDDEN);
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)n, &b), QNAV_LINK_OK);
    assert_int_equal(b.u.net.inputs, QNAV_NET_INPUTS_PREV);
    assert_memory_equal(b.u.net.w_prev, a.u.net.w_prev, sizeof a.u.net.w_prev);
    assert_memory_equal(b.u.net.w_out, a.u.net.w_out, sizeof a.u.net.w_out);
    /* the same bytes read as a 2-input blob have the wrong length */
    blob[1] = QNAV_MAX_HIDDEN;
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)n, &b), QNAV_LINK_E_LENGTH);
    blob[1] = 0x40u | QNAV_MAX_HIDDEN; /* an unused shape bit */
    assert_int_equal(qnav_link_policy_from_blob(blob, (uint16_t)n, &b), QNAV_LINK_E_VALUE);
}

static void test_policy_blob_refuses_a_policy_that_does_not_validate(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    qnav_policy_t a;
    (void)state;
    qnav_policy_net_zero(&a, 3);
    a.u.net.inputs = 4;
    assert_int_equal(qnav_link_policy_to_blob(&a, blob, sizeof blob), QNAV_LINK_E_VALUE);
    qnav_policy_prob_default(&a);
    a.u.prob.k_safe = 0;
    assert_int_equal(qnav_link_policy_to_blob(&a, blob, sizeof blob), QNAV_LINK_E_VALUE);
}

/* Issue 20: from_blob took what to_blob refuses (k_goal or k_safe outside (0, 64]). */
static void test_policy_blob_reader_refuses_what_the_writer_refuses(void **state)
{
    static const uint8_t fuzzed[6] = {0x01, 0x00, 0x00, 0x21, 0x1c, 0x93}; /* k_safe < 0 */
    static const uint8_t k_goal_zero[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0x04};
    static const uint8_t k_safe_above_64[6] = {0x01, 0x00, 0x00, 0x01, 0x01, 0x40};
    static const uint8_t both_64[6] = {0x01, 0x00, 0x00, 0x40, 0x00, 0x40};
    qnav_policy_t b;
    uint8_t out[8];
    (void)state;
    b.kind = 0xEEu;
    assert_int_equal(qnav_link_policy_from_blob(fuzzed, 6, &b), QNAV_LINK_E_VALUE);
    assert_int_equal(b.kind, 0xEEu); /* left untouched */
    assert_int_equal(qnav_link_policy_from_blob(k_goal_zero, 6, &b), QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_policy_from_blob(k_safe_above_64, 6, &b), QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_policy_from_blob(both_64, 6, &b), QNAV_LINK_OK);
    assert_int_equal(b.u.prob.k_goal, 64 * 256);
    /* whatever the reader accepts, the writer writes back byte for byte */
    assert_int_equal(qnav_link_policy_to_blob(&b, out, sizeof out), 6);
    assert_memory_equal(out, both_64, 6);
}

static void test_link_status_str_names_every_status(void **state)
{
    (void)state;
    assert_string_equal(qnav_link_status_str(QNAV_LINK_OK), "ok");
    assert_string_equal(qnav_link_status_str(QNAV_LINK_E_LENGTH),
                        "payload length wrong for the message");
    assert_string_equal(qnav_link_status_str(-99), "unknown link status");
}

/* Upload blob in chunks; return the commit's status. */
static int8_t upload(qnav_link_upload_t *up, const uint8_t *blob, uint16_t len, uint16_t crc,
                     qnav_policy_t *out)
{
    qnav_link_policy_chunk_t c;
    qnav_link_policy_commit_t cm;
    uint16_t off = 0;
    while (off < len) {
        uint16_t n = (uint16_t)(len - off);
        if (n > QNAV_LINK_CHUNK_BYTES) {
            n = QNAV_LINK_CHUNK_BYTES;
        }
        c.offset = off;
        c.total = len;
        c.len = (uint8_t)n;
        memcpy(c.data, &blob[off], n);
        assert_int_equal(qnav_link_upload_chunk(up, &c), QNAV_LINK_OK);
        off = (uint16_t)(off + n);
    }
    cm.total = len;
    cm.crc = crc;
    return qnav_link_upload_commit(up, &cm, out);
}

static void test_upload_in_chunks_delivers_the_policy(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    qnav_link_upload_t up;
    qnav_policy_t a, b;
    uint16_t n;
    (void)state;
    make_net(&a, 12);
    n = (uint16_t)qnav_link_policy_to_blob(&a, blob, sizeof blob);
    qnav_link_upload_init(&up);
    assert_int_equal(upload(&up, blob, n, qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, n), &b),
                     QNAV_LINK_ACK_OK);
    assert_int_equal(b.u.net.hidden, 12);
    assert_int_equal(b.u.net.w_theta[11], a.u.net.w_theta[11]);
}

static void test_upload_with_wrong_crc_is_refused(void **state)
{
    uint8_t blob[QNAV_LINK_POLICY_MAX_BYTES];
    qnav_link_upload_t up;
    qnav_policy_t a, b;
    uint16_t n;
    (void)state;
    make_net(&a, 12);
    n = (uint16_t)qnav_link_policy_to_blob(&a, blob, sizeof blob);
    qnav_link_upload_init(&up);
    memset(&b, 0, sizeof b);
    assert_int_equal(upload(&up, blob, n,
                            (uint16_t)(qnav_link_crc16(QNAV_LINK_CRC16_INIT, blob, n) ^ 1u),
                            &b),
                     QNAV_LINK_ACK_BAD_CRC);
    assert_int_equal(b.kind, 0);
}

static void test_upload_with_missing_chunk_is_refused(void **state)
{
    qnav_link_upload_t up;
    qnav_link_policy_chunk_t c;
    qnav_link_policy_commit_t cm = {100, 0};
    qnav_policy_t b;
    (void)state;
    qnav_link_upload_init(&up);
    memset(&c, 0, sizeof c);
    c.offset = 0;
    c.total = 100;
    c.len = QNAV_LINK_CHUNK_BYTES;
    assert_int_equal(qnav_link_upload_chunk(&up, &c), QNAV_LINK_OK);
    c.offset = 2 * QNAV_LINK_CHUNK_BYTES; /* skips one */
    c.len = 4;
    assert_int_equal(qnav_link_upload_chunk(&up, &c), QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_upload_commit(&up, &cm, &b), QNAV_LINK_ACK_BAD_LENGTH);
}

/* CONFIG: (key, value) pairs survive framing; a length that is not 1 + 5n is dropped by
 * the decoder. */
static void test_config_report_round_trips_and_bad_lengths_are_dropped(void **state)
{
    qnav_link_config_t m, got;
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    uint8_t p[QNAV_LINK_CONFIG_MAX_BYTES], wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t n, w, i;
    uint8_t got_frame = 0;
    (void)state;
    memset(&m, 0, sizeof m);
    m.n = 3;
    m.key[0] = 1;
    m.value[0] = 16;
    m.key[1] = 2;
    m.value[1] = 5000;
    m.key[2] = 3;
    m.value[2] = -29491;
    n = qnav_link_config_pack(&m, p, sizeof p);
    assert_int_equal(n, 16);
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    w = qnav_link_encode(&tx, QNAV_LINK_MSG_CONFIG, p, (uint16_t)n, wire, sizeof wire);
    assert_true(w > 0);
    for (i = 0; i < w; ++i) {
        got_frame |= qnav_link_rx_feed(&rx, wire[i], &f);
    }
    assert_int_equal(got_frame, 1);
    assert_int_equal(qnav_link_config_unpack(f.payload, f.len, &got), QNAV_LINK_OK);
    assert_int_equal(got.n, 3);
    assert_int_equal(got.value[1], 5000);
    assert_int_equal(got.value[2], -29491);
    /* one byte short: the count says 3 pairs */
    assert_int_equal(qnav_link_config_unpack(p, (uint16_t)(n - 1), &got), QNAV_LINK_E_LENGTH);
    w = qnav_link_encode(&tx, QNAV_LINK_MSG_CONFIG, p, (uint16_t)(n - 1), wire, sizeof wire);
    got_frame = 0;
    for (i = 0; i < w; ++i) {
        got_frame |= qnav_link_rx_feed(&rx, wire[i], &f);
    }
    assert_int_equal(got_frame, 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_LENGTH], 1);
    m.n = QNAV_LINK_CONFIG_MAX_FIELDS + 1u;
    assert_int_equal(qnav_link_config_pack(&m, p, sizeof p), QNAV_LINK_E_VALUE);
    /* pairs appended one at a time pack as the struct does, up to the maximum and the room */
    {
        uint8_t q[QNAV_LINK_CONFIG_MAX_BYTES];
        m.n = QNAV_LINK_CONFIG_MAX_FIELDS;
        q[0] = 0;
        for (i = 0; i < (int32_t)QNAV_LINK_CONFIG_MAX_FIELDS; ++i) {
            m.key[i] = (uint8_t)(i + 1);
            m.value[i] = -1000 * i;
            assert_int_equal(qnav_link_config_append(q, sizeof q, m.key[i], m.value[i]), 6 + 5 * i);
        }
        assert_int_equal(qnav_link_config_pack(&m, p, sizeof p), (int32_t)sizeof q);
        assert_memory_equal(p, q, sizeof q);
        assert_int_equal(qnav_link_config_append(q, sizeof q, 99, 1), QNAV_LINK_E_VALUE);
        q[0] = 0;
        assert_int_equal(qnav_link_config_append(q, 5, 1, 1), QNAV_LINK_E_SPACE);
        assert_int_equal(q[0], 0);
    }
}

static void test_heartbeat_carries_the_protocol_version_and_reads_version_1(void **state)
{
    qnav_link_heartbeat_t hb = {1234, QNAV_LINK_MODE_ONBOARD, 0x15, 7, 1, 0xBEEF, 0}, got;
    uint8_t p[QNAV_LINK_HEARTBEAT_MAX_BYTES];
    (void)state;
    assert_int_equal(qnav_link_heartbeat_pack(&hb, p, sizeof p), QNAV_LINK_HEARTBEAT_BYTES);
    assert_int_equal(p[12], QNAV_LINK_PROTOCOL_VERSION);
    assert_int_equal(qnav_link_heartbeat_unpack(p, QNAV_LINK_HEARTBEAT_BYTES, &got), 0);
    assert_int_equal(got.protocol, QNAV_LINK_PROTOCOL_VERSION);
    assert_int_equal(got.policy_crc, 0xBEEF);
    /* a version-1 board: 12 bytes, no version byte */
    assert_int_equal(qnav_link_heartbeat_unpack(p, QNAV_LINK_HEARTBEAT_V1_BYTES, &got), 0);
    assert_int_equal(got.protocol, 1);
    assert_int_equal(got.state, 0x15);
    /* a later version with more fields: its version read, the rest ignored */
    p[12] = 9;
    assert_int_equal(qnav_link_heartbeat_unpack(p, 20, &got), 0);
    assert_int_equal(got.protocol, 9);
    assert_int_equal(qnav_link_heartbeat_unpack(p, 11, &got), QNAV_LINK_E_LENGTH);
}

static void test_decoder_accepts_heartbeats_of_every_version_length(void **state)
{
    qnav_link_tx_t tx;
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    uint8_t p[40] = {0};
    wire_t w;
    (void)state;
    qnav_link_tx_init(&tx);
    qnav_link_rx_init(&rx);
    w = encode(&tx, QNAV_LINK_MSG_HEARTBEAT, p, QNAV_LINK_HEARTBEAT_V1_BYTES);
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    w = encode(&tx, QNAV_LINK_MSG_HEARTBEAT, p, QNAV_LINK_HEARTBEAT_MAX_BYTES);
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 1);
    w = encode(&tx, QNAV_LINK_MSG_HEARTBEAT, p, QNAV_LINK_HEARTBEAT_MAX_BYTES + 1u);
    assert_int_equal(feed(&rx, w.wire, w.len, &f), 0);
    assert_int_equal(rx.stats.dropped[QNAV_LINK_DROP_LENGTH], 1);
}

static void test_position_goal_and_pose_round_trip_with_negative_coordinates(void **state)
{
    qnav_link_goal_t g = {3, -4500, 0, QNAV_LINK_GOAL_POSITION, -1234567, 7654321}, g2;
    qnav_link_pose_t ps = {0xFFFFFFFEu, -2000000, 1999999, -17999, 3, 4000000u, 1u, 65535u}, ps2;
    uint8_t p[QNAV_LINK_POSE_BYTES];
    (void)state;
    assert_int_equal(qnav_link_goal_pack(&g, p, sizeof p), QNAV_LINK_GOAL_BYTES);
    assert_int_equal(qnav_link_goal_unpack(p, QNAV_LINK_GOAL_BYTES, &g2), 0);
    assert_int_equal(g2.kind, QNAV_LINK_GOAL_POSITION);
    assert_int_equal(g2.x_mm, -1234567);
    assert_int_equal(g2.y_mm, 7654321);
    p[8] = 2; /* no such goal kind */
    assert_int_equal(qnav_link_goal_unpack(p, QNAV_LINK_GOAL_BYTES, &g2), QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_pose_pack(&ps, p, sizeof p), QNAV_LINK_POSE_BYTES);
    assert_int_equal(qnav_link_pose_unpack(p, QNAV_LINK_POSE_BYTES, &ps2), 0);
    assert_int_equal(ps2.board_ms, 0xFFFFFFFEu);
    assert_int_equal(ps2.x_mm, -2000000);
    assert_int_equal(ps2.y_mm, 1999999);
    assert_int_equal(ps2.heading_cdeg, -17999);
    assert_int_equal(ps2.goal_distance_mm, 4000000u);
    assert_int_equal(ps2.escape_clear, 1u);
    assert_int_equal(ps2.escape_grow_mm, 65535u);
    assert_int_equal(qnav_link_pose_pack(&ps, p, QNAV_LINK_POSE_BYTES - 1u), QNAV_LINK_E_SPACE);
    /* the map's clear is 0 or 1: anything else is refused both ways */
    p[20] = 2u;
    assert_int_equal(qnav_link_pose_unpack(p, QNAV_LINK_POSE_BYTES, &ps2), QNAV_LINK_E_VALUE);
    ps.escape_clear = 2u;
    assert_int_equal(qnav_link_pose_pack(&ps, p, sizeof p), QNAV_LINK_E_VALUE);
    assert_int_equal(qnav_link_pose_unpack(p, QNAV_LINK_POSE_BYTES - 3u, &ps2), QNAV_LINK_E_LENGTH);
}

static uint32_t g_sent;

static void count_bytes(void *user, const uint8_t *bytes, uint16_t n)
{
    (void)user;
    (void)bytes;
    g_sent += n;
}

static void test_send_frames_once_and_sends_nothing_for_a_failed_pack(void **state)
{
    qnav_link_tx_t tx;
    uint8_t wire[64], p[4] = {1, 2, 3, 4};
    (void)state;
    qnav_link_tx_init(&tx);
    g_sent = 0;
    assert_true(qnav_link_send(&tx, QNAV_LINK_MSG_POLICY_COMMIT, p, 4, wire, sizeof wire,
                               count_bytes, NULL) > 0);
    assert_true(g_sent > 4u);
    assert_int_equal(tx.next_seq, 1);
    g_sent = 0;
    assert_int_equal(qnav_link_send(&tx, QNAV_LINK_MSG_POLICY_COMMIT, p, QNAV_LINK_E_SPACE,
                                    wire, sizeof wire, count_bytes, NULL), QNAV_LINK_E_SPACE);
    assert_int_equal(g_sent, 0);
    assert_int_equal(tx.next_seq, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_heartbeat_carries_the_protocol_version_and_reads_version_1),
        cmocka_unit_test(test_config_report_round_trips_and_bad_lengths_are_dropped),
        cmocka_unit_test(test_decoder_accepts_heartbeats_of_every_version_length),
        cmocka_unit_test(test_position_goal_and_pose_round_trip_with_negative_coordinates),
        cmocka_unit_test(test_send_frames_once_and_sends_nothing_for_a_failed_pack),
        cmocka_unit_test(test_crc16_matches_ccitt_false_check_value),
        cmocka_unit_test(test_codec_round_trips_scan_of_360_sectors),
        cmocka_unit_test(test_codec_round_trips_every_small_message),
        cmocka_unit_test(test_codec_drops_frame_with_bad_crc),
        cmocka_unit_test(test_codec_drops_truncated_frame_and_takes_the_next),
        cmocka_unit_test(test_codec_drops_replayed_frame),
        cmocka_unit_test(test_codec_accepts_sequence_wrap_and_counts_gaps),
        cmocka_unit_test(test_codec_accepts_any_sequence_after_reset),
        cmocka_unit_test(test_codec_drops_unknown_id_and_wrong_length),
        cmocka_unit_test(test_codec_drops_overlong_frame_and_recovers),
        cmocka_unit_test(test_codec_drops_frame_shorter_than_header),
        cmocka_unit_test(test_codec_drops_cobs_block_running_past_delimiter),
        cmocka_unit_test(test_encode_refuses_small_buffer_and_keeps_sequence),
        cmocka_unit_test(test_fuzz_random_bytes_never_accept_a_frame),
        cmocka_unit_test(test_fuzz_every_bit_flip_is_dropped),
        cmocka_unit_test(test_fuzz_every_truncation_is_dropped),
        cmocka_unit_test(test_fuzz_random_damage_never_yields_a_frame_that_was_not_sent),
        cmocka_unit_test(test_policy_blob_round_trips_network_and_probabilistic),
        cmocka_unit_test(test_policy_blob_round_trips_a_three_input_network),
        cmocka_unit_test(test_policy_blob_carries_row_shapes_after_a_two_input_network),
        cmocka_unit_test(test_policy_blob_refuses_a_policy_that_does_not_validate),
        cmocka_unit_test(test_policy_blob_reader_refuses_what_the_writer_refuses),
        cmocka_unit_test(test_link_status_str_names_every_status),
        cmocka_unit_test(test_upload_in_chunks_delivers_the_policy),
        cmocka_unit_test(test_upload_with_wrong_crc_is_refused),
        cmocka_unit_test(test_upload_with_missing_chunk_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
