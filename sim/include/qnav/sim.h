/*
 * The qnav simulator's C API: a Box2D world with a two-wheeled robot carrying N sonar
 * sectors, sensor and actuation noise, collision recovery and the paper's episodes and
 * fitness (Knudson & Tumer §3.3-3.4, Eq. 1-3). The controller that drives the simulated
 * robot is libqnav itself (qnav_ctrl_t), linked unchanged. C++17 inside, this C API
 * outside, so that simevo, navbridge and tests all drive it the same way.
 *
 * Use: qnav_sim_robot_load() + qnav_sim_env_load() (immutable, shareable between
 * contexts and threads) -> qnav_sim_config_default() -> edit -> qnav_sim_create() ->
 * either qnav_sim_run_episode() (whole episodes) or the step-wise API
 * (qnav_sim_reset / qnav_sim_scan / qnav_sim_command / qnav_sim_advance / qnav_sim_state /
 * qnav_sim_result) -> qnav_sim_destroy(). One context is used by one thread at a time;
 * different contexts may run in parallel. See docs/sim.md.
 *
 * Statuses: as in libqnav, what can fail on its input (load, parse, create, an episode,
 * reset, place) is QNAV_CHECK_RESULT; the per-tick calls (scan, command, advance, state,
 * result) fail only when misused (null, before the first reset), like a step, and are not.
 *
 * Frames and units: world frame x right, y up, metres; headings in the world frame are
 * radians counter-clockwise from +x. Robot-frame angles (scan, bearing, command) are
 * counter-clockwise positive, 0 = straight ahead, as in libqnav. Time is counted in
 * control ticks of QNAV_SIM_TICK_S seconds.
 */
#ifndef QNAV_SIM_H
#define QNAV_SIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "qnav/ctrl.h"
#include "qnav/check.h"
#include "qnav/map.h"
#include "qnav/nav.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Control tick, seconds. Fixed (DESIGN.md §4): tau_c counts these ticks. */
#define QNAV_SIM_TICK_S 0.1

/* Size of an error buffer that always holds a full message. */
#define QNAV_SIM_ERRLEN 512

/* Results of functions that can fail. 0 is success, negatives are errors. Every failing
 * function that takes err/errlen writes one line there: "FILE:LINE: problem" for files,
 * "FIELD: problem" for parameters. */
typedef enum {
    QNAV_SIM_OK = 0,
    QNAV_SIM_E_NULL = -1,    /* a required pointer was null */
    QNAV_SIM_E_IO = -2,      /* a file could not be opened or read */
    QNAV_SIM_E_PARSE = -3,   /* a file is malformed or has a bad or missing value */
    QNAV_SIM_E_PARAM = -4,   /* an impossible parameter (sector count, noise, controller
                                that does not match the context, ...) */
    QNAV_SIM_E_WORLD = -5,   /* an inconsistent world (start zone inside an obstacle or
                                outside the arena, destination unreachable by geometry) */
    QNAV_SIM_E_STATE = -6,   /* step-wise call out of order (no episode reset yet) */
    QNAV_SIM_E_NOMEM = -7    /* allocation failed */
} qnav_sim_status_t;

/* A robot profile (a TOML file in data/robots/) and an environment (data/envs/). Opaque,
 * immutable after loading; one loaded object may be shared by many contexts. */
typedef struct qnav_sim_robot qnav_sim_robot_t;
typedef struct qnav_sim_env qnav_sim_env_t;
/* A simulation context: one Box2D world, one robot, its generators. Holds one episode at
 * a time and may run any number of them in sequence. */
typedef struct qnav_sim qnav_sim_t;

/*
 * Load a robot profile. spec is a file path, or a bare name (no '/', no ".toml") looked
 * up as <data>/robots/<name>.toml, where <data> is $QNAV_DATA_DIR if set, else the
 * source tree's data/ folder. Returns QNAV_SIM_OK and *out (free with
 * qnav_sim_robot_free), or QNAV_SIM_E_NULL / _IO / _PARSE / _NOMEM with *out = NULL and
 * "FILE:LINE: problem" in err.
 */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_robot_load(const char *spec, qnav_sim_robot_t **out, char *err,
                                      size_t errlen);
/* Same from TOML text in memory; name stands in for the file name in messages. */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_robot_parse(const char *text, size_t len, const char *name,
                                       qnav_sim_robot_t **out, char *err, size_t errlen);
void qnav_sim_robot_free(qnav_sim_robot_t *robot);

/* Environments: as for robots, bare names are looked up as <data>/envs/<name>.toml.
 * A start zone that overlaps an obstacle or leaves the arena, or a destination inside an
 * obstacle, is refused with QNAV_SIM_E_WORLD.
 * A spec "gen:FAMILY:SEED[:DIFFICULTY[:ROBOT]]" is a generated world (docs/sim.md, "World
 * families"): FAMILY one of qnav_sim_world_families(), SEED a whole number in
 * [0, 2^64 - 1], DIFFICULTY in [0, 1] with at most 3 decimals (default 0.5), ROBOT the
 * robot (name or file) whose body the world is made passable for and whose diameter sets
 * gap, corridor and door widths (default tekbot). The same spec gives the same world; its
 * name is the spec with every field spelled out ("gen:gaps:7:0.5:tekbot"). A malformed
 * spec is QNAV_SIM_E_PARAM with one line naming the field ("world spec 'gen:x:1': unknown
 * family 'x' (families: ...)"). */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_env_load(const char *spec, qnav_sim_env_t **out, char *err,
                                    size_t errlen);
/* The world families a "gen:" spec may name, comma-separated ("clutter, gaps, ..."); a
 * static string. */
const char *qnav_sim_world_families(void);
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_env_parse(const char *text, size_t len, const char *name,
                                     qnav_sim_env_t **out, char *err, size_t errlen);
void qnav_sim_env_free(qnav_sim_env_t *env);

/* What a loaded robot profile says (read-only view). */
typedef struct {
    const char *name;          /* profile name, e.g. "pioneer3dx"; owned by the robot */
    double radius_m;           /* collision radius of the body, m */
    double v_max_mps;          /* maximum forward speed, m/s */
    double accel_mps2;         /* maximum acceleration, m/s^2 */
    double decel_mps2;         /* maximum deceleration, m/s^2 */
    double turn_rate_max_dps;  /* maximum turn rate, deg/s */
    double range_min_m;        /* sonar minimum range (closer reads this), m */
    double range_max_m;        /* sonar maximum range (farther is clipped), m */
    uint16_t default_sectors;  /* sector count when the config asks for 0 */
    double sonar_offset_m;     /* robot centre to the transducers (ranges start there), m */
    double wheel_base_m;       /* distance between the drive wheels (track), m */
    uint32_t um_per_count;     /* the board's wheel travel per encoder count, micrometres */
    uint32_t tick_ms;          /* control tick, ms (QNAV_SIM_TICK_S) */
    double sensor_noise;       /* the profile's typical p_s (qnav-sim's default) */
    double actuation_noise;    /* the profile's typical p_a (qnav-sim's default) */
    uint16_t turn_full_deg;    /* where a mixer turns at full wheel speed (qnav_drive_mix), deg:
                                  2 v_max / (wheel_base x heading_gain_per_s) rad, 90..360 */
} qnav_sim_robot_info_t;
void qnav_sim_robot_info(const qnav_sim_robot_t *robot, qnav_sim_robot_info_t *info);

/* The probabilistic policy hand-tuned for this robot (the paper tunes it "to the robot"):
 * the profile's [probabilistic] k_goal and k_safe (given, or range_max_m / safe_m and at
 * least 4) rounded to Q8.8, or libqnav's qnav_policy_prob_default() when the profile has
 * none. */
void qnav_sim_robot_prob_policy(const qnav_sim_robot_t *robot, qnav_policy_t *policy);

/* What a loaded environment says (read-only view). */
typedef struct {
    const char *name;          /* environment name; owned by the env */
    double width_m, height_m;  /* arena, walls at x = 0, x = width, y = 0, y = height, m */
    double dest_x_m, dest_y_m; /* destination centre, world frame, m */
    double dest_radius_m;      /* reached when the robot centre is this close, m */
    double episode_limit_s;    /* episode time limit, s */
    uint32_t n_obstacles;      /* circles + boxes */
    uint32_t n_start_zones;    /* rectangles the start point is drawn from */
    const char *source;        /* file it was read from (the name given to _parse);
                                  owned by the env */
} qnav_sim_env_info_t;
void qnav_sim_env_info(const qnav_sim_env_t *env, qnav_sim_env_info_t *info);

/* How an episode's figures become its fitness R (docs/sim.md, "Fitness"). */
typedef enum {
    /* Default. An episode that reaches the destination: Eq. 1-3 as in the paper. One that
     * does not: f2 = 0 (no reward for time) and f1 = progress toward the destination,
     * (d_start - d_end) / d_start clamped to [0, 1], so it earns at most 1 - tau_c and an
     * arrival up to 11 - tau_c. */
    QNAV_SIM_FITNESS_PROGRESS = 0,
    /* Eq. 1-3 literally for every episode (ablation): a robot that circles until the time
     * limit still earns ~6 of an arrival's 6.5-8.5. */
    QNAV_SIM_FITNESS_PAPER = 1
} qnav_sim_fitness_rule_t;

/* The rule's name as experiment files and command lines spell it ("progress", "paper"),
 * or NULL for a value that is not a rule. */
const char *qnav_sim_fitness_rule_name(qnav_sim_fitness_rule_t rule);
/* The rule called name (as above). Returns QNAV_SIM_OK and *rule, QNAV_SIM_E_NULL, or
 * QNAV_SIM_E_PARAM for an unknown name (*rule unchanged). */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_fitness_rule_parse(const char *name, qnav_sim_fitness_rule_t *rule);
/* The known rules' names, comma separated ("progress, paper"), for messages. */
const char *qnav_sim_fitness_rule_names(void);

/* Context settings. Obtain with qnav_sim_config_default(), then edit. */
typedef struct {
    uint16_t n_sectors;        /* sonar sectors N, 1..360; 0 = the profile's default */
    double sensor_noise;       /* p_s in [0, 1] (0.05 = 5 %): range*(1+p_s*n), bearing
                                  + p_s*pi*n rad, n ~ N(0,1) fresh per reading */
    double actuation_noise;    /* p_a in [0, 1]: commanded speed*(1+p_a*n), commanded heading
                                  + p_a*pi*n rad, fresh per tick */
    uint64_t seed;             /* context seed; an episode's randomness depends only on
                                  (seed, episode_seed), never on earlier episodes */
    double episode_limit_s;    /* episode time limit, s; 0 = the environment's */
    qnav_sim_fitness_rule_t fitness;  /* how R is computed (qnav_sim_result_t.R) */
    double map_frame_deg;      /* a profile's [map]: its grid's angle to the world's walls,
                                  deg in [0, 360) (0: aligned with the arena's walls, which a
                                  board's heading sensor never is); < 0: drawn per episode
                                  from (seed, episode_seed), the default */
    double survey_m;           /* a profile's [map]: > 0 starts every episode's map with what
                                  the sonar shows, noiseless, from every point of a grid this
                                  many metres apart where the body fits (a known world: what
                                  a miss owes to exploring; docs/sim.md, "A known world");
                                  0: off, the default; else 0.05..10 */
} qnav_sim_config_t;

/* Defaults: profile's sectors, no noise, seed 1, the environment's limit, fitness
 * QNAV_SIM_FITNESS_PROGRESS, the map's grid at an angle drawn per episode, no survey. */
void qnav_sim_config_default(qnav_sim_config_t *cfg);

/*
 * Create a context for (robot, env, cfg); the context keeps its own copies, so robot and
 * env may be freed afterwards. Returns QNAV_SIM_OK and *out, or QNAV_SIM_E_NULL,
 * QNAV_SIM_E_PARAM (n_sectors > 360, noise outside [0, 1] or not finite, limit outside
 * [0, 36000] s, fitness not a qnav_sim_fitness_rule_t, survey_m outside 0.05..10 or without
 * a [map] in the profile) with a "FIELD: problem" line in err, QNAV_SIM_E_WORLD (a start zone closer
 * than the robot's radius to an obstacle or wall: "FILE:LINE: ...") or QNAV_SIM_E_NOMEM.
 */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_create(const qnav_sim_robot_t *robot, const qnav_sim_env_t *env,
                                  const qnav_sim_config_t *cfg, qnav_sim_t **out, char *err,
                                  size_t errlen);
void qnav_sim_destroy(qnav_sim_t *sim);

/* The controller configuration that matches this context: qnav_sim_robot_ctrl_config() of
 * its robot at its sector count. */
void qnav_sim_ctrl_config(const qnav_sim_t *sim, qnav_ctrl_config_t *cfg);

/* The controller configuration a robot profile gives at n_sectors (0: the profile's
 * default_sectors): the one mapping from a profile to libqnav, used by the simulator, the
 * board header generator (qnav-sim robot-header) and navbridge --robot. Sets n_sectors,
 * max_range_mm ([sonar] range_max_m), body_radius_mm ([body] radius_m), safety_mm
 * ([clearance] safety_m), pass_mm ([map] pass_m when the profile has a map that gives it,
 * else safety_m), sensor_offset_mm ([sonar] offset_m), range_min_mm ([sonar]
 * range_min_m), v_max_mm_s ([drive] v_max_mps), decel_mm_s2 ([drive] decel_mps2, 0 with
 * [clearance] speed_guard = false);
 * every other field is qnav_ctrl_config_default()'s (docs/sim.md, "One robot
 * description"). */
void qnav_sim_robot_ctrl_config(const qnav_sim_robot_t *robot, uint16_t n_sectors,
                                qnav_ctrl_config_t *cfg);

/* The map a robot profile's [map] section describes (qnav/map.h; docs/sim.md): 1 and cfg
 * filled when the profile has one (the simulator, the SIL robot and a board made from the
 * profile then plan over it), 0 and cfg left alone when it has none. */
int qnav_sim_robot_map_config(const qnav_sim_robot_t *robot, qnav_map_config_t *cfg);

/* The board's memory for that map ([map] bytes): it places the map afresh at each goal
 * over the largest square the bytes hold (qnav_map_place), and so do the simulator and the
 * SIL robot; 0 when the profile gives none (the map then covers the whole arena). */
uint32_t qnav_sim_robot_map_bytes(const qnav_sim_robot_t *robot);

/* The episode's figures (paper Eq. 1-3; definitions in docs/sim.md). */
typedef struct {
    qnav_sim_fitness_rule_t fitness; /* the rule f1, f2 and R were computed with */
    double l;                  /* path length driven, m (sum of per-tick displacement) */
    double beta_l;             /* best path length: straight line from the start to the
                                  edge of the destination circle, m */
    double tau_l;              /* time used, s (ticks * QNAV_SIM_TICK_S) */
    double beta_tau;           /* shortest possible time: beta_l from rest at the
                                  profile's v_max and accel, s */
    double d_start_m;          /* robot centre to the destination circle's edge at the
                                  start, m (>= 0; equals beta_l) */
    double d_end_m;            /* the same at the end of the episode (0 when reached), m */
    double f1;                 /* Eq. 2: l/beta_l if l <= beta_l else beta_l/l; progress
                                  rule, not reached: (d_start - d_end)/d_start in [0, 1] */
    double f2;                 /* Eq. 3: tau_l/beta_tau if tau_l <= beta_tau else
                                  beta_tau/tau_l; progress rule, not reached: 0 */
    uint32_t tau_c;            /* ticks spent in collision recovery */
    double R;                  /* Eq. 1: eta1*f1 + eta2*f2 - tau_c, eta1 = 1, eta2 = 10 */
    bool reached;              /* the robot centre came within dest_radius_m */
    uint32_t ticks;            /* control ticks run */
    uint32_t collisions;       /* recovery manoeuvres started */
    double start_x_m, start_y_m;     /* start point, world frame, m */
    double start_heading_rad;        /* start heading, world frame, rad */
} qnav_sim_result_t;

/* One trajectory sample, delivered after every tick (and once after reset, tick 0). */
typedef struct {
    uint32_t tick;             /* ticks since reset */
    double x_m, y_m;           /* robot centre, world frame, m */
    double heading_rad;        /* true heading, world frame, rad, (-pi, pi] */
    double speed_mps;          /* forward speed, m/s */
    qnav_deg_t cmd_heading_deg;  /* command applied this tick, robot frame, deg */
    double cmd_speed;          /* commanded speed fraction of v_max, [0, 1] */
    bool recovering;           /* in a collision recovery manoeuvre */
    bool collided;             /* a new collision started this tick */
    int8_t escape_side;        /* the controller's escape after this tick's step: 0 none,
                                  +1 / -1 following a boundary on the right / left */
    double goal_bearing_deg;   /* the destination the command answered, as the controller
                                  was given it: robot frame, deg; with a map, the plan's
                                  sub-goal (0 before the first command) */
    double goal_range_m;       /* its range, m: with a map, the planned distance */
} qnav_sim_sample_t;

/* Called once per sample; user is passed through. */
typedef void (*qnav_sim_trace_fn)(void *user, const qnav_sim_sample_t *sample);

/*
 * Run one whole episode: reset with episode_seed, then every tick scan -> qnav_ctrl_step
 * -> command -> advance, until the destination is reached or the limit expires. ctrl is
 * an initialised libqnav controller (network, probabilistic or table mode) whose n_sectors
 * and max_range_mm match qnav_sim_ctrl_config(); it is only read. trace may be NULL.
 * Returns QNAV_SIM_OK with *res, or QNAV_SIM_E_NULL / QNAV_SIM_E_PARAM (controller not
 * ready or not matching).
 */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_run_episode(qnav_sim_t *sim, const qnav_ctrl_t *ctrl,
                                       uint64_t episode_seed, qnav_sim_result_t *res,
                                       qnav_sim_trace_fn trace, void *user);

/*
 * The same with any controller of the table in qnav/nav.h (path-quality "body" or
 * "literal", "vfh", ...): qnav_nav_reset() first, then every tick qnav_nav_step(). nav must
 * be initialised for this context's sensors. Same statuses.
 */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_run_episode_nav(qnav_sim_t *sim, qnav_nav_t *nav, uint64_t episode_seed,
                                           qnav_sim_result_t *res, qnav_sim_trace_fn trace,
                                           void *user);

/* The one-line message of the last failing call on this context (run_episode, reset,
 * advance, place), or "" when none failed. Valid until the next call on the context. */
const char *qnav_sim_last_error(const qnav_sim_t *sim);

/* ---- Step-wise API (software in the loop) ---------------------------------------- */

/* One tick's sensing, exactly what the controller takes. */
typedef struct {
    uint16_t n_sectors;                    /* N */
    qnav_mm_t max_range_mm;                /* profile's maximum range, mm */
    qnav_mm_t ranges_mm[QNAV_MAX_SECTORS]; /* sector k centred on k*360/N deg, robot
                                              frame, CCW; nearest obstacle in its cone,
                                              noisy, clipped to [min, max] range, mm */
    qnav_cdeg_t goal_bearing_cdeg;         /* destination bearing, robot frame, 0.01 deg,
                                              -18000..17999, from the noisy heading */
    qnav_cdeg_t prev_heading_cdeg;         /* the last command's heading (qnav_sim_command)
                                              in this tick's robot frame, from the same
                                              sensed heading, 0.01 deg; 0 before the first
                                              command: qnav_ctrl_input_t.prev_heading_cdeg */
    qnav_mm_t goal_range_mm;               /* distance from the robot's centre to the
                                              destination's, mm, 1..65535 (the pose the
                                              board's odometry or the inertial sensors give;
                                              exact): qnav_ctrl_input_t.goal_range_mm */
    uint8_t escape_clear;                  /* 1: pass this tick's controller a cleared
                                              escape memory (qnav_ctrl_input_t.escape):
                                              the map's plan grew (its way closed). With a
                                              profile's [map], goal_bearing_cdeg and
                                              goal_range_mm are the plan's sub-goal and
                                              planned distance (qnav/map.h) */
    uint16_t escape_grow_mm;               /* unless escape_clear: grow the escape memory
                                              passed to this tick's controller by this much
                                              (qnav_escape_follow_plan applies both): the
                                              map's new plan is that much longer; 0: none */
} qnav_sim_scan_t;

/* The robot's true state. */
typedef struct {
    uint32_t tick;             /* ticks since reset */
    double x_m, y_m;           /* robot centre, world frame, m */
    double heading_rad;        /* true heading, world frame, rad, (-pi, pi] */
    double speed_mps;          /* forward speed, m/s */
    double goal_distance_m;    /* robot centre to destination centre, m */
    bool recovering;           /* in a collision recovery manoeuvre (commands ignored) */
    uint32_t recovery_ticks_left;  /* ticks of the manoeuvre still to run */
    uint32_t collisions;       /* recovery manoeuvres started so far */
    bool done;                 /* episode over: reached, or the limit expired */
    bool reached;              /* destination reached */
} qnav_sim_state_t;

/* Start a new episode: random start point in a random start zone (zones weighted by
 * area), random heading, robot at rest. Computes the first scan. */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_reset(qnav_sim_t *sim, uint64_t episode_seed);

/* For tests and tools: move the robot of the current episode (reset first) to a pose
 * (world frame, m and rad) at rest, clear collisions and figures (the start becomes this
 * pose) and compute a new scan. QNAV_SIM_E_PARAM for a pose outside the arena. */
QNAV_CHECK_RESULT qnav_sim_status_t qnav_sim_place(qnav_sim_t *sim, double x_m, double y_m, double heading_rad);

/* Copy this tick's scan, every field (computed once per tick at reset/advance, so reading
 * it twice gives the same values; qnav_sim_command changes prev_heading_cdeg only from the
 * next advance). QNAV_SIM_E_STATE before the first reset. */
qnav_sim_status_t qnav_sim_scan(const qnav_sim_t *sim, qnav_sim_scan_t *scan);

/* Set the command for the next advance. heading is robot-frame deg (wrapped), speed is a
 * fraction of v_max (clamped to [0, 1]). Kept until replaced; ignored while recovering. */
qnav_sim_status_t qnav_sim_command(qnav_sim_t *sim, const qnav_ctrl_output_t *out);
qnav_sim_status_t qnav_sim_command_raw(qnav_sim_t *sim, double heading_deg, double speed);

/* Advance one tick (QNAV_SIM_TICK_S): actuation noise, heading controller, wheels and
 * slip, Box2D step, collision detection and recovery, then the next scan. Does nothing
 * once the episode is done. QNAV_SIM_E_STATE before the first reset. */
qnav_sim_status_t qnav_sim_advance(qnav_sim_t *sim);

/* The true state, and the figures so far (final once state.done). */
qnav_sim_status_t qnav_sim_state(const qnav_sim_t *sim, qnav_sim_state_t *state);
qnav_sim_status_t qnav_sim_result(const qnav_sim_t *sim, qnav_sim_result_t *res);

/* Fitness of an episode from its raw figures, for tests and tools: sets res->fitness to
 * rule and fills f1, f2 and R from l, beta_l, tau_l, beta_tau, tau_c, reached, d_start_m
 * and d_end_m (an unknown rule is treated as QNAV_SIM_FITNESS_PROGRESS). */
void qnav_sim_fitness(qnav_sim_result_t *res, qnav_sim_fitness_rule_t rule);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_SIM_H */
