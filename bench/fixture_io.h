/*
 * What the benchmark's generators share (host only): the policy list format of
 * bench/fixtures/policies.txt and the C headers of policies and scans that the benchmark
 * programs compile (bench_fixtures.h's types, QNAV_FLASH data). gen_fixtures.c writes the
 * fixtures with them, adversary.c the adversarial set; both drive the simulator along
 * episodes and take its scans at the poses they kept. Bad input: one line
 * "FILE:LINE: problem" on stderr, exit 2; a failed write: exit 1.
 */
#ifndef QNAV_BENCH_FIXTURE_IO_H
#define QNAV_BENCH_FIXTURE_IO_H

#include <stdint.h>
#include <stdio.h>

#include "bench_fixtures.h"
#include "qnav/sim.h"

/* One policy of a list: what its header entry says. */
typedef struct {
    char id[QNAV_BENCH_ID_LEN];
    uint8_t set;       /* QNAV_BENCH_SET_* */
    uint8_t group;     /* AVR table image, 0 = none */
    char provenance[256];
    qnav_policy_t policy;
} qnav_fx_policy_t;

/* One scan of a header: n ranges at ranges[offset..] of the writer's array. */
typedef struct {
    uint16_t n;
    uint8_t type;      /* QNAV_BENCH_SCAN_* */
    uint8_t k;
    qnav_cdeg_t bearing;
    uint32_t offset;
    char note[160];    /* printed beside it, may be empty */
} qnav_fx_scan_t;

/* A header being written: to a temporary file, renamed into place when complete. */
typedef struct {
    FILE *f;
    char tmp[1100];
    char path[1100];
} qnav_fx_out_t;

extern const char *const qnav_fx_set_names[QNAV_BENCH_SETS];

/* Print "qnav bench: <message>" on stderr and exit with code. */
void qnav_fx_fail(int code, const char *fmt, ...);

/* Is s a policy ID (1..23 letters, digits or '-')? */
int qnav_fx_id_ok(const char *s);

/* Read the policy list dir/name (policies.txt's format: ID SET TABLE SOURCE EXPERIMENT
 * CONDITION RUN COMMIT) into out[0..max-1]; SOURCE paths are relative to dir. Returns the
 * number of policies; bad input fails (exit 2). */
unsigned qnav_fx_read_list(const char *dir, const char *name, qnav_fx_policy_t *out,
                           unsigned max);

/* Open dir/name for writing (fails with exit 1). */
void qnav_fx_open(qnav_fx_out_t *o, const char *dir, const char *name);
/* Complete it: close and rename into place (fails with exit 1). */
void qnav_fx_close(qnav_fx_out_t *o);

/* n integers, 12 to a line, each followed by a comma. */
void qnav_fx_put_values(FILE *f, const int32_t *v, size_t n);

/* dir/bench_policies.h: the n policies as qnav_bench_policies[], under a comment that
 * begins with `about`. */
void qnav_fx_write_policies(const char *dir, const char *about, const qnav_fx_policy_t *p,
                            unsigned n);

/* dir/bench_scans.h: one QNAV_FLASH array of ranges per sector count (in the order the
 * scans first use it; a sector count's scans must follow each other in ranges[]) and
 * qnav_bench_scans[], under a comment that begins with `about`. */
void qnav_fx_write_scans(const char *dir, const char *about, const qnav_fx_scan_t *s,
                         unsigned n, const int32_t *ranges, unsigned max_range_mm);

/* A pose of an episode: the robot's centre (m) and heading (rad) in the world, its tick. */
typedef struct {
    double x_m, y_m, heading_rad;
    uint32_t tick;
} qnav_fx_pose_t;

/* Episode episode_seed of ctrl in sim, keeping the pose of every every-th tick (from tick
 * 0), at most max of them, in out; the episode's figures in *res. Returns how many were
 * kept; a failed episode fails (exit 2) naming what. */
unsigned qnav_fx_episode_poses(qnav_sim_t *sim, const qnav_ctrl_t *ctrl, uint64_t episode_seed,
                               uint32_t every, qnav_fx_pose_t *out, unsigned max,
                               qnav_sim_result_t *res, const char *what);

/* The simulator's scan with the robot placed at (x, y, heading), as the fixtures' dense
 * scans; a refused place fails (exit 2) naming what. */
void qnav_fx_scan_at(qnav_sim_t *sim, double x_m, double y_m, double heading_rad,
                     qnav_sim_scan_t *scan, const char *what);

#endif /* QNAV_BENCH_FIXTURE_IO_H */
