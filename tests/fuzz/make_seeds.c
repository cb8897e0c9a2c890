/*
 * Writes the seed corpora and regression inputs of the fuzz targets (tests/fuzz/corpus,
 * tests/fuzz/regress) with the link codec's own encoder, so they are real frames of this
 * protocol version. Regenerate after a change of the wire format:
 *   sh tests/fuzz/make_seeds.sh      (compiles this file with cc, runs it on tests/fuzz)
 * The regression inputs are named after the historical bug shapes of MAVLink's parsers:
 * resynchronising after a bad CRC, a message id the receiver does not know, a frame cut
 * short, a payload longer than a buffer shrunk by a compile-time knob (the AVR build's
 * 32-sector scan), a length that does not match the id, a replayed sequence number.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/board.h"
#include "qnav/link.h"
#include "qnav/tekbot.h"
#include "sim_hal.h"

static const char *g_root;
static uint8_t g_buf[65536];
static size_t g_n;
static qnav_link_tx_t g_tx;

static void put(const void *p, size_t n)
{
    if (g_n + n > sizeof g_buf) {
        fprintf(stderr, "make_seeds: buffer full (%zu + %zu)\n", g_n, n);
        exit(1);
    }
    memcpy(g_buf + g_n, p, n);
    g_n += n;
}

static void frame(uint8_t id, const uint8_t *payload, int32_t len)
{
    uint8_t wire[QNAV_LINK_MAX_WIRE(QNAV_LINK_MAX_PAYLOAD)];
    int32_t w = qnav_link_encode(&g_tx, id, payload, (uint16_t)len, wire, sizeof wire);
    if (len < 0 || w <= 0) {
        fprintf(stderr, "make_seeds: cannot encode message 0x%02x\n", id);
        exit(1);
    }
    put(wire, (size_t)w);
}

static void save(const char *dir, const char *name)
{
    char path[512];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s/%s", g_root, dir, name);
    f = fopen(path, "wb");
    if (f == NULL || fwrite(g_buf, 1, g_n, f) != g_n || fclose(f) != 0) {
        fprintf(stderr, "make_seeds: %s: cannot write\n", path);
        exit(1);
    }
    g_n = 0;
    qnav_link_tx_init(&g_tx);
}

static void heartbeat(uint8_t mode)
{
    qnav_link_heartbeat_t hb;
    uint8_t p[QNAV_LINK_HEARTBEAT_BYTES];
    memset(&hb, 0, sizeof hb);
    hb.uptime_ms = 1000;
    hb.mode = mode;
    hb.state = QNAV_LINK_STATE_LINK_OK;
    frame(QNAV_LINK_MSG_HEARTBEAT, p, qnav_link_heartbeat_pack(&hb, p, sizeof p));
}

static void scan(uint16_t sectors)
{
    qnav_link_scan_t s;
    uint8_t p[QNAV_LINK_SCAN_MAX_BYTES];
    uint16_t k;
    memset(&s, 0, sizeof s);
    s.board_ms = 500;
    s.n_sectors = sectors;
    s.max_range_mm = 3000;
    s.goal_bearing_cdeg = 3000;
    s.goal_id = 1;
    for (k = 0; k < sectors; ++k) {
        s.ranges_mm[k] = (qnav_mm_t)(400 + 100 * k);
    }
    frame(QNAV_LINK_MSG_SCAN, p, qnav_link_scan_pack(&s, p, sizeof p));
}

static void goal(void)
{
    qnav_link_goal_t g;
    uint8_t p[QNAV_LINK_GOAL_BYTES];
    memset(&g, 0, sizeof g);
    g.goal_id = 2;
    g.kind = QNAV_LINK_GOAL_POSITION;
    g.x_mm = 2000;
    g.y_mm = -500;
    frame(QNAV_LINK_MSG_GOAL, p, qnav_link_goal_pack(&g, p, sizeof p));
}

static void command(uint16_t seq)
{
    qnav_link_command_t c;
    uint8_t p[QNAV_LINK_COMMAND_BYTES];
    memset(&c, 0, sizeof c);
    c.scan_seq = seq;
    c.heading_deg = 20;
    c.speed = 16000;
    c.quality = 30000;
    frame(QNAV_LINK_MSG_COMMAND, p, qnav_link_command_pack(&c, p, sizeof p));
}

static void upload(const qnav_policy_t *pol, uint16_t crc_xor)
{
    sim_hal_t *sim = calloc(1, sizeof *sim);
    qnav_board_hal_t hal;
    sim_hal_init(sim, &hal);
    if (sim == NULL || sim_hal_upload(sim, &g_tx, pol, crc_xor) != 0) {
        fprintf(stderr, "make_seeds: upload\n");
        exit(1);
    }
    put(sim->to_board + sim->to_board_tail, sim->to_board_head - sim->to_board_tail); /* written at head */
    free(sim);
}

static void blob(const qnav_policy_t *pol)
{
    uint8_t b[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n = qnav_link_policy_to_blob(pol, b, sizeof b);
    if (n <= 0) {
        exit(1);
    }
    put(b, (size_t)n);
}

/* The blob navbridge uploads: with a 2-input network's carried row shapes. */
static void carried_blob(const qnav_policy_t *pol)
{
    uint8_t b[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n = sim_hal_blob(pol, b, (uint16_t)sizeof b);
    if (n <= 0) {
        exit(1);
    }
    put(b, (size_t)n);
}

/* An EEPROM after a committed upload of pol (the board core's own store). */
static void eeprom_with(const qnav_policy_t *pol)
{
    static sim_hal_t sim;
    static qnav_board_t bot;
    qnav_board_hal_t hal;
    qnav_board_config_t cfg;
    int k;
    sim_hal_init(&sim, &hal);
    sim.n_ranges = 8;
    qnav_tekbot_config_default(&cfg);
    cfg.ctrl.n_sectors = 8;
    if (qnav_board_init(&bot, &cfg, &hal) != QNAV_BOARD_OK) {
        exit(1);
    }
    qnav_link_tx_init(&g_tx);
    g_n = 0;
    heartbeat(QNAV_LINK_MODE_ONBOARD);
    sim_hal_to_board(&sim, g_buf, (uint32_t)g_n);
    g_n = 0;
    if (sim_hal_upload(&sim, &g_tx, pol, 0) != 0) {
        exit(1);
    }
    for (k = 0; k < 50; ++k) {
        sim.now_ms += 20;
        qnav_board_poll(&bot);
    }
    put(sim.nvm, 320); /* both slots */
}

int main(int argc, char **argv)
{
    qnav_policy_t prob, net;
    uint8_t raw[64];
    size_t cut;
    int k;
    if (argc != 2) {
        fprintf(stderr, "usage: make_seeds TESTS_FUZZ_DIR\n");
        return 2;
    }
    g_root = argv[1];
    qnav_link_tx_init(&g_tx);
    qnav_policy_prob_default(&prob);
    qnav_policy_net_zero(&net, 4);
    for (k = 0; k < QNAV_NET_WEIGHTS_IN(4, 2); ++k) {
        *qnav_net_weight(&net.u.net, (uint16_t)k) = (qnav_q8_8_t)((k * 977) % 2048 - 1024);
    }

    /* link: what each end sends */
    heartbeat(QNAV_LINK_MODE_OFFBOARD); save("corpus/link", "heartbeat");
    scan(8); scan(8); save("corpus/link", "two_scans_8_sectors");
    goal(); command(1); save("corpus/link", "goal_and_command");
    upload(&prob, 0); save("corpus/link", "upload_probabilistic");
    blob(&prob); save("corpus/link", "blob_probabilistic");
    blob(&net); save("corpus/link", "blob_network_4_hidden");
    carried_blob(&net); save("corpus/link", "blob_network_4_hidden_with_shapes");

    /* link regressions */
    heartbeat(QNAV_LINK_MODE_OFFBOARD);
    g_buf[g_n - 3] ^= 0x40u; /* a CRC byte of the first frame */
    heartbeat(QNAV_LINK_MODE_OFFBOARD); save("regress/link", "resync_after_bad_crc");
    raw[0] = 0;
    frame(0x7Fu, raw, 1); heartbeat(QNAV_LINK_MODE_OFFBOARD); save("regress/link", "unknown_msg_id");
    scan(8); cut = g_n / 2; g_n = cut; raw[0] = 0; put(raw, 1);
    heartbeat(QNAV_LINK_MODE_OFFBOARD); save("regress/link", "truncated_frame");
    scan(QNAV_LINK_MAX_SECTORS > 180 ? 180 : QNAV_LINK_MAX_SECTORS);
    heartbeat(QNAV_LINK_MODE_OFFBOARD); save("regress/link", "payload_beyond_avr_32_sector_buffer");
    memset(raw, 0x11, sizeof raw);
    frame(QNAV_LINK_MSG_GOAL, raw, 5); save("regress/link", "length_wrong_for_id");
    heartbeat(QNAV_LINK_MODE_OFFBOARD);
    memcpy(raw, g_buf, g_n); cut = g_n; put(raw, cut); save("regress/link", "replayed_sequence_number");

    /* board: what navbridge sends it */
    heartbeat(QNAV_LINK_MODE_OFFBOARD); goal(); command(0); command(1);
    save("corpus/board", "offboard_goal_and_commands");
    heartbeat(QNAV_LINK_MODE_ONBOARD); upload(&net, 0); goal();
    save("corpus/board", "onboard_upload_network");
    heartbeat(QNAV_LINK_MODE_ONBOARD); upload(&prob, 0x0101u);
    save("regress/board", "upload_commit_with_bad_crc");
    heartbeat(QNAV_LINK_MODE_ONBOARD); upload(&net, 0); g_buf[g_n / 2] ^= 0x08u;
    save("regress/board", "upload_with_damaged_chunk");

    /* board_store: EEPROM images */
    eeprom_with(&net); save("corpus/board_store", "one_slot_network");
    eeprom_with(&prob); g_buf[20] ^= 0x01u; save("regress/board_store", "slot_with_flipped_blob_byte");
    eeprom_with(&net); g_buf[4] = 0xFFu; g_buf[5] = 0x7Fu; save("regress/board_store", "slot_length_beyond_store");
    return 0;
}
