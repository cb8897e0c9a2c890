/*
 * Writes an LCM log holding one message of every qnav type on its usual channel, made by
 * the generated C encoders, so that the Java side (DecodeLog.java, lcm-spy's decoding)
 * can be checked against it.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <lcm/eventlog.h>

#include "qnav_command_t.h"
#include "qnav_goal_t.h"
#include "qnav_link_status_t.h"
#include "qnav_path_qualities_t.h"
#include "qnav_pose_t.h"
#include "qnav_scan_t.h"

static int put(lcm_eventlog_t *log, const char *channel, const void *data, int len)
{
    lcm_eventlog_event_t ev;
    memset(&ev, 0, sizeof ev);
    ev.timestamp = 1700000000000000LL;
    ev.channellen = (int32_t)strlen(channel);
    ev.datalen = len;
    ev.channel = (char *)channel;
    ev.data = (void *)data;
    return lcm_eventlog_write_event(log, &ev);
}

#define PUT(log, ch, T, msg)                                                                \
    do {                                                                                    \
        static uint8_t buf_[8192];                                                          \
        int n_ = T##_encode(buf_, 0, (int)sizeof buf_, (msg));                              \
        if (n_ <= 0 || put((log), (ch), buf_, n_) != 0) {                                   \
            fprintf(stderr, "make_sample_log: cannot write %s\n", (ch));                    \
            return 1;                                                                       \
        }                                                                                   \
    } while (0)

int main(int argc, char **argv)
{
    static qnav_scan_t scan;
    static qnav_path_qualities_t q;
    qnav_goal_t goal;
    qnav_command_t cmd;
    qnav_pose_t pose;
    qnav_link_status_t st;
    lcm_eventlog_t *log;
    int k;
    if (argc != 2) {
        fprintf(stderr, "usage: make_sample_log OUT.lcmlog\n");
        return 2;
    }
    log = lcm_eventlog_create(argv[1], "w");
    if (log == NULL) {
        fprintf(stderr, "make_sample_log: %s: cannot create\n", argv[1]);
        return 1;
    }
    scan.seq = 42;
    scan.n_sectors = 16;
    scan.max_range_mm = 5000;
    scan.goal_bearing_cdeg = -4500;
    for (k = 0; k < 16; ++k) {
        scan.ranges_mm[k] = 1000 + k;
    }
    memset(&goal, 0, sizeof goal);
    goal.goal_id = 7;
    goal.bearing_cdeg = 9000;
    memset(&cmd, 0, sizeof cmd);
    cmd.scan_seq = 42;
    cmd.heading_deg = -30;
    cmd.speed_q15 = 16384;
    cmd.speed = 0.5;
    q.scan_seq = 42;
    q.best_deg = -30;
    for (k = 0; k < 360; ++k) {
        q.quality_q15[k] = (int16_t)(k * 90);
        q.quality[k] = (float)(k * 90) / 32768.0f;
    }
    memset(&pose, 0, sizeof pose);
    pose.x_m = 1.5;
    pose.y_m = 2.5;
    memset(&st, 0, sizeof st);
    st.mode = 1;
    st.drop_crc = 3;
    PUT(log, "QNAV_SCAN", qnav_scan_t, &scan);
    PUT(log, "QNAV_GOAL", qnav_goal_t, &goal);
    PUT(log, "QNAV_COMMAND", qnav_command_t, &cmd);
    PUT(log, "QNAV_QUALITIES", qnav_path_qualities_t, &q);
    PUT(log, "QNAV_POSE", qnav_pose_t, &pose);
    PUT(log, "QNAV_LINK_STATUS", qnav_link_status_t, &st);
    lcm_eventlog_destroy(log);
    return 0;
}
