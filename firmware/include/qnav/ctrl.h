/*
 * The navigation controller (paper §3.1-3.3). Each control tick it takes N sonar sector
 * ranges and the destination bearing, gives each of the 360 candidate paths a quality in
 * [0, 1), turns to the best path and sets the speed linearly from its quality, capped by
 * what the path's clearance can stop in. A path is as wide as the robot: it sees the
 * nearest reading whose arc, enlarged by the robot's radius plus a safety distance
 * (VFH+), covers it. The best path is the one with the largest rank key: the network's
 * output before its sigmoid (the float network's order, which Q1.15 saturation would
 * hide), or the quality itself for the probabilistic policy. Nothing is remembered
 * between ticks. Fixed point only, no heap, no float, no writable file-scope
 * state: a population of controllers lives side by side in one process.
 *
 * Use: qnav_ctrl_config_default() -> edit fields -> qnav_ctrl_init() (or
 * qnav_ctrl_init_table()) -> qnav_ctrl_step() every tick. See docs/controller-api.md.
 */
#ifndef QNAV_CTRL_H
#define QNAV_CTRL_H

#include "qnav/check.h"
#include "qnav/fixed.h"
#include "qnav/policy.h"
#include "qnav/qnav_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Results of functions that can fail. 0 is success, negatives are errors. */
typedef enum {
    QNAV_OK = 0,
    QNAV_E_NULL = -1,         /* a required pointer was null */
    QNAV_E_SECTORS = -2,      /* n_sectors outside 1..QNAV_MAX_SECTORS */
    QNAV_E_RANGE = -3,        /* max_range_mm is 0, or range_min_mm not below it */
    QNAV_E_SPEED = -4,        /* full_speed_quality outside (0, 1), quality_full_speed < 0 */
    QNAV_E_POLICY_KIND = -5,  /* policy kind unknown */
    QNAV_E_HIDDEN = -6,       /* hidden units outside 1..QNAV_MAX_HIDDEN */
    QNAV_E_PROB_PARAM = -7,   /* a probabilistic parameter outside (0, 64] */
    QNAV_E_RANK = -8,         /* rank is not a qnav_rank_t */
    QNAV_E_INPUTS = -9,       /* network inputs neither 2 nor 3 */
    QNAV_E_NO_TABLE = -10,    /* this policy cannot be compiled into a 2-D table (3 inputs) */
    QNAV_E_VFH_PARAM = -11,   /* a VFH+ parameter out of range (qnav/vfh.h) */
    QNAV_E_NAME = -12,        /* no controller of that name (qnav/nav.h) */
    QNAV_E_WEDGE = -13,       /* wedge_pct above 100 */
    QNAV_E_KIND_DISABLED = -14, /* a policy kind, table mode or controller left out of
                                  this build (a QNAV_WITH_* switch at 0, qnav/qnav_config.h) */
    QNAV_E_KEEP = -15,        /* keep_pct above 100 */
    QNAV_E_MAP = -16          /* a map's configuration, size or memory out of range
                                 (qnav/map.h) */
} qnav_status_t;

/*
 * The previous tick's heading seen in this tick's robot frame: the last decision turned back
 * by the robot's own turn since, read from its heading (odometry's: any fixed frame), as the
 * simulator gives it from its heading. last_heading_deg: the previous output's heading;
 * last_yaw_cdeg, yaw_cdeg: the robot's heading then and now, 0.01 deg, counter-clockwise.
 * Board, bridge and replay compute it alike, so a replayed log decides as the board did;
 * it does not depend on the goal bearing, which a map moves to its sub-goal.
 */
qnav_cdeg_t qnav_ctrl_prev_heading(qnav_deg_t last_heading_deg, qnav_cdeg_t last_yaw_cdeg,
                                   qnav_cdeg_t yaw_cdeg);

/* One line of text for a status ("ok", "n_sectors outside 1..360", ...); never null. */
const char *qnav_status_str(qnav_status_t status);

/* What the step maximises over the paths (docs/architecture.md, "Argmax"). */
typedef enum {
    QNAV_RANK_QUALITY = 0,  /* the Q1.15 quality (the paper read literally; saturated
                               networks then tie on many paths) */
    QNAV_RANK_PREACT = 1    /* network: the output unit's pre-activation (default); the
                               probabilistic policy always ranks by its quality */
} qnav_rank_t;

/* A rank key: larger is better. QNAV_RANK_QUALITY: the quality, Q1.15. QNAV_RANK_PREACT:
 * the output pre-activation z companded into 16 bits: Q5.11 (z * 2048) for |z| < 8, then
 * 1/128 per step up to |z| = 136 (docs/qformats.md). -32768 is never a key. */
typedef int16_t qnav_qkey_t;

/* Output flags: the step never fails; it reports what it had to do here. */
#define QNAV_FLAG_RANGE_CLIPPED 0x01u  /* a range exceeded max_range_mm and was clipped */
#define QNAV_FLAG_NOT_READY 0x02u      /* controller not initialised or input null: stop */
#define QNAV_FLAG_NO_PATH 0x04u        /* every path has quality 0: stop */
#define QNAV_FLAG_FULL_SPEED 0x08u     /* quality at or above full_speed_quality: speed capped */
#define QNAV_FLAG_SPEED_GUARD 0x10u    /* speed lowered to what the path's clearance stops in */

/* Runtime configuration. Obtain with qnav_ctrl_config_default(), then edit. */
typedef struct {
    uint16_t n_sectors;               /* sonar sectors N, 1..360, evenly spaced, sector 0
                                         centred straight ahead, counter-clockwise */
    qnav_mm_t max_range_mm;           /* sonar maximum range, mm, 1..65535 */
    qnav_q1_15_t full_speed_quality;  /* quality giving full speed (F is linear through 0),
                                         Q1.15 in (0, 1); default 0.9 */
    qnav_mm_t body_radius_mm;         /* robot radius r (centre to the farthest point of the
                                         body), mm; with pass_mm the obstacle enlargement
                                         asin((r + pass_mm) / D); both 0: the paper's
                                         per-sector mapping. Default 120 (TekBot class) */
    qnav_mm_t safety_mm;              /* safety distance d_s the robot keeps, added to r, mm:
                                         the speed guard stops d_s short of an obstacle, the
                                         escape's and the map's distances keep it; default 50 */
    qnav_mm_t pass_mm;                /* passing distance added to r in the enlargement, mm:
                                         a path passes a reading's placed arc by at least r +
                                         pass_mm. Below safety_mm a robot passes narrower gaps
                                         and still brakes d_s short (docs/architecture.md,
                                         "Passing distance"); default 50 */
    qnav_mm_t sensor_offset_mm;       /* robot centre to where ranges are measured from, mm
                                         (transducers on the body's rim: r); D = range +
                                         offset. Default 120 */
    uint16_t v_max_mm_s;              /* speed 1.0 in mm/s, for the speed guard; default 500 */
    uint16_t decel_mm_s2;             /* braking deceleration, mm/s^2; the speed guard keeps
                                         v T + v^2 / (2 a) within the chosen path's clearance
                                         (T one 0.1 s tick); 0 turns the guard off. Default 2000 */
    uint8_t rank;                     /* a qnav_rank_t; default QNAV_RANK_PREACT */
    uint8_t wedge_pct;                /* where a sector's reading is placed before the
                                         enlargement: the central wedge_pct % of its 360/N
                                         wedge, 0..100 (100: the whole wedge, the most
                                         cautious; 0: the middle path). Per robot and
                                         sensor (docs/architecture.md, "Wedge placement").
                                         With the speed guard on, the edge a placement
                                         leaves unpainted is at most the enlargement at
                                         the distance the robot needs to brake from v_max
                                         (r + d_s + 2 v T + v^2 / (2 a)); default 100 */
    qnav_mm_t wedge_near_mm;          /* readings nearer than this block their whole wedge
                                         whatever wedge_pct says, mm; default 0 */
    uint8_t escape_stall_ticks;       /* ticks without progress toward the destination
                                         (half of body_radius_mm + safety_mm) before the
                                         robot follows the boundary in front of it; 0: no
                                         escape (docs/architecture.md, "Leaving dead
                                         ends"). Default 20 (2 s) */
    qnav_mm_t escape_follow_mm;       /* while following, a path with less clearance than
                                         this counts as blocked, mm; default 500 */
    uint8_t escape_follow_s;          /* longest first follow of one side before trying
                                         the other, s (each later try twice as long, at
                                         most 109 s); default 20 */
    uint8_t keep_pct;                 /* holding the heading: the previous tick's heading
                                         (prev_heading_cdeg) is kept, while going to the
                                         destination (not while the escape follows a
                                         boundary), as long as its key is near the
                                         best path's, so two nearly equal ways round
                                         an obstacle do not alternate tick by tick
                                         (docs/architecture.md, "Holding the heading"):
                                         quality keys (QNAV_RANK_QUALITY: the
                                         probabilistic policy, its tables) at least
                                         (100 - keep_pct) % of the best's quality;
                                         pre-activation keys (QNAV_RANK_PREACT: a
                                         2-input network, its tables) at most keep_pct
                                         hundredths of z below the best's, z above 0.
                                         Not for 3-input networks. 0..100, default 0
                                         (off) */
    qnav_mm_t range_min_mm;           /* sonar minimum range, mm, below max_range_mm: the
                                         sonar reads this for anything this near or nearer,
                                         so the speed guard takes a distance level that
                                         holds it as an obstacle at the transducers (no
                                         room to stop: cap 0 whenever sensor_offset_mm <=
                                         body_radius_mm + safety_mm), and the painter
                                         enlarges a reading at it by at least
                                         asin(r / (r + d_s)): the paths that would touch an
                                         obstacle at the safety distance. Default 0 (none) */
    qnav_q1_15_t quality_full_speed;  /* the quality giving full speed when keys rank by
                                         quality (QNAV_RANK_QUALITY: the probabilistic
                                         policy always, its tables), Q1.15 in (0, 1); 0:
                                         full_speed_quality, as for every other rank. A
                                         product of probabilities sits lower than a
                                         network's saturating output (docs/architecture.md,
                                         "The speed at full quality"). Default 0 */
} qnav_ctrl_config_t;

/* The escape memory: what the robot remembers between ticks to leave dead ends
 * (docs/architecture.md, "Leaving dead ends"). The caller keeps it: each tick's input
 * carries the previous output's, all zero at the start of an episode. */
typedef struct {
    uint16_t best_mm;   /* nearest the robot came to the destination while going to it, mm;
                           0: not yet */
    uint16_t hit_mm;    /* following: how near the destination the clear way toward it
                           ended when this follow began (best_mm less the sonar's clear
                           distance that way), mm; going: the range where the last follow
                           ended, mm */
    uint16_t ticks;     /* going: ticks without progress; following: ticks on this side */
    int8_t side;        /* 0: going to the destination; +1: following a boundary on the
                           right (going round it counter-clockwise); -1: on the left */
    int8_t last_side;   /* the side of the last follow (a new stall near where it ended
                           follows it again, so the robot does not shuttle between two
                           sides; one 4 (r + d_s) nearer chooses afresh); 0: none yet */
    uint8_t tries;      /* follows given up for the other side since the last progress */
    uint8_t stood;      /* ticks the decision stood still (speed 0), to 255, halved by a
                           decision that moves; kept when a map's plan clears the rest (a
                           new plan does not move the robot: docs/architecture.md, "A robot
                           that stands") */
    uint16_t stall_mm;  /* nearest the robot had come to the destination when the last
                           follow began, mm (a new stall no nearer means that follow led
                           back: the other side); 0: none yet */
    uint16_t near_mm;   /* following: nearest the robot came to the destination on this
                           side, mm */
    uint16_t loop_mm;   /* following: the destination's range at the loop mark (taken
                           escape_stall_ticks into the follow), mm */
    uint8_t loop_deg2;  /* following: the destination's bearing at the mark, 2 deg units */
    uint8_t loop;       /* following: QNAV_ESCAPE_LOOP_* (a follow back at its mark has
                           gone round its obstacle) */
    uint16_t from_mm;   /* following: the destination's range when this side began, moved
                           by every change while the side away from the boundary was
                           closed, mm */
    uint16_t over_mm;   /* following, past this side's time: nearest the robot has come to
                           the destination since its last progress, mm; 0: not past it */
    uint16_t prev_mm;   /* following: the destination's range at the previous tick, mm */
} qnav_escape_t;

/* The destination's distance is now measured d_mm longer where the robot is (a map's new,
 * longer plan: qnav/map.h): every distance the memory holds grows by d_mm, so that a stall
 * is no progress along the new measure, not along the old one; 0 stays "none yet". */
void qnav_escape_grow(qnav_escape_t *e, uint16_t d_mm);

/* What a map's plan did to the escape memory this tick (qnav/map.h: the flags
 * QNAV_MAP_ESCAPE_CLEARED and QNAV_MAP_ESCAPE_GROWN, qnav_map_grown_mm), applied by the map
 * itself or by a caller that carries the memory apart from the map's input (the step API,
 * navbridge offboard): cleared when clear is non-zero, otherwise grown by grow_mm. */
void qnav_escape_follow_plan(qnav_escape_t *e, int clear, uint16_t grow_mm);

/* qnav_escape_t.loop: no mark yet; marked; left the mark; back at it (round once). */
#define QNAV_ESCAPE_LOOP_NONE 0u
#define QNAV_ESCAPE_LOOP_MARKED 1u
#define QNAV_ESCAPE_LOOP_AWAY 2u
#define QNAV_ESCAPE_LOOP_ROUND 3u

/* One control tick's input. */
typedef struct {
    const qnav_mm_t *ranges_mm;       /* n_sectors ranges, mm; above max_range_mm clipped */
    qnav_cdeg_t goal_bearing_cdeg;    /* destination bearing in the robot frame, 0.01 deg,
                                         counter-clockwise positive; any value (wrapped) */
    qnav_cdeg_t prev_heading_cdeg;    /* the heading chosen at the previous tick, seen in
                                         this tick's robot frame (the previous output's
                                         heading minus the turn made since), 0.01 deg; 0
                                         on the first tick. Read by 3-input networks and
                                         VFH+; the step itself keeps no memory */
    qnav_mm_t goal_range_mm;          /* distance to the destination, mm (65535 and
                                         beyond: 65535); 0: unknown, no escape. The
                                         reading under the destination's bearing counts
                                         as clear when it lies beyond the destination by
                                         body radius + safety distance or more */
    qnav_escape_t escape;             /* the previous output's escape; zero at the start */
} qnav_ctrl_input_t;

/* One control tick's decision. */
typedef struct {
    qnav_deg_t heading_deg;   /* chosen path alpha, robot frame, degrees, -179..180 */
    qnav_q1_15_t speed;       /* F(X(alpha)): fraction of maximum speed, Q1.15, [0, 1) */
    qnav_q1_15_t quality;     /* X(alpha), Q1.15, [0, 1) */
    uint8_t flags;            /* QNAV_FLAG_* */
    qnav_escape_t escape;     /* to pass in with the next tick's input */
} qnav_ctrl_output_t;

/*
 * What a caller carries from one tick's decision to the next (the step keeps nothing): the
 * escape memory of the destination it belongs to and the last decision, from which the
 * previous heading is seen. The board core and navbridge (live and --replay) carry it
 * alike, so an offboard robot leaves dead ends as an onboard one does. Zero (or
 * qnav_ctrl_carry_reset) at the start.
 */
typedef struct {
    qnav_escape_t escape;        /* the last output's escape memory */
    uint16_t goal_id;            /* the destination it belongs to (0: none) */
    qnav_deg_t last_heading_deg; /* the last decision's heading, robot frame then, degrees */
    qnav_cdeg_t last_yaw_cdeg;   /* the robot's heading when it was made, 0.01 deg */
    qnav_cdeg_t yaw_cdeg;        /* the robot's heading this tick (qnav_ctrl_carry_input's) */
    uint8_t have_last;           /* a decision was made since the reset */
} qnav_ctrl_carry_t;

/* Forget everything (a new controller, or the start). */
void qnav_ctrl_carry_reset(qnav_ctrl_carry_t *c);

/*
 * Fill in's prev_heading_cdeg, goal_range_mm and escape for a tick toward destination
 * goal_id (a new id clears the escape memory) range_mm away (0: a bearing-only goal or no
 * distance known: no escape; beyond 65535 saturates), the robot heading yaw_cdeg (its
 * odometry's, 0.01 deg; kept for qnav_ctrl_carry_output).
 */
void qnav_ctrl_carry_input(qnav_ctrl_carry_t *c, uint16_t goal_id, uint32_t range_mm,
                           qnav_cdeg_t yaw_cdeg, qnav_ctrl_input_t *in);

/* Keep what the next tick needs from this tick's output and the heading its input was
 * given (a not-ready output leaves the last decision as it was). */
void qnav_ctrl_carry_output(qnav_ctrl_carry_t *c, const qnav_ctrl_output_t *out);

/* Derived, per-hidden-unit network parameters (docs/qformats.md, "network step"). */
typedef struct {
    int32_t bias_z;    /* hidden bias, units of 2^-19 */
    int32_t per_deg;   /* weight per degree of dtheta, units of 2^-19 */
    int32_t per_level; /* weight per distance level, units of 2^-19 */
    int16_t out;       /* output weight, Q8.8 */
} qnav_ctrl_unit_t;

/* What clearance.c derives from a configuration: how ranges become per-path distance
 * levels, the enlargement and the speed guard. Shared by every controller that looks at
 * paths (the path-quality controller, VFH+). Private: reach it through functions. */
typedef struct {
    uint16_t n_sectors;
    qnav_mm_t max_range_mm;
    uint16_t level_scale;             /* distance level = (range * S + 2^15) >> 16, S =
                                         level_scale + 2^16 level_scale_hi */
    uint16_t sector_paths;            /* 360 / N: paths in a sector, or one more */
    uint16_t sector_rem;              /* 360 - sector_paths * N */
    uint8_t enlarge_deg[QNAV_DIST_LEVELS];      /* obstacle enlargement gamma by level, deg */
    uint8_t first_sector_paths;       /* paths 0.. that lie in sector 0: ceil(180 / N) */
    uint8_t wedge_shrink;             /* paths a reading leaves free at each sector edge */
    uint8_t wedge_near_level;         /* readings below this level block their whole wedge */
    uint8_t level_scale_hi;           /* 0 unless max_range_mm < QNAV_DIST_LEVELS */
    uint8_t guard_from_level;         /* speed guard: levels below cap the speed at 0 */
    uint8_t guard_full_level;         /* speed guard: levels from here on leave it uncapped */
    uint8_t guard_min_level;          /* speed guard: levels up to this one hold the sonar's
                                         minimum range and are taken as range 0 */
    uint8_t dead_zone_deg;            /* least enlargement of a reading at the sonar's
                                         minimum range: asin(r / (r + d_s)); 0 with none */
    uint8_t esc_stall_ticks;          /* escape: ticks without progress; 0: off */
    uint8_t esc_free_level;           /* escape: lowest level of a free path */
    uint16_t esc_follow_ticks;        /* escape: first follow's length, ticks */
    uint16_t margin_mm;               /* body radius + safety distance (speed guard, escape) */
    uint16_t pass_margin_mm;          /* body radius + passing distance (enlargement) */
    qnav_mm_t sensor_offset_mm;
    qnav_mm_t range_min_mm;           /* the sonar's minimum range: it reads this for anything
                                         nearer */
    uint16_t v_max_mm_s;
    uint16_t decel_mm_s2;
} qnav_clearance_t;

/* What init learns of one row of keys (a distance level, dtheta 0..180), so that the step
 * can find a run's best path without evaluating it (docs/architecture.md, "Row shapes"). */
typedef struct {
    qnav_qkey_t top;   /* the row's largest key */
    uint8_t top_d;     /* the smallest dtheta with that key */
    uint8_t fall_d;    /* the smallest dtheta from which the key never rises again */
    uint8_t peak_lo;   /* the row's one interior peak: keys rise into peak_lo, stay equal */
    uint8_t peak_hi;   /* to peak_hi and fall after it; peak_lo 255: no interior peak,
                          254: more than one */
} qnav_row_shape_t;

/* The controller. Caller-owned (a static on an MCU, a vector element on a host); fields
 * are private: reach them through the functions below. */
typedef struct {
    uint16_t magic;                   /* set by a successful init */
    uint8_t kind;                     /* the policy's qnav_policy_kind_t; table mode: 0 (the
                                         kind that built the table is not known) */
    uint8_t hidden;
    uint8_t inputs;                   /* network inputs, 2 or 3 */
    uint8_t rank;                     /* qnav_rank_t of the keys (table: as given at init) */
    uint8_t keep_pct;                 /* qnav_ctrl_config_t.keep_pct */
    uint8_t shapes_carried;           /* 1: init took carried row shapes (not evaluated) */
    qnav_clearance_t clr;             /* levels, enlargement, speed guard */
    uint32_t speed_scale;             /* speed = min(MAX, (quality * scale) >> 15) */
    qnav_q1_15_t full_speed_quality;
    /* One kind's data. On the ATmega128 (16 hidden units) the probabilistic tables are
     * the largest member, so what only networks and table mode use is kept in theirs. */
    union {
        struct {
            qnav_q1_15_t goal[QNAV_DTHETA_MAX + 1]; /* P_goal by dtheta */
            qnav_q1_15_t safe[QNAV_DIST_LEVELS];    /* P_safe by distance level */
        } prob;
        struct {
            const qnav_qkey_t *table;               /* table mode: [QNAV_DIST_LEVELS][181]
                                                       rank keys (kind 0) */
            int32_t out_bias_z;                     /* network output bias, units of 2^-15 */
            qnav_ctrl_unit_t unit[QNAV_MAX_HIDDEN]; /* network */
            union {
                qnav_row_shape_t row[QNAV_DIST_LEVELS]; /* 2 inputs, and table mode */
                int32_t per_prev[QNAV_MAX_HIDDEN];      /* 3 inputs: weight per degree of
                                                           dprev, units of 2^-19 */
            } in;
        } net;
    } p;
#if QNAV_BENCH_COUNT
    uint32_t *bench_evals;            /* hidden-unit evaluations are added here (null: not
                                         counted); qnav_ctrl_count_evals */
#endif
} qnav_ctrl_t;

/*
 * The most hidden-unit evaluations one qnav_ctrl_step() of a network policy with h hidden
 * units makes, whatever its weights and the scan: every path once, at most a sixteenth more
 * for the 2-input run search's bounds (QNAV_NET_SEARCH_SLACK), and the held heading's path
 * (docs/architecture.md, "The run search"; cycles in docs/performance.md). The bench's
 * counted build checks every step of the fixtures and the adversarial set against it. A
 * sixteenth (383 h in all) keeps an ATmega128 step of up to 16 units within its 100 ms
 * tick at the highest cost per evaluation measured; an eighth did not.
 */
#define QNAV_NET_SEARCH_SLACK 16u
#define QNAV_NET_STEP_EVALS_MAX(h)                                                         \
    ((uint32_t)(QNAV_PATHS + QNAV_PATHS / QNAV_NET_SEARCH_SLACK + 1u) * (uint32_t)(h))

#if QNAV_BENCH_COUNT
/* Benchmarks only (QNAV_BENCH_COUNT = 1): from now on each hidden-unit evaluation of this
 * network controller (H per path evaluated) adds 1 to *evals; null stops counting. Call it
 * after init, which forgets the counter. The counter is the caller's: libqnav keeps no
 * state of its own. */
static inline void qnav_ctrl_count_evals(qnav_ctrl_t *ctrl, uint32_t *evals)
{
    ctrl->bench_evals = evals;
}
#endif

/* Number of entries of a quality table: QNAV_DIST_LEVELS * 181, row-major by level. */
#define QNAV_QTABLE_ENTRIES ((uint16_t)(QNAV_DIST_LEVELS * (QNAV_DTHETA_MAX + 1)))

/* Defaults: 16 sectors, 5000 mm, full speed at quality 0.9, a TekBot-class body (radius
 * 120 mm with the sonar on its rim, safety 50 mm, 500 mm/s, braking 2000 mm/s^2), rank by
 * pre-activation. */
void qnav_ctrl_config_default(qnav_ctrl_config_t *cfg);

/* The paper read literally, kept as an ablation: every path sees only its own sector
 * (zero radius and safety distance), no speed guard, rank by quality. Other fields are
 * left as they are. */
void qnav_ctrl_config_literal(qnav_ctrl_config_t *cfg);

/*
 * Check cfg and policy and derive the step's parameters into ctrl.
 * Returns QNAV_OK, or QNAV_E_NULL, QNAV_E_SECTORS, QNAV_E_RANGE, QNAV_E_SPEED, QNAV_E_RANK,
 * QNAV_E_POLICY_KIND, QNAV_E_HIDDEN, QNAV_E_INPUTS, QNAV_E_PROB_PARAM (the policy is
 * checked by qnav_policy_validate()), QNAV_E_KIND_DISABLED (its kind is left out of this
 * build); on error ctrl is left not ready
 * (a step then commands a stop). The policy is not referenced after init returns.
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_init(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                             const qnav_policy_t *policy);

/*
 * Table mode: like qnav_ctrl_init() but the step reads rank keys from a compiled table of
 * QNAV_QTABLE_ENTRIES entries (made by qnav_ctrl_build_table() or the policy-to-header
 * tool) and does no multiplies per path. rank says what the keys are (qnav_ctrl_rank() of
 * the controller that built it); cfg->rank is not used. With QNAV_TABLES_IN_FLASH the table
 * must be in program memory. The table must outlive ctrl. Same statuses as
 * qnav_ctrl_init(); QNAV_E_KIND_DISABLED without table mode (QNAV_WITH_TABLE 0).
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_init_table(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                   const qnav_qkey_t *table, qnav_rank_t rank);

/*
 * qnav_ctrl_init(), qnav_ctrl_build_table() into table, then qnav_ctrl_init_table() from
 * it, in one call that evaluates the policy at each (level, dtheta) once: the rows go
 * straight into the table and the row shapes are read from there (qnav_ctrl_init alone
 * evaluates every row for the shapes, and building the table again). For a host that
 * compiles many policies (simevo: one per candidate). table: QNAV_QTABLE_ENTRIES keys,
 * outliving ctrl. Statuses as those three; QNAV_E_NO_TABLE for a 3-input network. On any
 * error ctrl is left not ready.
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_init_compiled(qnav_ctrl_t *ctrl,
                                                        const qnav_ctrl_config_t *cfg,
                                                        const qnav_policy_t *policy,
                                                        qnav_qkey_t *table);

/*
 * Carried row shapes (docs/architecture.md, "Carried row shapes"): the row shapes a
 * 2-input network's init would compute, made where the policy is made (a host) and
 * carried with it, so that a small board's init copies them instead of evaluating every
 * row (ATmega128, H = 16: about 1 s). QNAV_SHAPES_BYTES bytes, little endian:
 *   [0] QNAV_SHAPES_FORMAT  [1] the qnav_rank_t of the keys
 *   [2 + 6 l ..] row l = 0..QNAV_DIST_LEVELS-1: top i16, top_d, fall_d, peak_lo, peak_hi
 *   [last 4] check u32: CRC-32 (IEEE, reflected) over the network (H, then every weight in
 *            qnav_net_weight() order, i16 LE) followed by the bytes above
 */
#define QNAV_SHAPES_FORMAT 1u
#define QNAV_SHAPES_BYTES ((uint16_t)(2u + 6u * QNAV_DIST_LEVELS + 4u))

/*
 * Write the row shapes of ctrl, initialised from policy (a 2-input network), into out
 * (QNAV_SHAPES_BYTES, caller's buffer) for qnav_ctrl_init_carried() on a board. Returns
 * QNAV_OK, QNAV_E_NULL, or QNAV_E_NO_TABLE when ctrl is not ready or policy is not a
 * 2-input network with ctrl's hidden-unit count.
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_shapes_save(const qnav_ctrl_t *ctrl,
                                                      const qnav_policy_t *policy,
                                                      uint8_t *out);

/*
 * qnav_ctrl_init() that takes a 2-input network's row shapes from shapes (len bytes,
 * written by qnav_ctrl_shapes_save) instead of evaluating every row, when they are this
 * policy's: the right length and format, the controller's rank, a check that matches the
 * policy's weights, every field in range, and each row's top equal to the key the network
 * gives at top_d. Otherwise (null, or any of that fails, or a 3-input network or
 * probabilistic policy) it computes them as qnav_ctrl_init() does: the same statuses, and
 * the same controller and decisions either way (qnav_ctrl_shapes_carried says which).
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_init_carried(qnav_ctrl_t *ctrl,
                                                       const qnav_ctrl_config_t *cfg,
                                                       const qnav_policy_t *policy,
                                                       const uint8_t *shapes, uint16_t len);

/* 1 when the last successful init took carried row shapes, else 0. */
uint8_t qnav_ctrl_shapes_carried(const qnav_ctrl_t *ctrl);

/* The qnav_rank_t of an initialised controller's keys (QNAV_RANK_QUALITY when not ready). */
qnav_rank_t qnav_ctrl_rank(const qnav_ctrl_t *ctrl);

/*
 * One control tick. Never fails: a range above max_range_mm is clipped and flagged; an
 * uninitialised controller or null input gives a stop (speed 0, heading 0) and
 * QNAV_FLAG_NOT_READY. qualities, when not null, receives X(theta_i) for i = 0..359
 * (path i points i degrees counter-clockwise of straight ahead).
 * The chosen path has the largest rank key; ties go to the smaller dtheta, then the smaller
 * turn, then counter-clockwise. The speed is F(quality), then at most the speed guard's
 * cap for the path's level (QNAV_FLAG_SPEED_GUARD when it lowered it).
 */
void qnav_ctrl_step(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, qnav_q1_15_t *qualities);

/*
 * The plain reference step: the same output as qnav_ctrl_step() (heading, speed, quality,
 * flags, escape memory, qualities) for every input, bit for bit, by the obvious route:
 * every path's key from its own inputs (level, dtheta, and dprev for a 3-input network),
 * the best under the same total order, then the same command. No runs, row shapes or
 * search: 360 policy evaluations a tick, so it is the reference the fast step is tested
 * against and the place a reader starts, not what a robot runs. It lives in its own object
 * (src/ctrl_plain.c): a firmware that does not call it does not link it.
 */
void qnav_ctrl_step_plain(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                          qnav_ctrl_output_t *out, qnav_q1_15_t *qualities);

/*
 * The rank key the policy gives one (distance level, dtheta) pair: the single function
 * that both the network/probabilistic step and every compiled table evaluate (a 3-input
 * network: with the path on the previous heading, dprev = 0).
 * level is clamped to 0..QNAV_DIST_LEVELS-1, dtheta_deg to 0..180. -32767 if not ready.
 */
qnav_qkey_t qnav_ctrl_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg);

/* The quality X of one (distance level, dtheta) pair: the sigmoid of the key's
 * pre-activation, or the key itself when it is a quality. 0 if not ready. */
qnav_q1_15_t qnav_ctrl_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg);

/* The quality that a key of this controller stands for (see qnav_ctrl_quality). */
qnav_q1_15_t qnav_ctrl_key_quality(const qnav_ctrl_t *ctrl, qnav_qkey_t key);

/*
 * Compile the controller's policy into a key table of QNAV_QTABLE_ENTRIES entries
 * (caller's buffer, in RAM), for qnav_ctrl_init_table(..., qnav_ctrl_rank(ctrl)).
 * Returns QNAV_OK, QNAV_E_NULL, QNAV_E_POLICY_KIND when ctrl is not initialised with a
 * policy, QNAV_E_NO_TABLE for a 3-input network (its key depends on dprev too: a 3-D
 * table of 32 x 181 x 181 keys, 371 KB, does not fit a small board), or
 * QNAV_E_KIND_DISABLED without table mode (QNAV_WITH_TABLE 0).
 */
QNAV_CHECK_RESULT qnav_status_t qnav_ctrl_build_table(const qnav_ctrl_t *ctrl, qnav_qkey_t *table);

/* The distance level a range maps to under this controller (clipped to max range). */
uint8_t qnav_ctrl_level(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm);

/* The sector (0..n_sectors-1) that contains path i (0..359). */
uint16_t qnav_ctrl_sector_of_path(uint16_t n_sectors, uint16_t path_deg);

/*
 * The distance level each path sees under this controller's enlargement (lvl[i] for path
 * i, i = 0..359; caller's buffer): the nearest reading whose enlarged arc covers the path.
 * Returns the step's QNAV_FLAG_RANGE_CLIPPED, or QNAV_FLAG_NOT_READY (lvl untouched).
 */
uint8_t qnav_ctrl_path_levels(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges_mm,
                              uint8_t *lvl);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_CTRL_H */
