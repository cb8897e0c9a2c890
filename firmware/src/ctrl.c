/*
 * The navigation controller: quantizes a scan and the destination bearing, gives each of
 * the 360 paths a quality through one policy function (network, probabilistic or compiled
 * table), picks the best path and maps its quality to a speed. Integer arithmetic only;
 * every format and bound is in docs/qformats.md.
 */
#include "qnav/ctrl.h"
#include "qnav/flash.h"
#include "sigmoid_lut.h"

#define QNAV_CTRL_MAGIC 0x514Eu
#define QNAV_TABLE_STRIDE (QNAV_DTHETA_MAX + 1)
#define QNAV_KIND_TABLE 0u

/* The network arithmetic shifts signed values right and relies on it being arithmetic
 * (implementation-defined in C99; true on gcc, avr-gcc and arm-none-eabi-gcc). */
typedef char qnav_arith_shift_check[((-8 >> 1) == -4) ? 1 : -1];

static int16_t sat16(int32_t v)
{
    if (v > 32767) {
        return 32767;
    }
    if (v < -32768) {
        return -32768;
    }
    return (int16_t)v;
}

/* Divide by a positive divisor, rounding halves away from zero. */
static int32_t div_round(int32_t num, int32_t den)
{
    return (num >= 0) ? (num + den / 2) / den : -((-num + den / 2) / den);
}

/*
 * e^-u for u in Q16.16 (u >= 0), result in units of 2^-15 in [0, 32768] (1.0 included).
 * Range reduction by ln 2, then 9 terms of the series in Q0.16; error at most 2 LSB.
 * @par Scaling and overflow: all products are r * t with r < 45426 and t <= 65536, which
 * fit uint32.
 */
static uint16_t exp_neg_q15(uint32_t u_q16)
{
    const uint32_t ln2_q16 = 45426u;
    uint32_t n = u_q16 / ln2_q16;
    uint32_t r = u_q16 - n * ln2_q16;
    uint32_t t = 65536u;
    uint32_t k;
    uint32_t v;
    if (n > 16u) {
        return 0;
    }
    for (k = 8u; k >= 1u; --k) {
        t = 65536u - ((r * t) / k >> 16);
    }
    v = (t + (1u << n)) >> (n + 1u);
    return (uint16_t)v;
}

void qnav_ctrl_config_default(qnav_ctrl_config_t *cfg)
{
    if (cfg == 0) {
        return;
    }
    cfg->n_sectors = 16u;
    cfg->max_range_mm = 5000u;
    cfg->full_speed_quality = QNAV_Q1_15(0.9);
}

static qnav_status_t init_common(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg)
{
    uint32_t q_full;
    if (ctrl == 0) {
        return QNAV_E_NULL;
    }
    ctrl->magic = 0u;
    if (cfg == 0) {
        return QNAV_E_NULL;
    }
    if (cfg->n_sectors < 1u || cfg->n_sectors > QNAV_MAX_SECTORS) {
        return QNAV_E_SECTORS;
    }
    if (cfg->max_range_mm == 0u) {
        return QNAV_E_RANGE;
    }
    if (cfg->full_speed_quality <= 0) {
        return QNAV_E_SPEED;
    }
    q_full = (uint32_t)cfg->full_speed_quality;
    ctrl->n_sectors = cfg->n_sectors;
    ctrl->max_range_mm = cfg->max_range_mm;
    ctrl->full_speed_quality = cfg->full_speed_quality;
    ctrl->level_scale = ((uint32_t)(QNAV_DIST_LEVELS - 1) * 65536u + cfg->max_range_mm / 2u) /
                        cfg->max_range_mm;
    ctrl->speed_scale = (32768u * 32768u + q_full / 2u) / q_full;
    ctrl->table = 0;
    ctrl->hidden = 0u;
    ctrl->out_bias_z = 0;
    return QNAV_OK;
}

static qnav_status_t init_prob(qnav_ctrl_t *ctrl, const qnav_prob_params_t *p)
{
    uint16_t i;
    const int16_t kmax = 64 * 256; /* 64.0 in Q8.8 */
    if (p->k_goal <= 0 || p->k_goal > kmax || p->k_safe <= 0 || p->k_safe > kmax) {
        return QNAV_E_PROB_PARAM;
    }
    for (i = 0; i <= QNAV_DTHETA_MAX; ++i) {
        uint32_t u = ((uint32_t)p->k_goal * i * 256u + QNAV_DTHETA_MAX / 2u) / QNAV_DTHETA_MAX;
        uint16_t g = exp_neg_q15(u);
        ctrl->p.prob.goal[i] = (qnav_q1_15_t)(g > 32767u ? 32767u : g);
    }
    for (i = 0; i < QNAV_DIST_LEVELS; ++i) {
        uint32_t u = ((uint32_t)p->k_safe * i * 256u + (QNAV_DIST_LEVELS - 1u) / 2u) /
                     (QNAV_DIST_LEVELS - 1u);
        ctrl->p.prob.safe[i] = (qnav_q1_15_t)(32768u - exp_neg_q15(u) > 32767u
                                                  ? 32767u : 32768u - exp_neg_q15(u));
    }
    return QNAV_OK;
}

static qnav_status_t init_net(qnav_ctrl_t *ctrl, const qnav_net_t *net)
{
    uint8_t j;
    if (net->hidden < 1u || net->hidden > QNAV_MAX_HIDDEN) {
        return QNAV_E_HIDDEN;
    }
    ctrl->hidden = net->hidden;
    for (j = 0; j < net->hidden; ++j) {
        qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        u->bias_z = (int32_t)net->b_hidden[j] * 16384;
        u->per_deg = div_round((int32_t)net->w_theta[j] * 16384, QNAV_DTHETA_MAX);
        u->per_level = div_round((int32_t)net->w_dist[j] * 16384, QNAV_DIST_LEVELS - 1);
        u->out = net->w_out[j];
    }
    ctrl->out_bias_z = (int32_t)net->b_out * 128;
    return QNAV_OK;
}

qnav_status_t qnav_ctrl_init(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                             const qnav_policy_t *policy)
{
    qnav_status_t st = init_common(ctrl, cfg);
    if (st != QNAV_OK) {
        return st;
    }
    if (policy == 0) {
        return QNAV_E_NULL;
    }
    if (policy->kind == (uint8_t)QNAV_POLICY_PROB) {
        st = init_prob(ctrl, &policy->u.prob);
    } else if (policy->kind == (uint8_t)QNAV_POLICY_NET) {
        st = init_net(ctrl, &policy->u.net);
    } else {
        st = QNAV_E_POLICY_KIND;
    }
    if (st == QNAV_OK) {
        ctrl->kind = policy->kind;
        ctrl->magic = QNAV_CTRL_MAGIC;
    }
    return st;
}

qnav_status_t qnav_ctrl_init_table(qnav_ctrl_t *ctrl, const qnav_ctrl_config_t *cfg,
                                   const qnav_q1_15_t *table)
{
    qnav_status_t st = init_common(ctrl, cfg);
    if (st != QNAV_OK) {
        return st;
    }
    if (table == 0) {
        return QNAV_E_NULL;
    }
    ctrl->table = table;
    ctrl->kind = QNAV_KIND_TABLE;
    ctrl->magic = QNAV_CTRL_MAGIC;
    return QNAV_OK;
}

/*
 * One hidden unit's share of the output pre-activation, in units of 2^-15.
 * zf is the unit's pre-activation in units of 2^-22 (|zf| < 3 * 2^29).
 * @par Scaling and overflow: (zf + 2^10) >> 11 is Q5.11, saturated to [-16, 16); out
 * (Q8.8) times h (Q1.15) is below 2^30; >> 8 leaves units of 2^-15, below 2^22 per unit,
 * so 32 units sum below 2^27.
 */
static int32_t unit_share(int32_t zf, int16_t out)
{
    int16_t h = qnav_sigmoid_q5_11(sat16((zf + 1024) >> 11));
    return ((int32_t)out * h + 128) >> 8;
}

/* Output unit: acc in units of 2^-15, rounded to Q5.11 and saturated. */
static qnav_q1_15_t net_output(int32_t acc)
{
    return qnav_sigmoid_q5_11(sat16((acc + 8) >> 4));
}

static qnav_q1_15_t prob_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    uint32_t q = (uint32_t)ctrl->p.prob.goal[dtheta] * (uint32_t)ctrl->p.prob.safe[level];
    return (qnav_q1_15_t)((q + 16384u) >> 15);
}

static qnav_q1_15_t net_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    int32_t acc = ctrl->out_bias_z;
    uint8_t j;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        int32_t zf = u->bias_z + u->per_level * level + u->per_deg * dtheta;
        acc += unit_share(zf, u->out);
    }
    return net_output(acc);
}

qnav_q1_15_t qnav_ctrl_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    if (level >= QNAV_DIST_LEVELS) {
        level = QNAV_DIST_LEVELS - 1u;
    }
    if (dtheta_deg > QNAV_DTHETA_MAX) {
        dtheta_deg = QNAV_DTHETA_MAX;
    }
    if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
        return net_quality(ctrl, level, dtheta_deg);
    }
    if (ctrl->kind == (uint8_t)QNAV_POLICY_PROB) {
        return prob_quality(ctrl, level, dtheta_deg);
    }
    return QNAV_FLASH_READ_I16(&ctrl->table[(uint16_t)level * QNAV_TABLE_STRIDE + dtheta_deg]);
}

qnav_status_t qnav_ctrl_build_table(const qnav_ctrl_t *ctrl, qnav_q1_15_t *table)
{
    uint16_t level;
    uint16_t dtheta;
    if (ctrl == 0 || table == 0) {
        return QNAV_E_NULL;
    }
    if (ctrl->magic != QNAV_CTRL_MAGIC || ctrl->kind == QNAV_KIND_TABLE) {
        return QNAV_E_POLICY_KIND;
    }
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        for (dtheta = 0; dtheta <= QNAV_DTHETA_MAX; ++dtheta) {
            table[level * QNAV_TABLE_STRIDE + dtheta] =
                qnav_ctrl_quality(ctrl, (uint8_t)level, (uint8_t)dtheta);
        }
    }
    return QNAV_OK;
}

/* Level of a range already known to be at most max_range_mm. */
static uint8_t level_of(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm)
{
    uint32_t level = ((uint32_t)range_mm * ctrl->level_scale + 32768u) >> 16;
    return (uint8_t)(level > QNAV_DIST_LEVELS - 1u ? QNAV_DIST_LEVELS - 1u : level);
}

uint8_t qnav_ctrl_level(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return level_of(ctrl, range_mm > ctrl->max_range_mm ? ctrl->max_range_mm : range_mm);
}

uint16_t qnav_ctrl_sector_of_path(uint16_t n_sectors, uint16_t path_deg)
{
    uint32_t s;
    if (n_sectors == 0u) {
        return 0;
    }
    s = ((uint32_t)(path_deg % QNAV_PATHS) * n_sectors + QNAV_PATHS / 2u) / QNAV_PATHS;
    return (uint16_t)(s % n_sectors);
}

/* Destination bearing in centidegrees to the nearest whole degree in 0..359. */
static uint16_t bearing_deg(qnav_cdeg_t cdeg)
{
    int32_t c = cdeg;
    int32_t d = (c >= 0) ? (c + 50) / 100 : -((-c + 50) / 100);
    d %= QNAV_PATHS;
    return (uint16_t)(d < 0 ? d + QNAV_PATHS : d);
}

/* Turn from straight ahead to path i, degrees in -179..180. */
static qnav_deg_t heading_of(uint16_t path)
{
    return (qnav_deg_t)(path <= 180u ? (int16_t)path : (int16_t)path - 360);
}

static void stop_output(qnav_ctrl_output_t *out, uint8_t flags, qnav_q1_15_t *qualities)
{
    uint16_t i;
    out->heading_deg = 0;
    out->speed = 0;
    out->quality = 0;
    out->flags = flags;
    if (qualities != 0) {
        for (i = 0; i < QNAV_PATHS; ++i) {
            qualities[i] = 0;
        }
    }
}

/* Does candidate (q, dtheta, turn) beat the best so far? Ties: smaller dtheta, smaller
 * turn, then counter-clockwise (positive heading). */
static uint8_t beats(qnav_q1_15_t q, uint8_t dtheta, qnav_deg_t heading, qnav_q1_15_t best_q,
                     uint8_t best_dtheta, qnav_deg_t best_heading)
{
    int16_t turn;
    int16_t best_turn;
    if (q != best_q) {
        return (uint8_t)(q > best_q);
    }
    if (dtheta != best_dtheta) {
        return (uint8_t)(dtheta < best_dtheta);
    }
    turn = (int16_t)(heading < 0 ? -heading : heading);
    best_turn = (int16_t)(best_heading < 0 ? -best_heading : best_heading);
    if (turn != best_turn) {
        return (uint8_t)(turn < best_turn);
    }
    return (uint8_t)(heading > best_heading);
}

void qnav_ctrl_step(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, qnav_q1_15_t *qualities)
{
    int32_t base[QNAV_MAX_HIDDEN];
    const qnav_q1_15_t *row = 0;
    uint16_t goal;
    uint16_t path;
    uint16_t sector = 0;
    uint16_t phase;         /* path * N + 180, reduced modulo 360: sector advances at wrap */
    uint16_t offset;        /* (path - goal) mod 360 */
    uint8_t level = 0;
    uint8_t flags = 0;
    uint8_t j;
    qnav_q1_15_t best_q = -1;
    uint8_t best_dtheta = 0;
    qnav_deg_t best_heading = 0;
    uint32_t speed;

    if (out == 0) {
        return;
    }
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || in == 0 || in->ranges_mm == 0) {
        stop_output(out, QNAV_FLAG_NOT_READY, qualities);
        return;
    }
    goal = bearing_deg(in->goal_bearing_cdeg);
    offset = (uint16_t)((QNAV_PATHS - goal) % QNAV_PATHS);
    phase = QNAV_PATHS / 2u;

    for (path = 0; path < QNAV_PATHS; ++path) {
        uint8_t dtheta = (uint8_t)(offset <= QNAV_DTHETA_MAX ? offset : QNAV_PATHS - offset);
        qnav_deg_t heading = heading_of(path);
        qnav_q1_15_t q;

        if (path == 0u || phase >= QNAV_PATHS) {
            qnav_mm_t r;
            if (phase >= QNAV_PATHS) {
                phase = (uint16_t)(phase - QNAV_PATHS);
                sector = (uint16_t)(sector + 1u == ctrl->n_sectors ? 0u : sector + 1u);
            }
            r = in->ranges_mm[sector];
            if (r > ctrl->max_range_mm) {
                r = ctrl->max_range_mm;
                flags |= QNAV_FLAG_RANGE_CLIPPED;
            }
            level = level_of(ctrl, r);
            if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
                for (j = 0; j < ctrl->hidden; ++j) {
                    base[j] = ctrl->p.unit[j].bias_z + ctrl->p.unit[j].per_level * level;
                }
            } else if (ctrl->kind == QNAV_KIND_TABLE) {
                row = &ctrl->table[(uint16_t)level * QNAV_TABLE_STRIDE];
            }
        }

        if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
            int32_t acc = ctrl->out_bias_z;
            for (j = 0; j < ctrl->hidden; ++j) {
                acc += unit_share(base[j] + ctrl->p.unit[j].per_deg * dtheta, ctrl->p.unit[j].out);
            }
            q = net_output(acc);
        } else if (ctrl->kind == (uint8_t)QNAV_POLICY_PROB) {
            q = prob_quality(ctrl, level, dtheta);
        } else {
            q = QNAV_FLASH_READ_I16(&row[dtheta]);
        }

        if (qualities != 0) {
            qualities[path] = q;
        }
        if (beats(q, dtheta, heading, best_q, best_dtheta, best_heading)) {
            best_q = q;
            best_dtheta = dtheta;
            best_heading = heading;
        }
        phase = (uint16_t)(phase + ctrl->n_sectors);
        offset = (uint16_t)(offset + 1u == QNAV_PATHS ? 0u : offset + 1u);
    }

    if (best_q <= 0) {
        out->heading_deg = 0;
        out->speed = 0;
        out->quality = 0;
        out->flags = (uint8_t)(flags | QNAV_FLAG_NO_PATH);
        return;
    }
    speed = ((uint32_t)best_q * ctrl->speed_scale) >> 15;
    if (best_q >= ctrl->full_speed_quality || speed > QNAV_Q1_15_MAX) {
        speed = QNAV_Q1_15_MAX;
        flags |= QNAV_FLAG_FULL_SPEED;
    }
    out->heading_deg = best_heading;
    out->speed = (qnav_q1_15_t)speed;
    out->quality = best_q;
    out->flags = flags;
}
