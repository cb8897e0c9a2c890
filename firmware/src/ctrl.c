/*
 * The navigation controller: quantizes a scan into per-path distance levels (clearance.c),
 * gives each of the 360 paths a rank key through one policy function (network,
 * probabilistic or compiled table), picks the best path and maps its quality to a speed
 * under the speed guard. Integer arithmetic only;
 * every format and bound is in docs/qformats.md.
 */
#include "qnav/ctrl.h"
#include "clearance.h"
#include "qnav/flash.h"
#include "sigmoid_lut.h"

#define QNAV_CTRL_MAGIC 0x514Eu
#define QNAV_TABLE_STRIDE (QNAV_DTHETA_MAX + 1)
#define QNAV_KIND_TABLE 0u

/* The network arithmetic shifts signed values right and relies on it being arithmetic
 * (implementation-defined in C99; true on gcc, avr-gcc and arm-none-eabi-gcc). */
typedef char qnav_arith_shift_check[((-8 >> 1) == -4) ? 1 : -1];

static inline int16_t sat16(int32_t v)
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
    v = (t + ((uint32_t)1 << n)) >> (n + 1u);
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
    cfg->body_radius_mm = 120u;
    cfg->safety_mm = 50u;
    cfg->sensor_offset_mm = 120u;
    cfg->v_max_mm_s = 500u;
    cfg->decel_mm_s2 = 2000u;
    cfg->rank = (uint8_t)QNAV_RANK_PREACT;
}

void qnav_ctrl_config_literal(qnav_ctrl_config_t *cfg)
{
    if (cfg == 0) {
        return;
    }
    cfg->body_radius_mm = 0u;
    cfg->safety_mm = 0u;
    cfg->decel_mm_s2 = 0u;
    cfg->rank = (uint8_t)QNAV_RANK_QUALITY;
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
    if (cfg->rank != (uint8_t)QNAV_RANK_QUALITY && cfg->rank != (uint8_t)QNAV_RANK_PREACT) {
        return QNAV_E_RANK;
    }
    q_full = (uint32_t)cfg->full_speed_quality;
    ctrl->n_sectors = cfg->n_sectors;
    ctrl->max_range_mm = cfg->max_range_mm;
    ctrl->full_speed_quality = cfg->full_speed_quality;
    ctrl->level_scale = ((uint32_t)(QNAV_DIST_LEVELS - 1) * 65536u + cfg->max_range_mm / 2u) /
                        cfg->max_range_mm;
    ctrl->speed_scale = ((uint32_t)32768u * 32768u + q_full / 2u) / q_full;
    ctrl->sector_paths = (uint16_t)(QNAV_PATHS / cfg->n_sectors);
    ctrl->sector_span = (uint16_t)(ctrl->sector_paths * cfg->n_sectors);
    ctrl->first_sector_paths = (uint16_t)((QNAV_PATHS / 2u + cfg->n_sectors - 1u) / cfg->n_sectors);
    ctrl->table = 0;
    ctrl->hidden = 0u;
    ctrl->out_bias_z = 0;
    ctrl->rank = cfg->rank;
    qnav_clearance_init(ctrl, cfg);
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
        u->bias_z = (int32_t)net->b_hidden[j] * 2048;
        u->per_deg = div_round((int32_t)net->w_theta[j] * 2048, QNAV_DTHETA_MAX);
        u->per_level = div_round((int32_t)net->w_dist[j] * 2048, QNAV_DIST_LEVELS - 1);
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
        ctrl->rank = (uint8_t)QNAV_RANK_QUALITY; /* a product of probabilities: no saturation */
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
                                   const qnav_qkey_t *table, qnav_rank_t rank)
{
    qnav_status_t st = init_common(ctrl, cfg);
    if (st != QNAV_OK) {
        return st;
    }
    if (table == 0) {
        return QNAV_E_NULL;
    }
    if (rank != QNAV_RANK_QUALITY && rank != QNAV_RANK_PREACT) {
        return QNAV_E_RANK;
    }
    ctrl->table = table;
    ctrl->rank = (uint8_t)rank;
    ctrl->kind = QNAV_KIND_TABLE;
    ctrl->magic = QNAV_CTRL_MAGIC;
    return QNAV_OK;
}

/*
 * One hidden unit's share of the output pre-activation, in units of 2^-15.
 * z is the unit's pre-activation in units of 2^-19 (|z| < 3 * 2^26).
 * @par Scaling and overflow: (z + 2^7) >> 8 is Q5.11 (a byte move on AVR), saturated to
 * [-16, 16); out (Q8.8) times h (Q1.15) is below 2^30; >> 8 leaves units of 2^-15, below
 * 2^22 per unit, so 32 units sum below 2^27.
 */
static inline int32_t unit_share(int32_t z, int16_t out)
{
    int16_t h = qnav_sigmoid_q5_11(sat16((z + 128) >> 8));
    return ((int32_t)out * h + 128) >> 8;
}

/* Knee of the companded key: |z| below 8 keeps Q5.11 resolution. */
#define QNAV_KEY_KNEE 16384
#define QNAV_KEY_NONE (-32767 - 1)

/* Output unit: acc in units of 2^-15, rounded to Q5.11 and saturated. */
static inline qnav_q1_15_t net_output(int32_t acc)
{
    return qnav_sigmoid_q5_11(sat16((acc + 8) >> 4));
}

/*
 * The companded pre-activation key of acc (units of 2^-15).
 * @par Scaling and overflow: a = round(acc / 16) is Q5.11; |a| < 16384 (|z| < 8) is kept,
 * beyond the knee every 16 Q5.11 steps are one key step (1/128 in z), saturated to
 * +-32767, so the key is monotone in acc and -32768 stays free. |acc| < 2^27.
 */
static inline qnav_qkey_t preact_key(int32_t acc)
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

/* The network's key for an output accumulator, under the controller's rank. */
static inline qnav_qkey_t net_key_of(const qnav_ctrl_t *ctrl, int32_t acc)
{
    return ctrl->rank == (uint8_t)QNAV_RANK_PREACT ? preact_key(acc) : net_output(acc);
}

/* A key back to the quality: expand to Q5.11 (saturating at +-16) and take the sigmoid. */
static qnav_q1_15_t key_quality(const qnav_ctrl_t *ctrl, qnav_qkey_t key)
{
    int32_t z = key;
    if (ctrl->rank != (uint8_t)QNAV_RANK_PREACT) {
        return (qnav_q1_15_t)(key < 0 ? 0 : key);
    }
    if (z >= QNAV_KEY_KNEE) {
        z = QNAV_KEY_KNEE + (z - QNAV_KEY_KNEE) * 16;
    } else if (z < -QNAV_KEY_KNEE) {
        z = -QNAV_KEY_KNEE + (z + QNAV_KEY_KNEE) * 16;
    }
    return qnav_sigmoid_q5_11(sat16(z));
}

static qnav_q1_15_t prob_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    uint32_t q = (uint32_t)ctrl->p.prob.goal[dtheta] * (uint32_t)ctrl->p.prob.safe[level];
    return (qnav_q1_15_t)((q + 16384u) >> 15);
}

/* a * b for a small unsigned b. */
static inline int32_t mul_u8(int32_t a, uint8_t b)
{
    return a * (int32_t)b;
}

static inline int32_t unit_base(const qnav_ctrl_unit_t *u, uint8_t level)
{
    return u->bias_z + mul_u8(u->per_level, level);
}

static qnav_qkey_t net_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    int32_t acc = ctrl->out_bias_z;
    uint8_t j;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        acc += unit_share(unit_base(u, level) + mul_u8(u->per_deg, dtheta), u->out);
    }
    return net_key_of(ctrl, acc);
}

static qnav_qkey_t key_at(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
        return net_key(ctrl, level, dtheta);
    }
    if (ctrl->kind == (uint8_t)QNAV_POLICY_PROB) {
        return prob_quality(ctrl, level, dtheta);
    }
    return QNAV_FLASH_READ_I16(&ctrl->table[(uint16_t)level * QNAV_TABLE_STRIDE + dtheta]);
}

qnav_qkey_t qnav_ctrl_key(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return -32767;
    }
    if (level >= QNAV_DIST_LEVELS) {
        level = QNAV_DIST_LEVELS - 1u;
    }
    if (dtheta_deg > QNAV_DTHETA_MAX) {
        dtheta_deg = QNAV_DTHETA_MAX;
    }
    return key_at(ctrl, level, dtheta_deg);
}

qnav_q1_15_t qnav_ctrl_key_quality(const qnav_ctrl_t *ctrl, qnav_qkey_t key)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return key_quality(ctrl, key);
}

qnav_q1_15_t qnav_ctrl_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta_deg)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return key_quality(ctrl, qnav_ctrl_key(ctrl, level, dtheta_deg));
}

qnav_rank_t qnav_ctrl_rank(const qnav_ctrl_t *ctrl)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || ctrl->rank != (uint8_t)QNAV_RANK_PREACT) {
        return QNAV_RANK_QUALITY;
    }
    return QNAV_RANK_PREACT;
}

uint8_t qnav_ctrl_level(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC) {
        return 0;
    }
    return qnav_clearance_level_of(ctrl, range_mm > ctrl->max_range_mm ? ctrl->max_range_mm : range_mm);
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

/* Destination bearing in centidegrees to the nearest whole degree (halves away from
 * zero) in 0..359. 16-bit arithmetic: one division, no 32-bit ones (costly on AVR). */
static uint16_t bearing_deg(qnav_cdeg_t cdeg)
{
    int16_t d = (int16_t)(cdeg / 100);
    int16_t rest = (int16_t)(cdeg - d * 100);
    if (rest >= 50) {
        ++d;
    } else if (rest <= -50) {
        --d;
    }
    while (d < 0) {
        d = (int16_t)(d + QNAV_PATHS);
    }
    while (d >= (int16_t)QNAV_PATHS) {
        d = (int16_t)(d - QNAV_PATHS);
    }
    return (uint16_t)d;
}


/*
 * A run: consecutive paths of one distance level along which dtheta moves one way. Within
 * a run each hidden unit's pre-activation is monotone, which is what lets the network step
 * bound a whole run from its two ends (docs/architecture.md).
 */
typedef struct {
    uint16_t first;      /* first path, degrees */
    uint8_t count;       /* paths in the run, 1..180 */
    uint8_t level;       /* distance level of every path of the run */
    uint8_t dtheta0;     /* dtheta of the first path */
    int8_t dir;          /* +1 or -1: change of dtheta from one path to the next */
} run_t;

/* A run kept for the network's best-first search, with its bound. */
typedef struct {
    uint16_t first;
    uint8_t count;
    uint8_t level;
    qnav_qkey_t bound;   /* no path of the run exceeds it; QNAV_KEY_NONE once evaluated */
} pending_t;

/* The best path so far under the controller's total order (key, then smaller dtheta,
 * then smaller turn, then counter-clockwise). */
typedef struct {
    qnav_qkey_t key;
    uint8_t dtheta;
    qnav_deg_t heading;
} best_t;

static void consider(best_t *best, qnav_qkey_t key, uint16_t path, uint8_t dtheta)
{
    qnav_deg_t heading;
    int16_t turn;
    int16_t best_turn;
    if (key < best->key) {
        return;
    }
    heading = (qnav_deg_t)(path <= 180u ? (int16_t)path : (int16_t)path - 360);
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

/* Walks the 360 paths once and hands out their runs in path order. */
typedef struct {
    const uint8_t *lvl;   /* distance level of every path */
    uint16_t goal;        /* destination, whole degrees 0..359 */
    uint16_t path;        /* next path to hand out */
} run_iter_t;

/* dtheta of a run's first path and its direction, from the path and the goal. */
static void run_shape(run_t *r, uint16_t goal)
{
    uint16_t offset = (uint16_t)(r->first >= goal ? r->first - goal : r->first + QNAV_PATHS - goal);
    r->dtheta0 = (uint8_t)(offset <= QNAV_DTHETA_MAX ? offset : QNAV_PATHS - offset);
    r->dir = (int8_t)(offset < QNAV_DTHETA_MAX ? 1 : -1);
}

/* The next run into *r; 0 when all 360 paths have been handed out. A run ends where the
 * level changes, where dtheta turns (at the goal and opposite it) and after path 359. */
static uint8_t run_iter_next(run_iter_t *it, run_t *r)
{
    uint16_t end;
    uint16_t to_turn;
    uint16_t p;
    uint8_t level;
    if (it->path >= QNAV_PATHS) {
        return 0;
    }
    r->first = it->path;
    run_shape(r, it->goal);
    to_turn = (uint16_t)(r->dir > 0 ? QNAV_DTHETA_MAX - r->dtheta0 : r->dtheta0);
    if (to_turn == 0u) {
        to_turn = QNAV_DTHETA_MAX; /* starts at the goal, or opposite it going down */
    }
    end = (uint16_t)(it->path + to_turn);
    if (end > QNAV_PATHS) {
        end = QNAV_PATHS;
    }
    level = it->lvl[it->path];
    p = (uint16_t)(it->path + 1u);
    while (p < end && it->lvl[p] == level) {
        ++p;
    }
    r->count = (uint8_t)(p - it->path);
    r->level = level;
    it->path = p;
    return 1;
}

/* Table mode: read a run's row. Along the run the tie order prefers earlier paths when
 * dtheta rises and later ones when it falls, so only the run's winner is considered. */
static void eval_table_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                           qnav_qkey_t *keys)
{
    const qnav_qkey_t *p = &ctrl->table[(uint16_t)r->level * QNAV_TABLE_STRIDE + r->dtheta0];
    qnav_qkey_t top = QNAV_KEY_NONE;
    uint8_t top_k = 0;
    uint8_t k;
    for (k = 0; k < r->count; ++k, p += r->dir) {
        qnav_qkey_t q = QNAV_FLASH_READ_I16(p);
        if (keys != 0) {
            keys[r->first + k] = q;
        }
        if (q > top || (q == top && r->dir < 0)) {
            top = q;
            top_k = k;
        }
    }
    consider(best, top, (uint16_t)(r->first + top_k),
             (uint8_t)(r->dir > 0 ? r->dtheta0 + top_k : r->dtheta0 - top_k));
}

static void eval_prob_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                          qnav_qkey_t *keys)
{
    uint8_t k;
    uint8_t dtheta = r->dtheta0;
    for (k = 0; k < r->count; ++k, dtheta = (uint8_t)(dtheta + r->dir)) {
        qnav_q1_15_t q = prob_quality(ctrl, r->level, dtheta);
        if (keys != 0) {
            keys[r->first + k] = q;
        }
        consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
}

/* Network: every path of a run; pre-activations walk by one degree's weight per path. */
static void eval_net_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                         qnav_qkey_t *keys)
{
    int32_t z[QNAV_MAX_HIDDEN];
    uint8_t k;
    uint8_t j;
    uint8_t dtheta = r->dtheta0;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        z[j] = unit_base(u, r->level) + mul_u8(u->per_deg, r->dtheta0);
    }
    for (k = 0; k < r->count; ++k, dtheta = (uint8_t)(dtheta + r->dir)) {
        int32_t acc = ctrl->out_bias_z;
        qnav_qkey_t q;
        for (j = 0; j < ctrl->hidden; ++j) {
            const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
            acc += unit_share(z[j], u->out);
            z[j] = (r->dir > 0) ? z[j] + u->per_deg : z[j] - u->per_deg;
        }
        q = net_key_of(ctrl, acc);
        if (keys != 0) {
            keys[r->first + k] = q;
        }
        consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
}

qnav_status_t qnav_ctrl_build_table(const qnav_ctrl_t *ctrl, qnav_qkey_t *table)
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
        qnav_qkey_t *row = &table[level * QNAV_TABLE_STRIDE];
        if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
            /* a row is a run of dtheta 0..180: the same integers, by addition */
            run_t r;
            best_t ignore;
            r.first = 0;
            r.count = QNAV_DTHETA_MAX + 1;
            r.level = (uint8_t)level;
            r.dtheta0 = 0;
            r.dir = 1;
            ignore.key = QNAV_KEY_NONE;
            ignore.dtheta = 0;
            ignore.heading = 0;
            eval_net_run(ctrl, &r, &ignore, row);
        } else {
            for (dtheta = 0; dtheta <= QNAV_DTHETA_MAX; ++dtheta) {
                row[dtheta] = prob_quality(ctrl, (uint8_t)level, (uint8_t)dtheta);
            }
        }
    }
    return QNAV_OK;
}

/* How the dtheta term moves in the current run (see bound_runs). */
typedef struct {
    uint8_t level;
    uint8_t span;     /* paths in the run - 1 */
    uint8_t up;       /* dtheta rises along the run */
    uint8_t step_up;  /* the run's first dtheta is above the previous run's last */
    uint8_t first;    /* first run of the step: c starts from dtheta0 */
    uint8_t dtheta0;
} run_walk_t;

/* One unit's largest share over a run; advances its dtheta term c (per_deg * dtheta at
 * the end of the previous run) to the run's end. */
static inline int32_t bound_unit(const qnav_ctrl_unit_t *u, int32_t *c_io, const run_walk_t *rw)
{
    int32_t base = unit_base(u, rw->level);
    int32_t c = rw->first ? mul_u8(u->per_deg, rw->dtheta0)
                          : (rw->step_up ? *c_io + u->per_deg : *c_io - u->per_deg);
    int32_t dz = mul_u8(u->per_deg, rw->span);
    int32_t z0 = base + c;
    int32_t z1;
    c = rw->up ? c + dz : c - dz;
    *c_io = c;
    z1 = base + c;
    return unit_share(((u->out >= 0) == (z1 > z0)) ? z1 : z0, u->out);
}

/*
 * Network, first pass: bound every run. Along a run each hidden unit's pre-activation is
 * linear in dtheta, and rounding, saturation, the interpolated sigmoid and the output
 * weight all keep order, so a unit's share is largest at one end, the end where
 * out * z is larger: one sigmoid per unit bounds the whole run, and the key is monotone
 * in the output's accumulator. The dtheta term is carried from run to run (neighbouring
 * paths differ by one degree). Runs whose bound is below the best so far are dropped;
 * runs beyond cap are evaluated at once (same answer). Returns the runs kept in runs[].
 */
static uint16_t bound_runs(const qnav_ctrl_t *ctrl, run_iter_t *it, pending_t *runs,
                           uint16_t cap, best_t *best)
{
    int32_t c[QNAV_MAX_HIDDEN];
    run_walk_t rw;
    uint8_t prev_end = 0;
    uint16_t n = 0;
    uint8_t j;
    run_t r;
    rw.first = 1;
    while (run_iter_next(it, &r)) {
        int32_t acc = ctrl->out_bias_z;
        qnav_qkey_t bound;
        rw.level = r.level;
        rw.span = (uint8_t)(r.count - 1u);
        rw.up = (uint8_t)(r.dir > 0);
        rw.step_up = (uint8_t)(r.dtheta0 > prev_end);
        rw.dtheta0 = r.dtheta0;
        for (j = 0; j < ctrl->hidden; ++j) {
            acc += bound_unit(&ctrl->p.unit[j], &c[j], &rw);
        }
        rw.first = 0;
        prev_end = (uint8_t)(rw.up ? r.dtheta0 + rw.span : r.dtheta0 - rw.span);
        bound = net_key_of(ctrl, acc);
        if (r.count == 1u) {
            consider(best, bound, r.first, r.dtheta0); /* the bound is exact */
        } else if (bound < best->key) {
            /* cannot win: the best only rises */
        } else if (n < cap) {
            runs[n].first = r.first;
            runs[n].count = r.count;
            runs[n].level = r.level;
            runs[n].bound = bound;
            ++n;
        } else {
            eval_net_run(ctrl, &r, best, 0);
        }
    }
    return n;
}

/* Best-first over the runs' bounds: stop when no run left can reach the best. */
static void search_runs(const qnav_ctrl_t *ctrl, pending_t *runs, uint16_t n, uint16_t goal,
                        best_t *best)
{
    uint16_t i;
    for (;;) {
        pending_t *top = 0;
        run_t r;
        for (i = 0; i < n; ++i) {
            if (runs[i].bound != QNAV_KEY_NONE && (top == 0 || runs[i].bound > top->bound)) {
                top = &runs[i];
            }
        }
        if (top == 0 || top->bound < best->key) {
            return;
        }
        r.first = top->first;
        r.count = top->count;
        r.level = top->level;
        run_shape(&r, goal);
        eval_net_run(ctrl, &r, best, 0);
        top->bound = QNAV_KEY_NONE;
    }
}

/* Probabilistic: quality falls with dtheta at a fixed level, so a run's best path is its
 * end nearest the goal, which the tie order also prefers. */
static void prob_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best)
{
    uint8_t k = (uint8_t)(r->dir > 0 ? 0u : r->count - 1u);
    uint8_t dtheta = (uint8_t)(r->dir > 0 ? r->dtheta0 : r->dtheta0 - k);
    consider(best, prob_quality(ctrl, r->level, dtheta), (uint16_t)(r->first + k), dtheta);
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

/* Network without qualities: bound every run, then search the runs best first. */
static void net_best(const qnav_ctrl_t *ctrl, run_iter_t *it, best_t *best)
{
    pending_t runs[QNAV_MAX_RUNS];
    uint16_t n;
    /* the path straight at the goal first: a good best prunes runs before they are kept */
    consider(best, net_key(ctrl, it->lvl[it->goal], 0), it->goal, 0);
    n = bound_runs(ctrl, it, runs, QNAV_MAX_RUNS, best);
    search_runs(ctrl, runs, n, it->goal, best);
}

/* Every path through its run: all keys, or the table's and probabilistic run winners. */
static void runs_best(const qnav_ctrl_t *ctrl, run_iter_t *it, best_t *best, qnav_qkey_t *keys)
{
    run_t r;
    while (run_iter_next(it, &r)) {
        if (ctrl->kind == QNAV_KIND_TABLE) {
            eval_table_run(ctrl, &r, best, keys);
        } else if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
            eval_net_run(ctrl, &r, best, keys);
        } else if (keys != 0) {
            eval_prob_run(ctrl, &r, best, keys);
        } else {
            prob_run(ctrl, &r, best);
        }
    }
}

uint8_t qnav_ctrl_path_levels(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges_mm, uint8_t *lvl)
{
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || ranges_mm == 0 || lvl == 0) {
        return QNAV_FLAG_NOT_READY;
    }
    return qnav_clearance_levels(ctrl, ranges_mm, lvl);
}

void qnav_ctrl_step(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, qnav_q1_15_t *qualities)
{
    uint8_t lvl[QNAV_PATHS];
    run_iter_t it;
    best_t best;
    uint8_t flags;
    uint16_t path;
    uint32_t speed;
    qnav_q1_15_t quality;
    qnav_q1_15_t cap;

    if (out == 0) {
        return;
    }
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || in == 0 || in->ranges_mm == 0) {
        stop_output(out, QNAV_FLAG_NOT_READY, qualities);
        return;
    }
    best.key = QNAV_KEY_NONE;
    best.dtheta = 0;
    best.heading = 0;
    flags = qnav_clearance_levels(ctrl, in->ranges_mm, lvl);
    it.lvl = lvl;
    it.goal = bearing_deg(in->goal_bearing_cdeg);
    it.path = 0;
    if (qualities == 0 && ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
        net_best(ctrl, &it, &best);
    } else {
        /* the keys land in qualities[] and are turned into qualities below */
        runs_best(ctrl, &it, &best, qualities);
    }
    if (qualities != 0) {
        for (path = 0; path < QNAV_PATHS; ++path) {
            qualities[path] = key_quality(ctrl, qualities[path]);
        }
    }

    quality = key_quality(ctrl, best.key);
    if (quality <= 0) {
        out->heading_deg = 0;
        out->speed = 0;
        out->quality = 0;
        out->flags = (uint8_t)(flags | QNAV_FLAG_NO_PATH);
        return;
    }
    speed = ((uint32_t)quality * ctrl->speed_scale) >> 15;
    if (quality >= ctrl->full_speed_quality || speed > QNAV_Q1_15_MAX) {
        speed = QNAV_Q1_15_MAX;
        flags |= QNAV_FLAG_FULL_SPEED;
    }
    path = (uint16_t)(best.heading < 0 ? best.heading + QNAV_PATHS : best.heading);
    cap = ctrl->speed_cap[lvl[path]];
    if (speed > (uint32_t)cap) {
        speed = (uint32_t)cap;
        flags |= QNAV_FLAG_SPEED_GUARD;
    }
    out->heading_deg = best.heading;
    out->speed = (qnav_q1_15_t)speed;
    out->quality = quality;
    out->flags = flags;
}
