/*
 * The floor every private source of libqnav stands on: the controller's magic, keys and
 * their pre-activation companding, the paths' angles (whole degrees, signed headings,
 * angular distance), the best-path record and its total order, and what ctrl.c lends
 * its plain sibling (ctrl_plain.c). Above it: the run machinery (runs.h), then the
 * policy kinds' evaluation (policy_eval.h), then the step (ctrl.c). Nothing here calls
 * upward (docs/architecture.md, "The step in rooms").
 */
#ifndef QNAV_CTRL_INTERNAL_H
#define QNAV_CTRL_INTERNAL_H

#include "qnav/ctrl.h"

#define QNAV_CTRL_MAGIC 0x514Eu

/* qnav_ctrl_t.kind of a controller in table mode (policy kinds start at 1). */
#define QNAV_CTRL_KIND_TABLE 0u

#define QNAV_TABLE_STRIDE (QNAV_DTHETA_MAX + 1)
/* No key: below every key a policy gives (keys are -32767..32767). */
#define QNAV_KEY_NONE (-32767 - 1)

/* The network arithmetic shifts signed values right and relies on it being arithmetic
 * (implementation-defined in C99; true on gcc, avr-gcc and arm-none-eabi-gcc). */
typedef char qnav_arith_shift_check[((-8 >> 1) == -4) ? 1 : -1];

/* Out of line on the ATmega128: inlined, a helper's registers and spills join its caller's
 * frame, which the step's deepest call path stacks on its 360-byte level array (4 KB of
 * RAM; docs/performance.md, "Issue 19: controller RAM within 1 KB"). Elsewhere the
 * compiler decides. */
#if defined(__AVR__)
#define QNAV_AVR_NOINLINE __attribute__((noinline))
#else
#define QNAV_AVR_NOINLINE
#endif

static inline int16_t qnav_sat16(int32_t v)
{
    if (v > 32767) {
        return 32767;
    }
    if (v < -32768) {
        return -32768;
    }
    return (int16_t)v;
}

/* Knee of the companded pre-activation key: |z| below 8 keeps Q5.11 resolution. */
#define QNAV_KEY_KNEE 16384

/*
 * The companded pre-activation key of acc (units of 2^-15): what a network ranks by under
 * QNAV_RANK_PREACT, and what such a network's compiled table holds.
 * @par Scaling and overflow: a = round(acc / 16) is Q5.11; |a| < 16384 (|z| < 8) is kept,
 * beyond the knee every 16 Q5.11 steps are one key step (1/128 in z), saturated to
 * +-32767, so the key is monotone in acc and -32768 stays free. |acc| < 2^27.
 */
static inline qnav_qkey_t qnav_preact_key(int32_t acc)
{
    int32_t a = (acc + 8) >> 4;
    if (a >= QNAV_KEY_KNEE) {
        a = QNAV_KEY_KNEE + ((a - QNAV_KEY_KNEE) >> 4);
        return (qnav_qkey_t)(a > 32767 ? 32767 : a);
    }
    if (a < -QNAV_KEY_KNEE) {
        a = -QNAV_KEY_KNEE + ((a + QNAV_KEY_KNEE) >> 4);
        return (qnav_qkey_t)(a < -32767 ? -32767 : a);
    }
    return (qnav_qkey_t)a;
}

/* Whether this build has pre-activation keys: networks make them, tables of networks hold
 * them. Turning one back into a quality reads the sigmoid table, so src/sigmoid_lut.c is
 * built exactly then (firmware/CMakeLists.txt says the same). */
#define QNAV_WITH_PREACT_KEYS (QNAV_WITH_NETWORK || QNAV_WITH_TABLE)

/* A pre-activation key back to the quality (ctrl.c; with QNAV_WITH_PREACT_KEYS only):
 * expand to Q5.11 (saturating at +-16) and take the sigmoid. */
qnav_q1_15_t qnav_preact_key_quality(qnav_qkey_t key);

/* The controller's compiled table, or null. The pointer shares the union with the
 * probabilistic tables, so only table mode's kind reads it. Without table mode
 * (QNAV_WITH_TABLE 0) never one, so the compiler leaves the table's paths out of the step. */
static inline const qnav_qkey_t *qnav_table_of(const qnav_ctrl_t *ctrl)
{
#if QNAV_WITH_TABLE
    return ctrl->kind == QNAV_CTRL_KIND_TABLE ? ctrl->p.net.table : 0;
#else
    (void)ctrl;
    return 0;
#endif
}

/* A path's direction (whole degrees 0..359) as a signed heading, -179..180 (180 stays
 * 180: straight behind turns counter-clockwise). */
static inline qnav_deg_t qnav_signed_deg(uint16_t deg)
{
    return (qnav_deg_t)(deg <= 180u ? (int16_t)deg : (int16_t)deg - 360);
}

/* Angular distance between two whole-degree directions 0..359, in 0..180. */
static inline uint8_t qnav_angle_dist_deg(uint16_t a, uint16_t b)
{
    uint16_t d = (uint16_t)(a >= b ? a - b : b - a);
    return (uint8_t)(d > QNAV_DTHETA_MAX ? QNAV_PATHS - d : d);
}

/* An angle in centidegrees to the nearest whole degree (halves away from zero), 0..359.
 * 16-bit arithmetic: one division, no 32-bit ones (costly on AVR). */
uint16_t qnav_whole_deg(qnav_cdeg_t cdeg); /* runs.c */

/* The best path so far under the controller's total order (key, then smaller dtheta,
 * then smaller turn, then counter-clockwise). */
typedef struct {
    qnav_qkey_t key;
    uint8_t dtheta;
    qnav_deg_t heading;
} qnav_best_t;

/* Offer path (with its key and dtheta) to best under the total order above. Inline: the
 * network calls it once per path. */
static inline void qnav_best_consider(qnav_best_t *best, qnav_qkey_t key, uint16_t path,
                                      uint8_t dtheta)
{
    qnav_deg_t heading;
    int16_t turn;
    int16_t best_turn;
    if (key < best->key) {
        return;
    }
    heading = qnav_signed_deg(path);
    if (key == best->key) {
        if (dtheta != best->dtheta) {
            if (dtheta > best->dtheta) {
                return;
            }
        } else {
            turn = (int16_t)(heading < 0 ? -heading : heading);
            best_turn = (int16_t)(best->heading < 0 ? -best->heading : best->heading);
            if (turn > best_turn || (turn == best_turn && heading < best->heading)) {
                return;
            }
        }
    }
    best->key = key;
    best->dtheta = dtheta;
    best->heading = heading;
}

/* ---- ctrl.c, for the plain step (ctrl_plain.c) ------------------------------------- */

/* The stop command with flags; qualities (may be null) all 0. */
void qnav_ctrl_stop(qnav_ctrl_output_t *out, uint8_t flags, qnav_q1_15_t *qualities);
/* The command from the best path: holding the heading (keep_pct), the speed from the
 * quality under the speed guard, and escape's keep-moving rule. lvl: the path levels;
 * goal, prev: the (escape's) goal and the previous heading, whole degrees 0..359; flags:
 * the clearance flags; out->escape already holds the memory qnav_escape_goal wrote. */
void qnav_ctrl_decide(const qnav_ctrl_t *ctrl, const uint8_t *lvl, uint16_t goal,
                      uint16_t prev, uint8_t flags, qnav_best_t *best,
                      qnav_ctrl_output_t *out);

#endif /* QNAV_CTRL_INTERNAL_H */
