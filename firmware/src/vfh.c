/*
 * VFH+ (Ulrich & Borenstein 1998) on libqnav's sector readings; see qnav/vfh.h. The polar
 * obstacle density of a 1-degree direction is the distance level of the nearest reading
 * whose arc, enlarged by asin((r + d_s) / D), covers it (clearance.c: VFH+'s enlargement,
 * written once for both controllers); VFH+'s magnitude a - b d is linear in distance, so
 * its thresholds tau_low / tau_high are distances here. Integer arithmetic only.
 */
#include "qnav/vfh.h"
#include <string.h>
#include "clearance.h"
#include "ctrl_internal.h"
#include "escape.h"
#include "vfh_plain.h"

#if !QNAV_WITH_VFH
#error "vfh.c is left out of the build when QNAV_WITH_VFH is 0 (qnav/qnav_config.h)"
#endif

#define QNAV_VFH_MAGIC 0x5646u

void qnav_vfh_config_default(qnav_vfh_config_t *cfg)
{
    if (cfg == 0) {
        return;
    }
    qnav_ctrl_config_default(&cfg->body);
    cfg->sector_deg = 5u;
    cfg->blocked_mm = 0u; /* scaled with the body at init */
    cfg->clear_mm = 0u;
    cfg->wide_sectors = 16u;
    cfg->mu_goal = 5u;
    cfg->mu_current = 2u;
    cfg->mu_prev = 2u;
    cfg->slow_mm = 0u;
}

/* tau_high scaled with the body (QNAV_VFH_BLOCKED_BODIES), at least 100 mm. */
static uint32_t body_blocked_mm(const qnav_ctrl_config_t *body)
{
    const uint32_t enlarge = (uint32_t)body->body_radius_mm + body->safety_mm;
    const uint32_t b = enlarge * QNAV_VFH_BLOCKED_BODIES / 10u;
    return b < 100u ? 100u : b;
}

static uint8_t level_at(const qnav_clearance_t *c, qnav_mm_t mm)
{
    return qnav_clearance_level_of(c, mm > c->max_range_mm ? c->max_range_mm : mm);
}

static qnav_mm_t clamp_mm(uint32_t mm)
{
    return (qnav_mm_t)(mm > UINT16_MAX ? UINT16_MAX : mm);
}

qnav_status_t qnav_vfh_init(qnav_vfh_t *vfh, const qnav_vfh_config_t *cfg)
{
    qnav_status_t st;
    uint32_t blocked, clear, slow;
    if (vfh == 0) {
        return QNAV_E_NULL;
    }
    vfh->magic = 0u;
    if (cfg == 0) {
        return QNAV_E_NULL;
    }
    st = qnav_clearance_setup(&vfh->clr, &cfg->body);
    if (st == QNAV_OK) {
        st = qnav_escape_setup(&vfh->clr, &cfg->body);
    }
    if (st != QNAV_OK) {
        return st;
    }
    blocked = cfg->blocked_mm != 0u ? cfg->blocked_mm : body_blocked_mm(&cfg->body);
    clear = cfg->clear_mm != 0u ? cfg->clear_mm : blocked * 14u / 10u;
    slow = cfg->slow_mm != 0u ? cfg->slow_mm : blocked * 2u;
    if (cfg->sector_deg < 1u || cfg->sector_deg > 30u || QNAV_PATHS % cfg->sector_deg != 0u ||
        clear < blocked || cfg->wide_sectors < 1u || cfg->wide_sectors > 180u) {
        return QNAV_E_VFH_PARAM;
    }
    vfh->sector_deg = cfg->sector_deg;
    vfh->n_hist = (uint16_t)(QNAV_PATHS / cfg->sector_deg);
    vfh->level_blocked = level_at(&vfh->clr, clamp_mm(blocked));
    vfh->level_clear = level_at(&vfh->clr, clamp_mm(clear));
    vfh->level_slow = level_at(&vfh->clr, clamp_mm(slow));
    if (vfh->level_slow == 0u) {
        vfh->level_slow = 1u;
    }
    vfh->wide_sectors = cfg->wide_sectors;
    vfh->mu_goal = cfg->mu_goal;
    vfh->mu_current = cfg->mu_current;
    vfh->mu_prev = cfg->mu_prev;
    vfh->magic = QNAV_VFH_MAGIC;
    return QNAV_OK;
}

void qnav_vfh_state_reset(qnav_vfh_state_t *state)
{
    uint16_t i;
    if (state == 0) {
        return;
    }
    for (i = 0; i < sizeof state->blocked; ++i) {
        state->blocked[i] = 0u;
    }
}

static uint16_t wrap360(uint16_t d)
{
    return (uint16_t)(d >= QNAV_PATHS ? d - QNAV_PATHS : d);
}

static uint16_t angle_dist(uint16_t a, uint16_t b)
{
    return qnav_angle_dist_deg(a, b);
}

static uint8_t is_blocked(const qnav_vfh_state_t *st, uint16_t k)
{
    return (uint8_t)((st->blocked[k >> 3] & (uint8_t)(1u << (k & 7u))) != 0u);
}

static void set_blocked(qnav_vfh_state_t *st, uint16_t k, uint8_t b)
{
    uint8_t bit = (uint8_t)(1u << (k & 7u));
    st->blocked[k >> 3] = (uint8_t)(b ? (st->blocked[k >> 3] | bit)
                                      : (st->blocked[k >> 3] & (uint8_t)~bit));
}

/* The least level (densest) of the n paths from p on (p < 720: wrapping past 359). */
static uint8_t least_level(const uint8_t *lvl, uint16_t p, uint8_t n)
{
    uint8_t low = (uint8_t)(QNAV_DIST_LEVELS - 1u);
    uint8_t i;
    for (i = 0; i < n; ++i) {
        uint8_t l = lvl[wrap360(p)];
        if (l < low) {
            low = l;
        }
        ++p;
    }
    return low;
}

/* On x86 hosts a sector's least level takes sixteen levels an instruction (least_level16),
 * from the levels with their first 32 repeated after path 359 so that no window wraps;
 * qnav_vfh_histogram_plain() keeps least_level() there for the tests, and the other
 * targets have only it. */
#if defined(QNAV_LEVELS_SSE2)
/* Bytes t >= n of a window loaded at past_n + 16 - n are 0xFF (nothing under min), the
 * others 0 (nothing under max). */
static const uint8_t past_n[32] = {
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
};

/* least_level() of the n paths (1..30) from ext + p on, ext the levels and their first 32
 * again: one window of 16 with the bytes past n raised to 0xFF, or two that overlap
 * (taking a level twice leaves the least as it was). */
static uint8_t least_level16(const uint8_t *ext, uint16_t p, uint8_t n)
{
    const uint8_t *q = ext + (p >= QNAV_PATHS ? p - QNAV_PATHS : p);
    __m128i v = n >= 16u ? _mm_min_epu8(qnav_levels16(q), qnav_levels16(q + n - 16u))
                         : _mm_max_epu8(qnav_levels16(q), qnav_levels16(past_n + 16u - n));
    uint8_t low;
    v = _mm_min_epu8(v, _mm_srli_si128(v, 8));
    v = _mm_min_epu8(v, _mm_srli_si128(v, 4));
    v = _mm_min_epu8(v, _mm_srli_si128(v, 2));
    v = _mm_min_epu8(v, _mm_srli_si128(v, 1));
    low = (uint8_t)_mm_cvtsi128_si32(v);
    return low < QNAV_DIST_LEVELS - 1u ? low : (uint8_t)(QNAV_DIST_LEVELS - 1u);
}
#define LEAST_LEVEL(lvl, ext, p, n, plain)                                                   \
    ((plain) ? least_level(lvl, p, n) : least_level16(ext, p, n))
#define PLAIN_PARAM , int plain
#define PLAIN_ARG(p) , (p)
#else
#define LEAST_LEVEL(lvl, ext, p, n, plain) least_level(lvl, p, n)
#define PLAIN_PARAM
#define PLAIN_ARG(p)
#endif

/*
 * The binary histogram: sector k (centred on k * alpha) takes the lowest level (densest)
 * of its alpha paths; below level_blocked it is blocked, at or above level_clear free, in
 * between as last tick. Returns the number of blocked sectors.
 */
static uint16_t binary_histogram(const qnav_vfh_t *v, qnav_vfh_state_t *st, const uint8_t *lvl
                                 PLAIN_PARAM)
{
    uint16_t k;
    uint16_t n_blocked = 0;
    uint16_t half = (uint16_t)(v->sector_deg / 2u);
#if defined(QNAV_LEVELS_SSE2)
    uint8_t ext[QNAV_PATHS + 32u];
    memcpy(ext, lvl, QNAV_PATHS);
    memcpy(ext + QNAV_PATHS, lvl, 32u);
#endif
    for (k = 0; k < v->n_hist; ++k) {
        uint16_t p = (uint16_t)((uint16_t)(k * v->sector_deg) + QNAV_PATHS - half);
        uint8_t low = LEAST_LEVEL(lvl, ext, p, v->sector_deg, plain);
        if (low < v->level_blocked) {
            set_blocked(st, k, 1u);
        } else if (low >= v->level_clear) {
            set_blocked(st, k, 0u);
        }
        n_blocked = (uint16_t)(n_blocked + is_blocked(st, k));
    }
    return n_blocked;
}

#if defined(QNAV_LEVELS_SSE2)
uint16_t qnav_vfh_histogram(const qnav_vfh_t *v, qnav_vfh_state_t *st, const uint8_t *lvl)
{
    return binary_histogram(v, st, lvl, 0);
}

uint16_t qnav_vfh_histogram_plain(const qnav_vfh_t *v, qnav_vfh_state_t *st, const uint8_t *lvl)
{
    return binary_histogram(v, st, lvl, 1);
}
#endif

/* The candidate of least cost so far. */
typedef struct {
    uint32_t cost;
    uint16_t dir;     /* degrees 0..359 */
    uint8_t any;
} choice_t;

static void offer(const qnav_vfh_t *v, choice_t *c, uint16_t dir, uint16_t goal, uint16_t prev)
{
    uint32_t cost = (uint32_t)v->mu_goal * angle_dist(dir, goal) +
                    (uint32_t)v->mu_current * angle_dist(dir, 0u) +
                    (uint32_t)v->mu_prev * angle_dist(dir, prev);
    if (c->any) {
        uint16_t turn = angle_dist(dir, 0u);
        uint16_t best_turn = angle_dist(c->dir, 0u);
        if (cost > c->cost) {
            return;
        }
        /* equal cost: the smaller turn, then counter-clockwise (dir in 1..180) */
        if (cost == c->cost && (turn > best_turn || (turn == best_turn && dir > 180u))) {
            return;
        }
    }
    c->cost = cost;
    c->dir = dir;
    c->any = 1u;
}

/* The candidates of one gap of n free sectors starting at sector first. */
static void gap(const qnav_vfh_t *v, choice_t *c, uint16_t first, uint16_t n, uint16_t goal,
                    uint16_t prev)
{
    uint16_t right = (uint16_t)(first * v->sector_deg);
    uint16_t span = (uint16_t)((n - 1u) * v->sector_deg); /* right to left border, deg */
    uint16_t side = (uint16_t)((uint16_t)v->wide_sectors * v->sector_deg / 2u);
    uint16_t goal_off;
    if (n <= v->wide_sectors) {
        offer(v, c, wrap360((uint16_t)(right + span / 2u)), goal, prev);
        return;
    }
    offer(v, c, wrap360((uint16_t)(right + side)), goal, prev);
    offer(v, c, wrap360((uint16_t)(right + span - side)), goal, prev);
    goal_off = (uint16_t)(goal >= right ? goal - right : goal + QNAV_PATHS - right);
    if (goal_off >= side && goal_off + side <= span) {
        offer(v, c, goal, goal, prev);
    }
}

/* Walk the circle from a blocked sector and offer every gap's candidates. */
static void gaps(const qnav_vfh_t *v, const qnav_vfh_state_t *st, choice_t *c,
                     uint16_t goal, uint16_t prev)
{
    uint16_t start = 0;
    uint16_t i;
    uint16_t run_first = 0;
    uint16_t run_n = 0;
    while (!is_blocked(st, start)) {
        ++start;
    }
    for (i = 1; i <= v->n_hist; ++i) {
        uint16_t k = (uint16_t)((start + i) % v->n_hist);
        if (!is_blocked(st, k)) {
            if (run_n == 0u) {
                run_first = k;
            }
            ++run_n;
        } else if (run_n != 0u) {
            gap(v, c, run_first, run_n, goal, prev);
            run_n = 0;
        }
    }
}

static void stop(qnav_ctrl_output_t *out, uint8_t flags)
{
    out->heading_deg = 0;
    out->speed = 0;
    out->quality = 0;
    out->flags = flags;
    qnav_escape_clear(&out->escape);
}

void qnav_vfh_step(const qnav_vfh_t *vfh, qnav_vfh_state_t *state, const qnav_ctrl_input_t *in,
                   qnav_ctrl_output_t *out)
{
    uint8_t lvl[QNAV_PATHS];
    choice_t c;
    uint8_t flags;
    uint16_t goal;
    uint16_t n_blocked;
    uint8_t l;
    qnav_q1_15_t speed;
    qnav_q1_15_t cap;
    qnav_escape_t esc;
    if (out == 0) {
        return;
    }
    if (vfh == 0 || vfh->magic != QNAV_VFH_MAGIC || state == 0 || in == 0 ||
        in->ranges_mm == 0) {
        stop(out, QNAV_FLAG_NOT_READY);
        return;
    }
    flags = qnav_clearance_input_levels(&vfh->clr, in, lvl);
    goal = qnav_escape_goal(&vfh->clr, lvl, in, &esc);
    n_blocked = binary_histogram(vfh, state, lvl PLAIN_ARG(0));
    if (n_blocked == vfh->n_hist) {
        stop(out, (uint8_t)(flags | QNAV_FLAG_NO_PATH));
        out->escape = esc;
        qnav_escape_keep_moving(&vfh->clr, lvl, &esc, goal, out);
        qnav_escape_unstand(&vfh->clr, lvl, qnav_whole_deg(in->prev_heading_cdeg), out);
        qnav_escape_hold_turn(qnav_whole_deg(in->prev_heading_cdeg), out);
        return;
    }
    c.any = 0u;
    c.cost = 0u;
    c.dir = 0u;
    if (n_blocked == 0u) {
        c.dir = goal; /* one gap all round: the goal is its own candidate */
    } else {
        gaps(vfh, state, &c, goal, qnav_whole_deg(in->prev_heading_cdeg));
    }
    /* speed falls linearly with the chosen direction's density, then the speed guard */
    l = lvl[c.dir];
    if (l >= vfh->level_slow) {
        speed = QNAV_Q1_15_MAX;
        flags |= QNAV_FLAG_FULL_SPEED;
    } else {
        speed = (qnav_q1_15_t)(((uint32_t)l * QNAV_Q1_15_MAX) / vfh->level_slow);
    }
    out->quality = speed;
    cap = qnav_clearance_turn_cap(&vfh->clr, lvl, c.dir);
    if (speed > cap) {
        speed = cap;
        flags |= QNAV_FLAG_SPEED_GUARD;
    }
    out->heading_deg = qnav_signed_deg(c.dir);
    out->speed = speed;
    out->flags = flags;
    out->escape = esc;
    qnav_escape_keep_moving(&vfh->clr, lvl, &esc, goal, out);
    qnav_escape_unstand(&vfh->clr, lvl, qnav_whole_deg(in->prev_heading_cdeg), out);
    qnav_escape_hold_turn(qnav_whole_deg(in->prev_heading_cdeg), out);
}
