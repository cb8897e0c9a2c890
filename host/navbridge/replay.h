/*
 * Replay of a recorded trial through the bridge's controller: every QNAV_SCAN event of an
 * LCM log (lcm-logger's or navbridge --log's) runs through libqnav again with the given
 * policy, fed the goal distance and previous heading that the QNAV_NAV_INPUT before it
 * records and carrying the escape memory from scan to scan as the bridge did, and each
 * logged QNAV_COMMAND that answered a scan is compared field by field with the fresh
 * result. Same library, same integers: a clean trial replays identically.
 */
#ifndef QNAV_NAVBRIDGE_REPLAY_H
#define QNAV_NAVBRIDGE_REPLAY_H

#include <stdint.h>
#include <stdio.h>

#include "qnav/ctrl.h"

typedef struct {
    uint64_t scans;       /* QNAV_SCAN events read */
    uint64_t with_input;  /* of those, replayed with their logged QNAV_NAV_INPUT (goal
                             distance and previous heading); the others (logs from before
                             it) without a goal distance, i.e. without the escape */
    uint64_t compared;    /* logged commands matched to a scan and compared */
    uint64_t identical;   /* of those, equal in heading, speed, quality and flags */
    uint64_t differ;      /* of those, different */
    uint64_t stops;       /* logged stop commands (not compared) */
    uint64_t other_policy; /* logged commands of another policy (CRC differs) */
    uint64_t bad_events;  /* events on qnav channels that did not decode */
} qnav_replay_result_t;

/*
 * Replay the log at path with the controller of that name (qnav/nav.h; null: "body"),
 * policy and ctrl config cfg (n_sectors and max range are
 * taken from each scan). Commands whose policy CRC is set and differs from policy's (a
 * trial with an upload part-way) are counted in other_policy, not compared. Differences
 * are listed on out (may be NULL), at most 10.
 * Returns 0, or -1 with "PATH: problem" in err when the log cannot be read or holds no
 * events (not an LCM log).
 */
int qnav_replay_log(const char *path, const qnav_ctrl_config_t *cfg, const char *controller,
                    const qnav_policy_t *policy, qnav_replay_result_t *res, FILE *out,
                    char *err, size_t errlen);

/*
 * The controller configuration the log's decisions were made with: the config_crc of its
 * first QNAV_NAV_INPUT (qnav_bridge_config_crc) into crc. 1 found, 0 the log records none
 * (recorded before QNAV_NAV_INPUT existed, or onboard without --robot), -1 the log cannot
 * be opened or holds no events.
 */
int qnav_replay_log_config(const char *path, uint16_t *crc);

#endif /* QNAV_NAVBRIDGE_REPLAY_H */
