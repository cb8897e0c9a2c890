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
    ctrl->speed_scale = ((uint32_t)32768u * 32768u + q_full / 2u) / q_full;
    ctrl->sector_paths = (uint16_t)(QNAV_PATHS / cfg->n_sectors);
    ctrl->sector_span = (uint16_t)(ctrl->sector_paths * cfg->n_sectors);
    ctrl->first_sector_paths = (uint16_t)((QNAV_PATHS / 2u + cfg->n_sectors - 1u) / cfg->n_sectors);
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

/* Output unit: acc in units of 2^-15, rounded to Q5.11 and saturated. */
static inline qnav_q1_15_t net_output(int32_t acc)
{
    return qnav_sigmoid_q5_11(sat16((acc + 8) >> 4));
}

static qnav_q1_15_t prob_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    uint32_t q = (uint32_t)ctrl->p.prob.goal[dtheta] * (uint32_t)ctrl->p.prob.safe[level];
    return (qnav_q1_15_t)((q + 16384u) >> 15);
}

/* a * b for a small unsigned b: avr-gcc then uses its 32x16 multiply, not 32x32. */
static inline int32_t mul_u8(int32_t a, uint8_t b)
{
    return a * (int32_t)b;
}

static inline int32_t unit_base(const qnav_ctrl_unit_t *u, uint8_t level)
{
    return u->bias_z + mul_u8(u->per_level, level);
}

static qnav_q1_15_t net_quality(const qnav_ctrl_t *ctrl, uint8_t level, uint8_t dtheta)
{
    int32_t acc = ctrl->out_bias_z;
    uint8_t j;
    for (j = 0; j < ctrl->hidden; ++j) {
        const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
        acc += unit_share(unit_base(u, level) + mul_u8(u->per_deg, dtheta), u->out);
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


/* Level of a range already known to be at most max_range_mm. For ranges of 32 mm and
 * more the scale fits 16 bits and a 16x16 multiply does (much cheaper on AVR). */
static uint8_t level_of(const qnav_ctrl_t *ctrl, qnav_mm_t range_mm)
{
    uint32_t level;
    if (ctrl->level_scale <= 0xFFFFu) {
        level = ((uint32_t)range_mm * (uint16_t)ctrl->level_scale + 32768u) >> 16;
    } else {
        level = ((uint32_t)range_mm * ctrl->level_scale + 32768u) >> 16;
    }
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
 * A run: consecutive paths in one sector along which dtheta moves one way. Within a run
 * the distance level is fixed and each hidden unit's pre-activation is monotone, which is
 * what lets the network step bound a whole run from its two ends (docs/architecture.md).
 */
typedef struct {
    uint16_t first;      /* first path, degrees */
    uint8_t count;       /* paths in the run, 1..180 */
    uint8_t level;       /* distance level of the run's sector */
    uint8_t dtheta0;     /* dtheta of the first path */
    int8_t dir;          /* +1 or -1: change of dtheta from one path to the next */
} run_t;

/* A run kept for the network's best-first search, with its bound. */
typedef struct {
    uint16_t first;
    uint8_t count;
    uint8_t level;
    qnav_q1_15_t bound;  /* no path of the run exceeds it; -1 once evaluated */
} pending_t;

/* The best path so far under the controller's total order (quality, then smaller
 * dtheta, then smaller turn, then counter-clockwise). */
typedef struct {
    qnav_q1_15_t q;
    uint8_t dtheta;
    qnav_deg_t heading;
} best_t;

static void consider(best_t *best, qnav_q1_15_t q, uint16_t path, uint8_t dtheta)
{
    qnav_deg_t heading;
    int16_t turn;
    int16_t best_turn;
    if (q < best->q) {
        return;
    }
    heading = (qnav_deg_t)(path <= 180u ? (int16_t)path : (int16_t)path - 360);
    if (q == best->q) {
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
    best->q = q;
    best->dtheta = dtheta;
    best->heading = heading;
}

/* Walks the 360 paths once and hands out their runs in path order, a run at a time. */
typedef struct {
    const qnav_ctrl_t *ctrl;
    const qnav_mm_t *ranges;
    uint16_t goal;        /* destination, whole degrees 0..359 */
    uint16_t path;        /* next path to hand out */
    uint16_t sector;      /* its sector */
    uint16_t left;        /* paths of that sector still to hand out */
    uint16_t phase;       /* first path of the sector * N + 180, modulo 360 */
    uint16_t count;       /* paths in the sector */
    uint8_t level;        /* distance level of the sector */
    uint8_t flags;        /* QNAV_FLAG_RANGE_CLIPPED once a clipped range was seen */
} run_iter_t;

static void run_iter_enter_sector(run_iter_t *it)
{
    qnav_mm_t r = it->ranges[it->sector];
    if (r > it->ctrl->max_range_mm) {
        r = it->ctrl->max_range_mm;
        it->flags |= QNAV_FLAG_RANGE_CLIPPED;
    }
    it->level = level_of(it->ctrl, r);
    it->left = it->count;
}

static void run_iter_start(run_iter_t *it, const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges,
                           uint16_t goal)
{
    it->ctrl = ctrl;
    it->ranges = ranges;
    it->goal = goal;
    it->path = 0;
    it->sector = 0;
    it->phase = QNAV_PATHS / 2u;
    it->count = ctrl->first_sector_paths;
    it->flags = 0;
    run_iter_enter_sector(it);
}

/* dtheta of a run's first path and its direction, from the path and the goal. */
static void run_shape(run_t *r, uint16_t goal)
{
    uint16_t offset = (uint16_t)(r->first >= goal ? r->first - goal : r->first + QNAV_PATHS - goal);
    r->dtheta0 = (uint8_t)(offset <= QNAV_DTHETA_MAX ? offset : QNAV_PATHS - offset);
    r->dir = (int8_t)(offset < QNAV_DTHETA_MAX ? 1 : -1);
}

/* The next run into *r; 0 when all 360 paths have been handed out. A run ends where the
 * sector ends, where dtheta turns (at the goal and opposite it) and after path 359.
 * Sector lengths follow from path * N + 180 wrapping past 360: a sector whose first path
 * has phase p holds q = 360 / N paths, or q + 1 when p + q * N is still below 360. */
static uint8_t run_iter_next(run_iter_t *it, run_t *r)
{
    uint16_t n;
    uint16_t to_turn;
    if (it->path >= QNAV_PATHS) {
        return 0;
    }
    if (it->left == 0u) {
        const qnav_ctrl_t *c = it->ctrl;
        it->phase = (uint16_t)(it->phase + it->count * c->n_sectors - QNAV_PATHS);
        it->count = (uint16_t)(c->sector_paths + (it->phase + c->sector_span < QNAV_PATHS ? 1u : 0u));
        it->sector = (uint16_t)(it->sector + 1u == c->n_sectors ? 0u : it->sector + 1u);
        run_iter_enter_sector(it);
    }
    r->first = it->path;
    run_shape(r, it->goal);
    to_turn = (uint16_t)(r->dir > 0 ? QNAV_DTHETA_MAX - r->dtheta0 : r->dtheta0);
    if (to_turn == 0u) {
        to_turn = QNAV_DTHETA_MAX; /* starts at the goal, or opposite it going down */
    }
    n = it->left < to_turn ? it->left : to_turn;
    if (n > QNAV_PATHS - it->path) {
        n = (uint16_t)(QNAV_PATHS - it->path);
    }
    r->count = (uint8_t)n;
    r->level = it->level;
    it->path = (uint16_t)(it->path + n);
    it->left = (uint16_t)(it->left - n);
    return 1;
}

/* Table mode: read a run's row. Along the run the tie order prefers earlier paths when
 * dtheta rises and later ones when it falls, so only the run's winner is considered. */
static void eval_table_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                           qnav_q1_15_t *qualities)
{
    const qnav_q1_15_t *p = &ctrl->table[(uint16_t)r->level * QNAV_TABLE_STRIDE + r->dtheta0];
    qnav_q1_15_t top = -1;
    uint8_t top_k = 0;
    uint8_t k;
    for (k = 0; k < r->count; ++k, p += r->dir) {
        qnav_q1_15_t q = QNAV_FLASH_READ_I16(p);
        if (qualities != 0) {
            qualities[r->first + k] = q;
        }
        if (q > top || (q == top && r->dir < 0)) {
            top = q;
            top_k = k;
        }
    }
    consider(best, top, (uint16_t)(r->first + top_k),
             (uint8_t)(r->dir > 0 ? r->dtheta0 + top_k : r->dtheta0 - top_k));
}

/*
 * Table mode without qualities, the MCU's fast path: one pass over the sectors in path
 * order with everything in locals; each stretch of a sector along which dtheta moves one
 * way is scanned with a pointer into its level's row, and only its winner is considered
 * (ties inside a stretch go to the smaller dtheta: the first path when dtheta rises, the
 * last when it falls). Same answer as eval_table_run over the runs.
 */
static uint8_t table_best(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges, uint16_t goal,
                          best_t *best)
{
    uint16_t path = 0;
    uint16_t sector = 0;
    uint16_t phase = QNAV_PATHS / 2u;
    uint16_t count = ctrl->first_sector_paths;
    uint16_t offset = goal == 0u ? 0u : (uint16_t)(QNAV_PATHS - goal);
    uint8_t flags = 0;
    for (;;) {
        qnav_mm_t range = ranges[sector];
        const qnav_q1_15_t *row;
        uint16_t left = count;
        if (range > ctrl->max_range_mm) {
            range = ctrl->max_range_mm;
            flags |= QNAV_FLAG_RANGE_CLIPPED;
        }
        row = &ctrl->table[(uint16_t)level_of(ctrl, range) * QNAV_TABLE_STRIDE];
        if (left > QNAV_PATHS - path) {
            left = (uint16_t)(QNAV_PATHS - path);
        }
        while (left != 0u) {
            uint8_t n;
            uint8_t i;
            uint8_t k = 0;
            uint8_t d;
            qnav_q1_15_t top;
            const qnav_q1_15_t *p;
            if (offset < QNAV_DTHETA_MAX) {
                d = (uint8_t)offset;
                n = (uint8_t)(left < QNAV_DTHETA_MAX - offset ? left : QNAV_DTHETA_MAX - offset);
                p = row + d;
                top = QNAV_FLASH_READ_I16(p);
                for (i = 1; i < n; ++i) {
                    qnav_q1_15_t q = QNAV_FLASH_READ_I16(++p);
                    if (q > top) {
                        top = q;
                        k = i;
                    }
                }
                d = (uint8_t)(d + k);
            } else {
                d = (uint8_t)(QNAV_PATHS - offset);
                n = (uint8_t)(left < QNAV_PATHS - offset ? left : QNAV_PATHS - offset);
                p = row + d;
                top = QNAV_FLASH_READ_I16(p);
                for (i = 1; i < n; ++i) {
                    qnav_q1_15_t q = QNAV_FLASH_READ_I16(--p);
                    if (q >= top) {
                        top = q;
                        k = i;
                    }
                }
                d = (uint8_t)(d - k);
            }
            if (top >= best->q) {
                consider(best, top, (uint16_t)(path + k), d);
            }
            path = (uint16_t)(path + n);
            left = (uint16_t)(left - n);
            offset = (uint16_t)(offset + n);
            if (offset >= QNAV_PATHS) {
                offset = (uint16_t)(offset - QNAV_PATHS);
            }
        }
        if (path >= QNAV_PATHS) {
            return flags;
        }
        phase = (uint16_t)(phase + count * ctrl->n_sectors - QNAV_PATHS);
        count = (uint16_t)(ctrl->sector_paths + (phase + ctrl->sector_span < QNAV_PATHS ? 1u : 0u));
        sector = (uint16_t)(sector + 1u == ctrl->n_sectors ? 0u : sector + 1u);
    }
}

static void eval_prob_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                          qnav_q1_15_t *qualities)
{
    uint8_t k;
    uint8_t dtheta = r->dtheta0;
    for (k = 0; k < r->count; ++k, dtheta = (uint8_t)(dtheta + r->dir)) {
        qnav_q1_15_t q = prob_quality(ctrl, r->level, dtheta);
        if (qualities != 0) {
            qualities[r->first + k] = q;
        }
        consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
}

/* Network: every path of a run; pre-activations walk by one degree's weight per path. */
static void eval_net_run(const qnav_ctrl_t *ctrl, const run_t *r, best_t *best,
                         qnav_q1_15_t *qualities)
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
        qnav_q1_15_t q;
        for (j = 0; j < ctrl->hidden; ++j) {
            const qnav_ctrl_unit_t *u = &ctrl->p.unit[j];
            acc += unit_share(z[j], u->out);
            z[j] = (r->dir > 0) ? z[j] + u->per_deg : z[j] - u->per_deg;
        }
        q = net_output(acc);
        if (qualities != 0) {
            qualities[r->first + k] = q;
        }
        consider(best, q, (uint16_t)(r->first + k), dtheta);
    }
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
        qnav_q1_15_t *row = &table[level * QNAV_TABLE_STRIDE];
        if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
            /* a row is a run of dtheta 0..180: the same integers, by addition */
            run_t r;
            best_t ignore;
            r.first = 0;
            r.count = QNAV_DTHETA_MAX + 1;
            r.level = (uint8_t)level;
            r.dtheta0 = 0;
            r.dir = 1;
            ignore.q = -1;
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

/*
 * Network, first pass: bound every run. Along a run each hidden unit's pre-activation is
 * linear in dtheta, and rounding, saturation, the interpolated sigmoid and the output
 * weight all keep order, so a unit's share is largest at one end, the end where
 * out * z is larger: one sigmoid per unit bounds the whole run. The dtheta term
 * c = per_deg * dtheta is carried from run to run (neighbouring paths differ by one
 * degree) and across a run by precomputed multiples, so the pass multiplies once per
 * unit per run (the level term). Runs beyond cap are evaluated at once (same answer).
 * Returns the number of runs kept in runs[].
 */
/* What bound_runs carries per hidden unit from run to run. */
typedef struct {
    int32_t c;    /* per_deg * dtheta at the end of the previous run */
    int32_t span; /* per_deg * (sector_paths - 1) */
} unit_walk_t;

/* How the dtheta term moves in the current run (see bound_runs). */
typedef struct {
    uint8_t level;
    uint8_t span;     /* paths in the run - 1 */
    uint8_t q1;       /* sector_paths - 1 */
    uint8_t up;       /* dtheta rises along the run */
    uint8_t step_up;  /* the run's first dtheta is above the previous run's last */
    uint8_t first;    /* first run of the step: c starts from dtheta0 */
    uint8_t dtheta0;
} run_walk_t;

/* One unit's largest share over a run; advances its dtheta term to the run's end. */
static inline int32_t bound_unit(const qnav_ctrl_unit_t *u, unit_walk_t *w, const run_walk_t *rw)
{
    int32_t base = unit_base(u, rw->level);
    int32_t c = rw->first ? mul_u8(u->per_deg, rw->dtheta0)
                          : (rw->step_up ? w->c + u->per_deg : w->c - u->per_deg);
    int32_t dz;
    int32_t z0 = base + c;
    int32_t z1;
    if (rw->span == rw->q1) {
        dz = w->span;
    } else if (rw->span == rw->q1 + 1u) {
        dz = w->span + u->per_deg;
    } else {
        dz = mul_u8(u->per_deg, rw->span);
    }
    c = rw->up ? c + dz : c - dz;
    w->c = c;
    z1 = base + c;
    return unit_share(((u->out >= 0) == (z1 > z0)) ? z1 : z0, u->out);
}

/*
 * Network, first pass: bound every run. Along a run each hidden unit's pre-activation is
 * linear in dtheta, and rounding, saturation, the interpolated sigmoid and the output
 * weight all keep order, so a unit's share is largest at one end, the end where
 * out * z is larger: one sigmoid per unit bounds the whole run. The dtheta term
 * c = per_deg * dtheta is carried from run to run (neighbouring paths differ by one
 * degree) and across a run by precomputed multiples, so the pass multiplies once per
 * unit per run (the level term). Runs whose bound is below the best so far are dropped;
 * runs beyond cap are evaluated at once (same answer). Returns the runs kept in runs[].
 */
static uint16_t bound_runs(const qnav_ctrl_t *ctrl, run_iter_t *it, pending_t *runs,
                           uint16_t cap, best_t *best)
{
    unit_walk_t walk[QNAV_MAX_HIDDEN];
    run_walk_t rw;
    uint8_t prev_end = 0;
    uint16_t n = 0;
    uint8_t j;
    run_t r;
    rw.q1 = (uint8_t)(ctrl->sector_paths > 180u ? 179u : ctrl->sector_paths - 1u);
    rw.first = 1;
    for (j = 0; j < ctrl->hidden; ++j) {
        walk[j].span = mul_u8(ctrl->p.unit[j].per_deg, rw.q1);
    }
    while (run_iter_next(it, &r)) {
        int32_t acc = ctrl->out_bias_z;
        qnav_q1_15_t bound;
        rw.level = r.level;
        rw.span = (uint8_t)(r.count - 1u);
        rw.up = (uint8_t)(r.dir > 0);
        rw.step_up = (uint8_t)(r.dtheta0 > prev_end);
        rw.dtheta0 = r.dtheta0;
        for (j = 0; j < ctrl->hidden; ++j) {
            acc += bound_unit(&ctrl->p.unit[j], &walk[j], &rw);
        }
        rw.first = 0;
        prev_end = (uint8_t)(rw.up ? r.dtheta0 + rw.span : r.dtheta0 - rw.span);
        bound = net_output(acc);
        if (r.count == 1u) {
            consider(best, bound, r.first, r.dtheta0); /* the bound is exact */
        } else if (bound < best->q) {
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
            if (runs[i].bound >= 0 && (top == 0 || runs[i].bound > top->bound)) {
                top = &runs[i];
            }
        }
        if (top == 0 || top->bound < best->q) {
            return;
        }
        r.first = top->first;
        r.count = top->count;
        r.level = top->level;
        run_shape(&r, goal);
        eval_net_run(ctrl, &r, best, 0);
        top->bound = -1;
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
static uint8_t net_best(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges, uint16_t goal,
                        best_t *best)
{
    pending_t runs[QNAV_MAX_RUNS];
    run_iter_t it;
    uint16_t n;
    qnav_mm_t range = ranges[qnav_ctrl_sector_of_path(ctrl->n_sectors, goal)];
    /* the path straight at the goal first: a good best prunes runs before they are kept */
    consider(best, net_quality(ctrl, level_of(ctrl, range > ctrl->max_range_mm ?
                                                        ctrl->max_range_mm : range), 0),
             goal, 0);
    run_iter_start(&it, ctrl, ranges, goal);
    n = bound_runs(ctrl, &it, runs, QNAV_MAX_RUNS, best);
    search_runs(ctrl, runs, n, goal, best);
    return it.flags;
}

/* Every path through its run: all qualities, or the probabilistic policy's run ends. */
static uint8_t runs_best(const qnav_ctrl_t *ctrl, const qnav_mm_t *ranges, uint16_t goal,
                         best_t *best, qnav_q1_15_t *qualities)
{
    run_iter_t it;
    run_t r;
    run_iter_start(&it, ctrl, ranges, goal);
    while (run_iter_next(&it, &r)) {
        if (ctrl->kind == QNAV_KIND_TABLE) {
            eval_table_run(ctrl, &r, best, qualities);
        } else if (ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
            eval_net_run(ctrl, &r, best, qualities);
        } else if (qualities != 0) {
            eval_prob_run(ctrl, &r, best, qualities);
        } else {
            prob_run(ctrl, &r, best);
        }
    }
    return it.flags;
}

void qnav_ctrl_step(const qnav_ctrl_t *ctrl, const qnav_ctrl_input_t *in,
                    qnav_ctrl_output_t *out, qnav_q1_15_t *qualities)
{
    best_t best;
    uint16_t goal;
    uint8_t flags;
    uint32_t speed;

    if (out == 0) {
        return;
    }
    if (ctrl == 0 || ctrl->magic != QNAV_CTRL_MAGIC || in == 0 || in->ranges_mm == 0) {
        stop_output(out, QNAV_FLAG_NOT_READY, qualities);
        return;
    }
    best.q = -1;
    best.dtheta = 0;
    best.heading = 0;
    goal = bearing_deg(in->goal_bearing_cdeg);
    if (qualities == 0 && ctrl->kind == QNAV_KIND_TABLE) {
        flags = table_best(ctrl, in->ranges_mm, goal, &best);
    } else if (qualities == 0 && ctrl->kind == (uint8_t)QNAV_POLICY_NET) {
        flags = net_best(ctrl, in->ranges_mm, goal, &best);
    } else {
        flags = runs_best(ctrl, in->ranges_mm, goal, &best, qualities);
    }

    if (best.q <= 0) {
        out->heading_deg = 0;
        out->speed = 0;
        out->quality = 0;
        out->flags = (uint8_t)(flags | QNAV_FLAG_NO_PATH);
        return;
    }
    speed = ((uint32_t)best.q * ctrl->speed_scale) >> 15;
    if (best.q >= ctrl->full_speed_quality || speed > QNAV_Q1_15_MAX) {
        speed = QNAV_Q1_15_MAX;
        flags |= QNAV_FLAG_FULL_SPEED;
    }
    out->heading_deg = best.heading;
    out->speed = (qnav_q1_15_t)speed;
    out->quality = best.q;
    out->flags = flags;
}
