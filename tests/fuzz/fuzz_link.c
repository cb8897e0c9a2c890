/*
 * libFuzzer target: the serial link codec (firmware/link) as a receiver meets it. The
 * input is a byte stream fed to qnav_link_rx_feed one byte at a time; every accepted frame
 * is unpacked by its message id's unpacker, and its payload is also tried as a policy blob.
 * Properties beyond "no crash, no sanitizer report": an accepted frame's payload length is
 * within QNAV_LINK_MAX_PAYLOAD; frames taken plus frames dropped never exceed the frames
 * (delimiters + 1) seen; a blob qnav_link_policy_from_blob accepts serialises again with
 * qnav_link_policy_to_blob_carried (and the carried row shapes qnav_link_blob_shapes finds
 * in it, if any) to the same bytes (the codec reads only what it writes).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "qnav/link.h"

static void check_blob(const uint8_t *p, uint16_t len)
{
    qnav_policy_t pol;
    uint8_t again[QNAV_LINK_POLICY_MAX_BYTES];
    int32_t n;
    if (qnav_link_policy_from_blob(p, len, &pol) != QNAV_LINK_OK) {
        return;
    }
    n = qnav_link_policy_to_blob_carried(&pol, qnav_link_blob_shapes(p, len), again,
                                         sizeof again);
    if (n != (int32_t)len || memcmp(again, p, len) != 0) {
        abort(); /* accepted a blob the codec itself would not write */
    }
}

static void unpack(const qnav_link_frame_t *f)
{
    union {
        qnav_link_scan_t scan;
        qnav_link_goal_t goal;
        qnav_link_command_t command;
        qnav_link_policy_chunk_t chunk;
        qnav_link_policy_commit_t commit;
        qnav_link_policy_ack_t ack;
        qnav_link_heartbeat_t heartbeat;
        qnav_link_pose_t pose;
    } m;
    switch (f->msg_id) {
    case QNAV_LINK_MSG_SCAN: (void)qnav_link_scan_unpack(f->payload, f->len, &m.scan); break;
    case QNAV_LINK_MSG_GOAL: (void)qnav_link_goal_unpack(f->payload, f->len, &m.goal); break;
    case QNAV_LINK_MSG_COMMAND:
        (void)qnav_link_command_unpack(f->payload, f->len, &m.command);
        break;
    case QNAV_LINK_MSG_POLICY_CHUNK:
        (void)qnav_link_policy_chunk_unpack(f->payload, f->len, &m.chunk);
        break;
    case QNAV_LINK_MSG_POLICY_COMMIT:
        (void)qnav_link_policy_commit_unpack(f->payload, f->len, &m.commit);
        break;
    case QNAV_LINK_MSG_POLICY_ACK:
        (void)qnav_link_policy_ack_unpack(f->payload, f->len, &m.ack);
        break;
    case QNAV_LINK_MSG_HEARTBEAT:
        (void)qnav_link_heartbeat_unpack(f->payload, f->len, &m.heartbeat);
        break;
    case QNAV_LINK_MSG_POSE: (void)qnav_link_pose_unpack(f->payload, f->len, &m.pose); break;
    default: abort(); /* the decoder accepted an id it does not know */
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    qnav_link_rx_t rx;
    qnav_link_frame_t f;
    uint32_t delimiters = 0, accepted = 0;
    size_t i;
    qnav_link_rx_init(&rx);
    for (i = 0; i < size; ++i) {
        delimiters += data[i] == 0u;
        if (qnav_link_rx_feed(&rx, data[i], &f)) {
            accepted++;
            if (f.len > QNAV_LINK_MAX_PAYLOAD) {
                abort();
            }
            unpack(&f);
            check_blob(f.payload, f.len);
        }
    }
    /* each frame (bytes up to a delimiter, and a last one without) is taken or dropped
     * once */
    if (accepted != rx.stats.frames_ok ||
        accepted + qnav_link_rx_dropped_total(&rx) > delimiters + 1u) {
        abort();
    }
    /* the raw input as a blob too (uploads are reassembled from chunks) */
    if (size <= 0xFFFFu) {
        check_blob(data, (uint16_t)size);
    }
    return 0;
}
