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

/* One replay: the controller, the scans waiting for their command, and what was found. */
typedef struct {
    pending_t pend[PENDING];
    unsigned next;
    int crc_noted;
    qnav_bridge_ctrl_t bc;
    qnav_nav_input_t rec;    /* the last logged QNAV_NAV_INPUT */
    int have_rec;
    qnav_replay_result_t *res;
    FILE *out;
} replay_t;

/* A logged controller input: kept for the scan that follows it. */
static void on_input(replay_t *r, const lcm_eventlog_event_t *ev)
{
    if (qnav_nav_input_t_decode(ev->data, 0, ev->datalen, &r->rec) < 0) {
        r->res->bad_events++;
        r->have_rec = 0;
        return;
    }
    r->have_rec = 1;
}

/* A logged scan: run the controller on it, with its logged input (goal distance, previous
 * heading) when the log has one, and keep the command until the log's own. */
static void on_scan(replay_t *r, const lcm_eventlog_event_t *ev)
{
    qnav_scan_t scan;
    qnav_nav_input_t rec;
    pending_t *p = &r->pend[r->next];
    if (qnav_scan_t_decode(ev->data, 0, ev->datalen, &scan) < 0) {
        r->res->bad_events++;
        return;
    }
    r->res->scans++;
    if (r->have_rec && r->rec.scan_seq == scan.seq) {
        rec = r->rec;
        r->res->with_input++;
    } else {
        /* a log from before QNAV_NAV_INPUT: no goal distance (no escape), the previous
         * heading the replay's own last decision (no heading known: not turned) */
        qnav_bridge_ctrl_input(&r->bc, &scan, 0u, 0, &rec);
    }
    r->have_rec = 0;
    p->used = 1;
    p->seq = scan.seq;
    qnav_bridge_ctrl_step(&r->bc, &scan, &rec, &p->cmd, NULL);
    r->next = (r->next + 1u) % PENDING;
}

/* The logged command c against the replayed one of its scan p (first 10 differences
 * printed). */
static void compare(replay_t *r, const qnav_command_t *c, const pending_t *p)
{
    r->res->compared++;
    if (p->cmd.heading_deg == c->heading_deg && p->cmd.speed_q15 == c->speed_q15 &&
        p->cmd.quality_q15 == c->quality_q15 && p->cmd.flags == c->flags) {
        r->res->identical++;
        return;
    }
    r->res->differ++;
    if (r->out != NULL && r->res->differ <= 10u) {
        fprintf(r->out,
                "scan %d: logged heading %d speed %d quality %d flags %d,"
                " replayed heading %d speed %d quality %d flags %d\n",
                c->scan_seq, c->heading_deg, c->speed_q15, c->quality_q15, c->flags,
                p->cmd.heading_deg, p->cmd.speed_q15, p->cmd.quality_q15, p->cmd.flags);
    }
}

/* A logged command: compared with the newest pending scan of its sequence number, unless
 * it is a stop or came from another policy. */
static void on_command(replay_t *r, const lcm_eventlog_event_t *ev)
{
    qnav_command_t c;
    unsigned k;
    if (qnav_command_t_decode(ev->data, 0, ev->datalen, &c) < 0) {
        r->res->bad_events++;
    } else if (c.stop_reason != QNAV_STOP_NONE || c.scan_seq < 0) {
        r->res->stops++;
    } else if (c.policy_crc != 0 && (uint16_t)c.policy_crc != r->bc.policy_crc) {
        r->res->other_policy++;
        if (!r->crc_noted && r->out != NULL) {
            fprintf(r->out, "note: some logged commands came from policy crc 0x%04x, "
                            "replaying with 0x%04x: those are not compared\n",
                    (unsigned)(uint16_t)c.policy_crc, (unsigned)r->bc.policy_crc);
            r->crc_noted = 1;
        }
    } else {
        for (k = 1; k <= PENDING; ++k) {
            pending_t *p = &r->pend[(r->next + PENDING - k) % PENDING];
            if (p->used && p->seq == c.scan_seq) {
                compare(r, &c, p);
                p->used = 0;
                break;
            }
        }
    }
}

int qnav_replay_log(const char *path, const qnav_ctrl_config_t *cfg, const char *controller,
                    const qnav_policy_t *policy, qnav_replay_result_t *res, FILE *out,
                    char *err, size_t errlen)
{
    replay_t r;
    lcm_eventlog_t *log;
    lcm_eventlog_event_t *ev;
    unsigned events = 0;

    memset(res, 0, sizeof *res);
    memset(&r, 0, sizeof r);
    r.res = res;
    r.out = out;
    log = lcm_eventlog_create(path, "r");
    if (log == NULL) {
        snprintf(err, errlen, "%s: cannot open LCM log (%s)", path, strerror(errno));
        return -1;
    }
    qnav_bridge_ctrl_init(&r.bc, cfg, controller, policy);
    while ((ev = lcm_eventlog_read_next_event(log)) != NULL) {
        events++;
        if (strcmp(ev->channel, QNAV_CH_NAV_INPUT) == 0) {
            on_input(&r, ev);
        } else if (strcmp(ev->channel, QNAV_CH_SCAN) == 0) {
            on_scan(&r, ev);
        } else if (strcmp(ev->channel, QNAV_CH_COMMAND) == 0) {
            on_command(&r, ev);
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

int qnav_replay_log_config(const char *path, uint16_t *crc)
{
    lcm_eventlog_t *log = lcm_eventlog_create(path, "r");
    lcm_eventlog_event_t *ev;
    qnav_nav_input_t rec;
    int found = 0;
    int seen = 0;
    unsigned events = 0;
    if (log == NULL) {
        return -1;
    }
    while (!seen && (ev = lcm_eventlog_read_next_event(log)) != NULL) {
        events++;
        if (strcmp(ev->channel, QNAV_CH_NAV_INPUT) == 0 &&
            qnav_nav_input_t_decode(ev->data, 0, ev->datalen, &rec) >= 0) {
            seen = 1;
            *crc = (uint16_t)rec.config_crc;
            found = rec.config_crc >= 0; /* -1: not known to the bridge (onboard) */
        }
        lcm_eventlog_free_event(ev);
    }
    lcm_eventlog_destroy(log);
    return events == 0 ? -1 : found; /* no events: not a log (qnav_replay_log says so) */
}
