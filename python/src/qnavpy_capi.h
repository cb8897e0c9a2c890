/*
 * The C entry points of libqnavpy, the shared library under the qnavpy Python package
 * (python/qnavpy/_lib.py declares them for ctypes). They add what a Python caller needs
 * on top of the simulator's C API (qnav/sim.h), libqnav's controller table (qnav/nav.h),
 * the policy files (qnav/policy_io.h) and simevo's evaluation (SimRunner): coarse calls
 * (one per tick, one per batch) that fill caller-owned arrays, so that the Python side
 * pays one foreign call per step. Policies cross as (kind, hidden, inputs, Q8.8 weights
 * in the policy files' flat order). Every function that can fail returns 0 or a negative
 * status and writes one line into err: the line the command-line tools print after
 * their "PROGRAM: " prefix.
 */
#ifndef QNAVPY_CAPI_H
#define QNAVPY_CAPI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Most weights a policy has: a 3-input network of QNAV_MAX_HIDDEN (32) units. */
#define QPY_MAX_WEIGHTS 161
/* Policy kinds across the boundary: libqnav's (1 prob, 2 net) and "the robot's tuned
 * probabilistic policy" (evaluate only). */
#define QPY_KIND_ROBOT_PROB 0
/* Length of the per-tick integer observation after the N ranges, and of the float and
 * info arrays (see qpy_env_step). */
#define QPY_OBS_INT_EXTRA 5
#define QPY_OBS_FLOAT 5
#define QPY_INFO 10
/* Columns of a trajectory row (qpy_env_trace). */
#define QPY_TRACE_COLS 9
/* Fields of an episode result (qpy_env_result). */
#define QPY_RESULT 16

typedef struct qpy_env qpy_env_t;
typedef struct qpy_ctrl qpy_ctrl_t;

/* libqnavpy's version (the project's VERSION). */
const char *qpy_version(void);
/* The generated world families, comma separated. */
const char *qpy_world_families(void);
/* Controllers of libqnav's table, comma separated ("body, literal, vfh"). */
const char *qpy_controller_names(void);

/* Robot profile figures: info[0..11] = radius_m, v_max_mps, accel_mps2, decel_mps2,
 * turn_rate_max_dps, range_min_m, range_max_m, default_sectors, sonar_offset_m,
 * wheel_base_m, sensor_noise, actuation_noise; its name into name (namelen bytes); its
 * tuned probabilistic policy's k_goal, k_safe (Q8.8) into prob[2]. */
int qpy_robot_info(const char *spec, double *info, char *name, size_t namelen, int16_t *prob,
                   char *err, size_t errlen);
/* Environment figures: info[0..8] = width_m, height_m, dest_x_m, dest_y_m, dest_radius_m,
 * episode_limit_s, n_obstacles, n_start_zones, unused; its name into name. */
int qpy_world_info(const char *spec, double *info, char *name, size_t namelen, char *err,
                   size_t errlen);

/* Policies. */
int qpy_policy_check(int32_t kind, int32_t hidden, int32_t inputs, const int16_t *w, int32_t nw,
                     char *err, size_t errlen);
int qpy_policy_read(const char *path, int32_t *kind, int32_t *hidden, int32_t *inputs, int16_t *w,
                    int32_t *nw, char *err, size_t errlen);
int qpy_policy_write(const char *path, int32_t kind, int32_t hidden, int32_t inputs,
                     const int16_t *w, int32_t nw, const char *comment, char *err, size_t errlen);

/* A simulation context as `qnav-sim run` makes it (noise < 0: the profile's typical;
 * map_frame_deg < 0: the map's grid turned per episode, as --map-frame's default;
 * survey_m > 0: each episode's map starts surveyed, as --survey; 0: not). */
int qpy_env_create(const char *robot, const char *world, int32_t sectors, double sensor_noise,
                   double actuation_noise, uint64_t seed, double limit_s, const char *fitness,
                   double map_frame_deg, double survey_m, qpy_env_t **out, char *err, size_t errlen);
void qpy_env_free(qpy_env_t *env);
/* n_sectors, max_range_mm, limit ticks, sensor noise, actuation noise as used. */
void qpy_env_params(const qpy_env_t *env, double *params);
/* Start an episode (ctrl, when not null, is reset too) and write the first observation. */
int qpy_env_reset(qpy_env_t *env, uint64_t episode_seed, qpy_ctrl_t *ctrl, int32_t *obs_i,
                  double *obs_f, double *info, char *err, size_t errlen);
/*
 * One tick: ctrl decides from this tick's scan (exactly as qnav_sim_run_episode_nav does),
 * or with ctrl null the command is (heading_deg, speed); then advance and write the next
 * observation. obs_i: N ranges (mm), goal bearing (0.01 deg), previous heading (0.01 deg),
 * goal range (mm), escape_clear (0/1), escape_grow_mm (qnav_sim_scan_t's: what the map did
 * to the escape memory a caller carries). obs_f: x_m, y_m, heading_rad, speed_mps, goal_distance_m. info: tick,
 * done, reached, recovering, collisions, collided this tick, command heading (deg),
 * command speed (fraction), controller flags (-1 without ctrl), episode R when done.
 */
int qpy_env_step(qpy_env_t *env, qpy_ctrl_t *ctrl, double heading_deg, double speed, int32_t *obs_i,
                 double *obs_f, double *info, char *err, size_t errlen);
/* The episode's figures: R, f1, f2, tau_c, reached, ticks, collisions, l, beta_l, tau_l,
 * beta_tau, d_start_m, d_end_m, start_x_m, start_y_m, start_heading_rad. */
int qpy_env_result(const qpy_env_t *env, double *res, char *err, size_t errlen);
/* A whole episode in C with ctrl (qnav_sim_run_episode_nav); the trajectory is kept for
 * qpy_env_trace. */
int qpy_env_run_episode(qpy_env_t *env, qpy_ctrl_t *ctrl, uint64_t episode_seed, double *res,
                        char *err, size_t errlen);
/* Rows of the last run_episode's trajectory; copies them (tick, x_m, y_m, heading_rad,
 * speed_mps, cmd_heading_deg, cmd_speed, recovering, collided) into rows when not null. */
int64_t qpy_env_trace(const qpy_env_t *env, double *rows);
/* Environment geometry for plots: circles (x, y, r) and boxes (x, y, w, h, angle_deg);
 * counts returned through n_circles/n_boxes, arrays filled when not null. */
void qpy_env_shapes(const qpy_env_t *env, double *circles, int32_t *n_circles, double *boxes,
                    int32_t *n_boxes);

/* A controller of libqnav's table: name "body", "literal" or "vfh"; sensors from env when
 * not null, else from robot (a spec) at sectors, else libqnav's defaults with sectors and
 * max_range_mm (0: default). Policy kind 0 with robot or env: the robot's probabilistic
 * policy; kind -1: none (vfh). table: compile the policy into a quality table. */
int qpy_ctrl_create(const char *name, const qpy_env_t *env, const char *robot, int32_t sectors,
                    int32_t max_range_mm, int32_t kind, int32_t hidden, int32_t inputs,
                    const int16_t *w, int32_t nw, int32_t table, qpy_ctrl_t **out, char *err,
                    size_t errlen);
void qpy_ctrl_free(qpy_ctrl_t *ctrl);
/* n_sectors and max_range_mm the controller was made for. */
void qpy_ctrl_sensors(const qpy_ctrl_t *ctrl, int32_t *n_sectors, int32_t *max_range_mm);
/* Forget the escape memory and VFH+ histogram (start of an episode). */
void qpy_ctrl_reset(qpy_ctrl_t *ctrl);
/* One qnav step on a scan of n ranges; the escape memory is carried to the next step,
 * cleared first when escape_clear is 1, else grown by escape_grow_mm (a map's verdicts:
 * qnav_sim_scan_t).
 * out[4] = heading_deg, speed (Q1.15), quality (Q1.15), flags. qualities (360 Q1.15
 * values, path-quality controllers only) when not null. */
int qpy_ctrl_step(qpy_ctrl_t *ctrl, const uint16_t *ranges_mm, int32_t n, int32_t goal_bearing_cdeg,
                  int32_t prev_heading_cdeg, int32_t goal_range_mm, int32_t escape_clear,
                  int32_t escape_grow_mm, int32_t *out, int16_t *qualities, char *err,
                  size_t errlen);
/* The rank key and quality grids of a path-quality controller's policy, 32 distance levels
 * x 181 dtheta (what tools/plot_policy.py draws): keys and qualities row-major. */
int qpy_ctrl_grid(const qpy_ctrl_t *ctrl, int16_t *keys, int16_t *qualities, int32_t *rank,
                  char *err, size_t errlen);

/*
 * simevo eval for a batch: every policy over episodes seeded mix_seed(seed, i), i =
 * 0..episodes-1, in a context like `simevo eval --env --robot --sectors --noise --seed
 * --fitness`, on jobs threads (0: all cores). Policy p is kind[p], hidden[p], inputs[p]
 * and w[p * QPY_MAX_WEIGHTS ...]. Results row-major [policy][episode].
 */
int qpy_evaluate(const char *robot, const char *world, int32_t sectors, double noise,
                 uint64_t seed, const char *fitness, int32_t n_policies, const int32_t *kind,
                 const int32_t *hidden, const int32_t *inputs, const int16_t *w, uint32_t episodes,
                 int32_t jobs, double *R, uint8_t *reached, uint32_t *tau_c, double *f1, double *f2,
                 char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* QNAVPY_CAPI_H */
