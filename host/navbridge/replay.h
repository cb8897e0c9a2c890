/*
 * Replay of a recorded trial through the bridge's controller: every QNAV_SCAN event of an
 * LCM log (lcm-logger's or navbridge --log's) runs through libqnav again with the given
 * policy, and each logged QNAV_COMMAND that answered a scan is compared field by field
 * with the fresh result. Same library, same integers: a clean trial replays identically.
 */
#ifndef QNAV_NAVBRIDGE_REPLAY_H
#define QNAV_NAVBRIDGE_REPLAY_H

#include <stdint.h>
#include <stdio.h>

#include "qnav/ctrl.h"

typedef struct {
    uint64_t scans;       /* QNAV_SCAN events read */
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

#endif /* QNAV_NAVBRIDGE_REPLAY_H */
