/*
 * A test's hand on the LCM bus, for tests/navbridge/goal_trust.sh: publish one goal or
 * route on a channel of our choosing (the stray sender and the operator alike), or wait
 * for a number of QNAV_SCAN messages and say which goal ids the board reported in them
 * (the board echoes the goal it drives to in every scan, so a goal navbridge obeyed shows
 * there within a tick or two).
 *
 * usage: lcm_poke URL ACTION...   each ACTION one of, done in order:
 *          goal CHANNEL GOAL_ID BEARING_CDEG     publish a goal_t
 *          route CHANNEL X:Y RADIUS_M            publish a one-point waypoints_t
 *          scans N                               wait for N QNAV_SCAN messages
 * Exit 0 on success; 1 when the bus or N scans could not be had (scans waits for events,
 * with a last-resort limit of 600 s so a broken run ends); 2 for bad usage.
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lcm/lcm.h>

#include "qnav_goal_t.h"
#include "qnav_scan_t.h"
#include "qnav_waypoints_t.h"

typedef struct {
    int seen;
    int with_goal;   /* scans whose goal_id is not 0 */
    int max_goal_id;
} scan_tally_t;

static void on_scan(const lcm_recv_buf_t *rbuf, const char *channel, const qnav_scan_t *msg,
                    void *user)
{
    scan_tally_t *t = (scan_tally_t *)user;
    (void)rbuf;
    (void)channel;
    t->seen++;
    t->with_goal += msg->goal_id != 0;
    if (msg->goal_id > t->max_goal_id) {
        t->max_goal_id = msg->goal_id;
    }
}

static int wait_scans(lcm_t *lcm, int n)
{
    scan_tally_t t;
    int idle_s = 0, r = 0;
    qnav_scan_t_subscription_t *sub;
    memset(&t, 0, sizeof t);
    sub = qnav_scan_t_subscribe(lcm, "QNAV_SCAN", on_scan, &t);
    while (sub != NULL && t.seen < n && idle_s < 600 && r >= 0) {
        r = lcm_handle_timeout(lcm, 1000);
        idle_s += r == 0;
    }
    if (sub != NULL) {
        qnav_scan_t_unsubscribe(lcm, sub);
    }
    printf("scans %d with_goal %d max_goal_id %d\n", t.seen, t.with_goal, t.max_goal_id);
    return t.seen >= n ? 0 : 1;
}

int main(int argc, char **argv)
{
    lcm_t *lcm;
    int k = 2, rc = 0;
    if (argc < 4) {
        fprintf(stderr, "usage: lcm_poke URL ACTION... (goal CHANNEL ID CDEG | route CHANNEL "
                        "X:Y R | scans N)\n");
        return 2;
    }
    lcm = lcm_create(argv[1]);
    if (lcm == NULL) {
        fprintf(stderr, "lcm_poke: %s: cannot join the LCM bus\n", argv[1]);
        return 1;
    }
    /* the actions in order, in one process: a loaded machine starts processes slowly */
    while (rc == 0 && k < argc) {
        if (strcmp(argv[k], "goal") == 0 && k + 3 < argc) {
            qnav_goal_t g;
            memset(&g, 0, sizeof g);
            g.goal_id = atoi(argv[k + 2]);
            g.bearing_cdeg = (int16_t)atoi(argv[k + 3]);
            rc = qnav_goal_t_publish(lcm, argv[k + 1], &g) == 0 ? 0 : 1;
            k += 4;
        } else if (strcmp(argv[k], "route") == 0 && k + 3 < argc) {
            qnav_waypoints_t w;
            memset(&w, 0, sizeof w);
            w.route_id = 7;
            w.n = 1;
            if (sscanf(argv[k + 2], "%lf:%lf", &w.x_m[0], &w.y_m[0]) != 2) {
                rc = 2;
                break;
            }
            w.radius_m = atof(argv[k + 3]);
            rc = qnav_waypoints_t_publish(lcm, argv[k + 1], &w) == 0 ? 0 : 1;
            k += 4;
        } else if (strcmp(argv[k], "scans") == 0 && k + 1 < argc) {
            rc = wait_scans(lcm, atoi(argv[k + 1]));
            k += 2;
        } else {
            rc = 2;
        }
    }
    if (rc == 2) {
        fprintf(stderr, "lcm_poke: %s: bad usage\n", argv[k < argc ? k : argc - 1]);
    }
    lcm_destroy(lcm);
    return rc;
}
