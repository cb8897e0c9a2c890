/*
 * Log replay (replay.h): reads an LCM event log with lcm_eventlog, re-runs the controller
 * on each scan and compares with the commands the log holds.
 */
#define _POSIX_C_SOURCE 200809L
#include "replay.h"

#include <errno.h>
#include <string.h>

#include <lcm/eventlog.h>

#include "bridge.h"

/* Scans waiting for their logged command, by link sequence number (ring). */
#define PENDING 64

typedef struct {
    int used;
    int32_t seq;
    qnav_command_t cmd;
} pending_t;

int qnav_replay_log(const char *path, const qnav_ctrl_config_t *cfg, const char *controller,
                    const qnav_policy_t *policy, qnav_replay_result_t *res, FILE *out,
                    char *err, size_t errlen)
{
    pending_t pend[PENDING];
    qnav_scan_t scan;
    qnav_bridge_ctrl_t bc;
    lcm_eventlog_t *log;
    lcm_eventlog_event_t *ev;
    unsigned next = 0, events = 0;
    int crc_noted = 0;

    memset(res, 0, sizeof *res);
    memset(pend, 0, sizeof pend);
    log = lcm_eventlog_create(path, "r");
    if (log == NULL) {
        snprintf(err, errlen, "%s: cannot open LCM log (%s)", path, strerror(errno));
        return -1;
    }
    qnav_bridge_ctrl_init(&bc, cfg, controller, policy);
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        events++;
        if (strcmp(ev->channel, QNAV_CH_SCAN) == 0) {
            if (qnav_scan_t_decode(ev->data, 0, ev->datalen, &scan) < 0) {
                res->bad_events++;
            } else {
                res->scans++;
                pend[next].used = 1;
                pend[next].seq = scan.seq;
                qnav_bridge_ctrl_step(&bc, &scan, &pend[next].cmd, NULL);
                next = (next + 1u) % PENDING;
            }
        } else if (strcmp(ev->channel, QNAV_CH_COMMAND) == 0) {
            qnav_command_t c;
            if (qnav_command_t_decode(ev->data, 0, ev->datalen, &c) < 0) {
                res->bad_events++;
            } else if (c.stop_reason != QNAV_STOP_NONE || c.scan_seq < 0) {
                res->stops++;
            } else if (c.policy_crc != 0 && (uint16_t)c.policy_crc != bc.policy_crc) {
                res->other_policy++;
                if (!crc_noted && out != NULL) {
                    fprintf(out, "note: some logged commands came from policy crc 0x%04x, "
                                 "replaying with 0x%04x: those are not compared\n",
                            (unsigned)(uint16_t)c.policy_crc, (unsigned)bc.policy_crc);
                    crc_noted = 1;
                }
            } else {
                /* newest pending scan with that sequence number */
                unsigned k;
                for (k = 1; k <= PENDING; ++k) {
                    pending_t *p = &pend[(next + PENDING - k) % PENDING];
                    if (!p->used || p->seq != c.scan_seq) {
                        continue;
                    }
                    res->compared++;
                    if (p->cmd.heading_deg == c.heading_deg &&
                        p->cmd.speed_q15 == c.speed_q15 &&
                        p->cmd.quality_q15 == c.quality_q15 && p->cmd.flags == c.flags) {
                        res->identical++;
                    } else {
                        res->differ++;
                        if (out != NULL && res->differ <= 10u) {
                            fprintf(out,
                                    "scan %d: logged heading %d speed %d quality %d flags %d,"
                                    " replayed heading %d speed %d quality %d flags %d\n",
                                    c.scan_seq, c.heading_deg, c.speed_q15, c.quality_q15,
                                    c.flags, p->cmd.heading_deg, p->cmd.speed_q15,
                                    p->cmd.quality_q15, p->cmd.flags);
                        }
                    }
                    p->used = 0;
                    break;
                }
            }
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    if (events == 0) {
        /* lcm_eventlog stops at the first bad sync word: a text file, a truncated header
         * or an empty file all read as "no events", and are not logs to replay */
        snprintf(err, errlen, "%s: not an LCM log (no events could be read)", path);
        return -1;
    }
    return 0;
}
