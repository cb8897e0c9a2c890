/*
 * VFH+ (Ulrich & Borenstein, "VFH+: Reliable obstacle avoidance for fast mobile robots",
 * ICRA 1998), the standard reactive baseline (Player's vfh driver, PX4's local planner
 * family), as a sibling of the path-quality controller: the same qnav_ctrl_input_t and
 * qnav_ctrl_output_t, its own config -> init -> step, and a caller-owned state struct for
 * what VFH+ keeps between ticks (the binary histogram's hysteresis). From the N sector
 * readings it builds the polar obstacle density per 1-degree path with the readings
 * enlarged by robot radius + safety distance (clearance.c, shared with the path-quality
 * controller), reduces it to K sectors of alpha degrees, thresholds it with two levels
 * into a binary histogram, finds the gaps, takes candidate directions from them
 * (a narrow gap's middle; a wide gap's two sides and the goal when it lies
 * inside) and picks the one of least cost mu_goal * |c - goal| + mu_current * |c| +
 * mu_prev * |c - previous heading|; the speed falls with the chosen direction's density
 * and is capped by the speed guard. Fixed point, no heap, no file-scope state.
 * Parameters and their sources: docs/architecture.md, "VFH+".
 */
#ifndef QNAV_VFH_H
#define QNAV_VFH_H

#include "qnav/check.h"
#include "qnav/ctrl.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Default tau_high in tenths of the body's enlargement (radius + safety distance): 2.5 of
 * them, 0.43 m for the TekBot and 0.70 m for the Pioneer 3-DX (until 0.13.1 1.0 m for
 * every robot, an assumption: docs/architecture.md, "VFH+"). */
#define QNAV_VFH_BLOCKED_BODIES 25u

/* Largest number of histogram sectors (alpha = 1 degree). */
#define QNAV_VFH_MAX_SECTORS 360u

/* Runtime configuration. Obtain with qnav_vfh_config_default(), then edit. */
typedef struct {
    qnav_ctrl_config_t body;  /* sensors, body radius, safety distance, sensor offset, speed
                                 guard: the same fields and defaults as the path-quality
                                 controller (full_speed_quality and rank are not used) */
    uint8_t sector_deg;       /* histogram sector width alpha, degrees, divides 360, 1..30;
                                 default 5 (VFH+ paper) */
    qnav_mm_t blocked_mm;     /* tau_high: a sector whose nearest enlarged reading is nearer
                                 than this is blocked, mm; default 0: scaled with the body,
                                 QNAV_VFH_BLOCKED_BODIES tenths of body_radius_mm +
                                 safety_mm (at least 100 mm; measured: docs/architecture.md,
                                 "VFH+") */
    qnav_mm_t clear_mm;       /* tau_low: a sector is free again only beyond this, mm;
                                 >= blocked_mm; in between it keeps last tick's value.
                                 Default 0: 1.4 times blocked_mm */
    uint8_t wide_sectors;     /* s_max: a gap of more sectors is wide, 1..180;
                                 default 16 (VFH+ paper: 16 sectors of 5 deg) */
    uint8_t mu_goal;          /* cost weight of the angle to the goal; default 5 (VFH+ paper,
                                 mu1 > mu2 + mu3 for a goal-oriented robot) */
    uint8_t mu_current;       /* cost weight of the turn from the current heading; default 2 */
    uint8_t mu_prev;          /* cost weight of the angle to the previous tick's heading;
                                 default 2 */
    qnav_mm_t slow_mm;        /* full speed when the chosen direction is clear this far,
                                 linearly less nearer (VFH's V = Vmax (1 - h_c / h_m));
                                 default 0: twice blocked_mm */
} qnav_vfh_config_t;

/* Derived parameters. Caller-owned, private fields; only read by the step. */
typedef struct {
    uint16_t magic;
    qnav_clearance_t clr;
    uint8_t sector_deg;
    uint16_t n_hist;          /* K = 360 / alpha */
    uint8_t level_blocked;    /* a sector below this distance level is blocked */
    uint8_t level_clear;      /* at or above this level it is free */
    uint8_t level_slow;       /* level at and above which the speed is full */
    uint8_t wide_sectors;
    uint8_t mu_goal;
    uint8_t mu_current;
    uint8_t mu_prev;
} qnav_vfh_t;

/* What VFH+ keeps between ticks: the binary histogram (hysteresis). Caller-owned; clear
 * it with qnav_vfh_state_reset() at the start of an episode. */
typedef struct {
    uint8_t blocked[(QNAV_VFH_MAX_SECTORS + 7u) / 8u]; /* bit k: sector k blocked */
} qnav_vfh_state_t;

/* Defaults: qnav_ctrl_config_default() for the body, and the values above. */
void qnav_vfh_config_default(qnav_vfh_config_t *cfg);

/* Check cfg and derive the step's parameters. Returns QNAV_OK, QNAV_E_NULL,
 * QNAV_E_SECTORS, QNAV_E_RANGE or QNAV_E_VFH_PARAM (sector_deg, thresholds, s_max). */
QNAV_CHECK_RESULT qnav_status_t qnav_vfh_init(qnav_vfh_t *vfh, const qnav_vfh_config_t *cfg);

/* Every sector free (the state before the first tick). */
void qnav_vfh_state_reset(qnav_vfh_state_t *state);

/*
 * One control tick. Never fails: an uninitialised vfh or null input or state gives a
 * stop and QNAV_FLAG_NOT_READY; every sector blocked gives a stop and QNAV_FLAG_NO_PATH.
 * Reads in->prev_heading_cdeg for the previous-direction cost. out->quality is the speed
 * before the speed guard (VFH+ has no path quality). Ties in cost go to the smaller turn,
 * then counter-clockwise. Updates state.
 * @par Cost: the clearance levels (as the path-quality controller), 360 byte reads for the
 * histogram, and a few operations per gap.
 */
void qnav_vfh_step(const qnav_vfh_t *vfh, qnav_vfh_state_t *state, const qnav_ctrl_input_t *in,
                   qnav_ctrl_output_t *out);

#ifdef __cplusplus
}
#endif

#endif /* QNAV_VFH_H */
