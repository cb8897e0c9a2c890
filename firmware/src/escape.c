/*
 * Leaving dead ends: the boundary follower in front of every path controller (escape.h;
 * docs/architecture.md, "Leaving dead ends"). Integer arithmetic only, a few hundred byte
 * compares a tick.
 */
#include "escape.h"

#include <stddef.h>

#include "clearance.h"
#include "ctrl_internal.h"

/* Crawl speed while following a boundary whose policy would stand still: 1/4 of v_max. */
#define QNAV_ESCAPE_CRAWL ((qnav_q1_15_t)8192)
/* A stall this many margins (r + d_s) nearer to the destination than where the last
 * follow ended is at another obstacle: its side is chosen afresh. */
#define QNAV_ESCAPE_NEW_MARGINS 4u
/* A side is given up once it has led this many margins (r + d_s) farther from the
 * destination (twice as far for each try given up) while the side away from the boundary
 * was open beyond QNAV_ESCAPE_OPEN_MARGINS, over the sectors within
 * QNAV_ESCAPE_OPEN_HALF_DEG of the path 90 degrees away from the boundary. */
#define QNAV_ESCAPE_AWAY_MARGINS 14u
#define QNAV_ESCAPE_OPEN_MARGINS 9u
#define QNAV_ESCAPE_OPEN_HALF_DEG 11
/* Longest follow, in ticks, however many tries were given up (about 109 s). */
#define QNAV_ESCAPE_MAX_FOLLOW 1092u
/* A lost boundary is approached until a path clears its nearest reading by this many levels. */
#define QNAV_ESCAPE_SKIRT_STEP 3u
/* Nearer the boundary than half the follow level: this many degrees more away per level. */
#define QNAV_ESCAPE_AWAY_DEG 10
/* The leave rule's clear way is the shortest reading within this many degrees of the
 * destination's bearing (way_opened). */
#define QNAV_ESCAPE_LEAVE_HALF_DEG 11

qnav_status_t qnav_escape_setup(qnav_clearance_t *c, const qnav_ctrl_config_t *cfg)
{
    qnav_mm_t follow = cfg->escape_follow_mm < c->max_range_mm ? cfg->escape_follow_mm
                                                              : c->max_range_mm;
    c->esc_stall_ticks = cfg->escape_stall_ticks;
    c->esc_free_level = qnav_clearance_level_of(c, follow);
    c->esc_follow_ticks = (uint16_t)(cfg->escape_follow_s * 10u);
    if (c->esc_follow_ticks == 0u || c->esc_follow_ticks > QNAV_ESCAPE_MAX_FOLLOW) {
        c->esc_follow_ticks = QNAV_ESCAPE_MAX_FOLLOW;
    }
    return QNAV_OK;
}

static uint16_t wrap(int16_t p)
{
    while (p < 0) {
        p = (int16_t)(p + (int16_t)QNAV_PATHS);
    }
    while (p >= (int16_t)QNAV_PATHS) {
        p = (int16_t)(p - (int16_t)QNAV_PATHS);
    }
    return (uint16_t)p;
}

static uint8_t blocked(const qnav_clearance_t *c, const uint8_t *lvl, int16_t p)
{
    return (uint8_t)(lvl[wrap(p)] < c->esc_free_level);
}

/* The lowest level on side s's boundary half (from straight ahead round to straight
 * behind, ends excluded), and in *at the first path that has it (left as it was when the
 * half is all at 255). */
#if defined(QNAV_LEVELS_SSE2)
/* On x86 hosts sixteen levels at a time: the half's lowest level by windows (the last
 * overlapping the one before it; a minimum does not mind a byte seen twice), then the
 * windows in the walk's order until one holds it, its first byte that does in that order.
 * The same level and path as the byte walk below (test_escape, the shared vectors). */
static uint8_t nearest_on_side(const uint8_t *lvl, int8_t s, int16_t *at)
{
    const uint8_t *lo = s < 0 ? lvl + 1 : lvl + QNAV_PATHS - (QNAV_DTHETA_MAX - 1u);
    const uint8_t *last = lo + (QNAV_DTHETA_MAX - 1u) - 16u; /* the last window */
    const uint8_t *q;
    __m128i m = qnav_levels16(last);
    uint8_t lw;
    for (q = lo; q < last; q += 16) {
        m = _mm_min_epu8(m, qnav_levels16(q));
    }
    m = _mm_min_epu8(m, _mm_srli_si128(m, 8));
    m = _mm_min_epu8(m, _mm_srli_si128(m, 4));
    m = _mm_min_epu8(m, _mm_srli_si128(m, 2));
    m = _mm_min_epu8(m, _mm_srli_si128(m, 1));
    lw = (uint8_t)_mm_cvtsi128_si32(m);
    if (lw == 255u) {
        return lw; /* as the byte walk: *at left as it was */
    }
    m = _mm_set1_epi8((char)lw);
    /* upward (s < 0) the lowest path that has it, downward from 359 the highest; the
     * windows cover the half, so one of them holds it */
    for (q = s < 0 ? lo : last;; q = s < 0 ? (q + 16 < last ? q + 16 : last)
                                          : (q - 16 > lo ? q - 16 : lo)) {
        const unsigned hit = (unsigned)_mm_movemask_epi8(_mm_cmpeq_epi8(qnav_levels16(q), m));
        if (hit != 0u) {
            *at = s < 0 ? (int16_t)((q - lvl) + __builtin_ctz(hit))
                        : (int16_t)((q - lvl) + (31 - __builtin_clz(hit)) - (int16_t)QNAV_PATHS);
            return lw;
        }
        if (q == (s < 0 ? last : lo)) {
            return lw;
        }
    }
}
#else
static uint8_t nearest_on_side(const uint8_t *lvl, int8_t s, int16_t *at)
{
    /* path -s * k for k = 1..179: upward from path 1 (s = -1) or downward from 359 */
    const int8_t step = (int8_t)-s;
    const uint8_t *q = s < 0 ? lvl + 1 : lvl + QNAV_PATHS - 1;
    uint8_t lw = 255u;
    int16_t k;
    for (k = 1; k < (int16_t)QNAV_DTHETA_MAX; ++k, q += step) {
        if (*q < lw) {
            lw = *q;
            *at = (int16_t)(step * k);
        }
    }
    return lw;
}
#endif

/* The least k in 1..359 such that path from + s * k (round the circle) has a level of at
 * least need; 0 when none has: one walk along the bytes that jumps at the wrap, where a
 * wrapped index per path cost the host two thirds of the follow's instructions. */
static int16_t first_at_least(const uint8_t *lvl, int16_t from, int8_t s, uint8_t need)
{
    const uint16_t p0 = wrap((int16_t)(from + s));
    /* paths up to the wrap: p0..359 upward, or p0..0 downward */
    const int16_t before = s > 0 ? (int16_t)(QNAV_PATHS - p0) : (int16_t)(p0 + 1u);
    const uint8_t *q = lvl + p0;
    int16_t k;
    for (k = 1; k < (int16_t)QNAV_PATHS; ++k, q += s) {
        if (k == before + 1) {
            q = s > 0 ? lvl : lvl + QNAV_PATHS - 1;
        }
        if (*q >= need) {
            return k;
        }
    }
    return 0;
}

/*
 * The free path that skirts the boundary on side s (+1: obstacle on the right, the robot
 * goes round it counter-clockwise; -1: mirrored). Reference: the nearest reading on that
 * side (the lowest level from straight ahead round to straight behind), so the choice
 * moves with the boundary, not with the last command. From it, turning away from the
 * side, the first path whose level clears the follow level, or the nearest reading by a
 * step when that is farther (the boundary was lost: turn back toward it). A reading placed
 * on the central part of its wedge (wedge_pct) may lie anywhere in the edge the placement
 * left free, and a follow drives tangent to what it sees: the skirt keeps half that edge
 * more away (docs/architecture.md, "The follow keeps half the shaved edge away").
 */
static uint16_t skirt(const qnav_clearance_t *c, const uint8_t *lvl, int8_t s)
{
    int16_t w = (int16_t)(-90 * s);
    uint8_t lw = nearest_on_side(lvl, s, &w);
    uint8_t need;
    int16_t k;
    need = (uint8_t)(lw + QNAV_ESCAPE_SKIRT_STEP);
    if (need < c->esc_free_level) {
        need = c->esc_free_level;
    }
    if (need > QNAV_DIST_LEVELS - 1u) {
        need = QNAV_DIST_LEVELS - 1u;
    }
    k = first_at_least(lvl, w, s, need);
    if (k != 0) {
        /* nearer than half the follow level: a little more away from the boundary */
        uint8_t half = (uint8_t)(c->esc_free_level / 2u);
        int16_t off = lw < half ? (int16_t)((half - lw) * QNAV_ESCAPE_AWAY_DEG) : 0;
        if (lw >= c->wedge_near_level) {
            off = (int16_t)(off + (int16_t)(c->wedge_shrink / 2u));
        }
        return wrap((int16_t)(w + s * (k + off)));
    }
    return wrap(180);
}

/* The side to follow: the one whose nearest free path to the goal is the nearer turn
 * (counter-clockwise, i.e. going round with the obstacle on the right, on a tie). */
static int8_t choose_side(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t goal)
{
    int16_t g = (int16_t)goal;
    int16_t k;
    for (k = 0; k <= (int16_t)QNAV_DTHETA_MAX; ++k) {
        if (!blocked(c, lvl, (int16_t)(g + k))) {
            return 1;
        }
        if (!blocked(c, lvl, (int16_t)(g - k))) {
            return -1;
        }
    }
    return 1;
}

/* How near the destination (range_mm away) the clear way toward it ends: range less how
 * far the robot's centre can go toward it before its margin reaches the shortest reading
 * of the sectors that look within half_deg of it (0: the one sector under the bearing;
 * the result 0: the destination is in plain view). The sectors' readings, not the paths'
 * painted levels: with readings placed on the central part of their wedge (wedge_pct) the
 * paths between sector centres are left clear at long range. */
static uint16_t rest_mm(const qnav_clearance_t *c, const qnav_ctrl_input_t *in, uint16_t goal,
                        uint16_t range_mm, int16_t half_deg)
{
    uint16_t s = qnav_ctrl_sector_of_path(c->n_sectors, wrap((int16_t)((int16_t)goal - half_deg)));
    uint16_t last = qnav_ctrl_sector_of_path(c->n_sectors, wrap((int16_t)((int16_t)goal + half_deg)));
    uint32_t r = in->ranges_mm[last];
    uint32_t clear_mm;
    for (; s != last; s = (uint16_t)(s + 1u == c->n_sectors ? 0u : s + 1u)) {
        if (in->ranges_mm[s] < r) {
            r = in->ranges_mm[s];
        }
    }
    r = (r < c->max_range_mm ? r : c->max_range_mm) + c->sensor_offset_mm;
    clear_mm = r > c->margin_mm ? r - c->margin_mm : 0u;
    return (uint16_t)(range_mm > clear_mm ? range_mm - clear_mm : 0u);
}

static uint16_t follow_limit(const qnav_clearance_t *c, uint8_t tries)
{
    uint16_t t = c->esc_follow_ticks;
    while (tries-- != 0u && t < QNAV_ESCAPE_MAX_FOLLOW) {
        t = (uint16_t)(2u * t);
    }
    return t < QNAV_ESCAPE_MAX_FOLLOW ? t : QNAV_ESCAPE_MAX_FOLLOW;
}

/* Getting nearer by half a margin (r + d_s) counts as progress toward the destination. */
static uint16_t progress_mm(const qnav_clearance_t *c)
{
    return (uint16_t)(c->margin_mm / 2u);
}

/* DistBug's leave rule (Kamon & Rivlin 1997): the clear way toward the destination ends
 * nearer to it, by a step, than it did at the hit point. Read over the sectors within
 * QNAV_ESCAPE_LEAVE_HALF_DEG of the bearing, not only the one under it: a bearing that
 * wobbles across a sector boundary (a noisy compass) must not see a longer way on one tick
 * than is there, or the robot leaves and drives back into the pocket it is leaving. The one
 * sector under the bearing still leaves when it sees far past the hit (by
 * QNAV_ESCAPE_NEW_MARGINS margins, more than a neighbour's wall can fake): the end of a bar
 * seen past its corner (docs/architecture.md, "Leaving"). */
static uint8_t way_opened(const qnav_clearance_t *c, const qnav_ctrl_input_t *in,
                          const qnav_escape_t *e, uint16_t goal, uint16_t range)
{
    return (uint8_t)((uint32_t)rest_mm(c, in, goal, range, QNAV_ESCAPE_LEAVE_HALF_DEG) +
                             progress_mm(c) <= e->hit_mm ||
                     (uint32_t)rest_mm(c, in, goal, range, 0) +
                             QNAV_ESCAPE_NEW_MARGINS * c->margin_mm <= e->hit_mm);
}

static void grow_mm(uint16_t *v, uint16_t d)
{
    if (*v != 0u) {
        *v = (uint16_t)((uint32_t)*v + d > 65535u ? 65535u : *v + d);
    }
}

void qnav_escape_grow(qnav_escape_t *e, uint16_t d_mm)
{
    if (e == NULL || d_mm == 0u) {
        return;
    }
    grow_mm(&e->best_mm, d_mm);
    grow_mm(&e->hit_mm, d_mm);
    grow_mm(&e->stall_mm, d_mm);
    grow_mm(&e->near_mm, d_mm);
    grow_mm(&e->loop_mm, d_mm);
    grow_mm(&e->from_mm, d_mm);
    grow_mm(&e->over_mm, d_mm);
    grow_mm(&e->prev_mm, d_mm);
}

void qnav_escape_follow_plan(qnav_escape_t *e, int clear, uint16_t grow_mm)
{
    if (e == NULL) {
        return;
    }
    if (clear) {
        const uint8_t stood = e->stood; /* a new plan does not move the robot */
        qnav_escape_clear(e);
        e->stood = stood;
    } else {
        qnav_escape_grow(e, grow_mm);
    }
}

void qnav_escape_clear(qnav_escape_t *e)
{
    e->best_mm = 0u;
    e->hit_mm = 0u;
    e->ticks = 0u;
    e->side = 0;
    e->last_side = 0;
    e->tries = 0u;
    e->stood = 0u;
    e->stall_mm = 0u;
    e->near_mm = 0u;
    e->loop_mm = 0u;
    e->loop_deg2 = 0u;
    e->loop = QNAV_ESCAPE_LOOP_NONE;
    e->from_mm = 0u;
    e->over_mm = 0u;
    e->prev_mm = 0u;
}

static uint16_t diff_mm(uint16_t a, uint16_t b)
{
    return (uint16_t)(a > b ? a - b : b - a);
}

/*
 * Has this follow gone round its obstacle (an island: a box in a room)? Without a position,
 * a place on the boundary is known by the destination's range and bearing there (the robot
 * passes it again heading the same way): marked escape_stall_ticks into the follow, left
 * once the range differs by 2 (r + d_s), back when it is within (r + d_s) and the bearing
 * within 30 degrees. Returns 1 when the robot, having gone round, is as near the
 * destination as it came on the way round (Bug1's leave point).
 */
static uint8_t gone_round(const qnav_clearance_t *c, qnav_escape_t *e, uint16_t range,
                          uint16_t bearing)
{
    uint8_t b2 = (uint8_t)(bearing / 2u);
    uint8_t off_deg = qnav_angle_dist_deg((uint16_t)(2u * b2), (uint16_t)(2u * e->loop_deg2));
    if (range < e->near_mm) {
        e->near_mm = range;
    }
    switch (e->loop) {
    case QNAV_ESCAPE_LOOP_NONE:
        if (e->ticks >= c->esc_stall_ticks) {
            e->loop_mm = range;
            e->loop_deg2 = b2;
            e->loop = QNAV_ESCAPE_LOOP_MARKED;
        }
        return 0u;
    case QNAV_ESCAPE_LOOP_MARKED:
        if (diff_mm(range, e->loop_mm) > 2u * c->margin_mm) {
            e->loop = QNAV_ESCAPE_LOOP_AWAY;
        }
        return 0u;
    case QNAV_ESCAPE_LOOP_AWAY:
        if (diff_mm(range, e->loop_mm) <= c->margin_mm && off_deg <= 30u) {
            e->loop = QNAV_ESCAPE_LOOP_ROUND;
        }
        return 0u;
    default:
        return (uint8_t)((uint32_t)range <= (uint32_t)e->near_mm + progress_mm(c));
    }
}

static void start_follow(qnav_escape_t *e, int8_t side, uint16_t range)
{
    e->side = side;
    e->last_side = side;
    e->ticks = 0u;
    e->near_mm = range;
    e->loop = QNAV_ESCAPE_LOOP_NONE;
    e->from_mm = range;
    e->over_mm = 0u;
    e->prev_mm = range;
}

/* The nearest reading on side s's away hand: the sectors whose wedges meet the span of
 * QNAV_ESCAPE_OPEN_HALF_DEG either side of the path 90 degrees away from the boundary, so
 * that "open" means the same at every sector count (one 22.5-degree sector at 16 sectors,
 * three 11.25-degree ones at 32). */
static qnav_mm_t away_open_mm(const qnav_clearance_t *c, const qnav_ctrl_input_t *in, int8_t s)
{
    int16_t centre = (int16_t)(90 * s);
    uint16_t k = qnav_ctrl_sector_of_path(c->n_sectors,
                                          wrap((int16_t)(centre - QNAV_ESCAPE_OPEN_HALF_DEG)));
    uint16_t last = qnav_ctrl_sector_of_path(c->n_sectors,
                                             wrap((int16_t)(centre + QNAV_ESCAPE_OPEN_HALF_DEG)));
    qnav_mm_t m = in->ranges_mm[k];
    while (k != last) {
        k = (uint16_t)(k + 1u == c->n_sectors ? 0u : k + 1u);
        if (in->ranges_mm[k] < m) {
            m = in->ranges_mm[k];
        }
    }
    return m;
}

/*
 * Has this side led away? Following a long wall the wrong way (its gap lies behind) takes
 * the robot round the arena's corner, ever farther from the destination through open
 * space; a time limit alone lets it go on for the whole try. A side is given up once the
 * robot has got QNAV_ESCAPE_AWAY_MARGINS margins (doubled per try given up) farther from
 * the destination while the side away from the boundary was open beyond
 * QNAV_ESCAPE_OPEN_MARGINS: what the range grows by while that side is closed does not
 * count (from_mm moves with it). In a corridor or a pocket the way out leads away from the
 * destination first, between walls on both hands, and the away hand opens only at a turn,
 * which is the way on: giving the side up there only returns to the dead end (at 32
 * sectors, where one sector sees through a corridor's turn, a budget counted from where
 * the side began turned the robot back at every turn: docs/results.md).
 */
static uint8_t led_away(const qnav_clearance_t *c, const qnav_ctrl_input_t *in,
                        qnav_escape_t *e, uint16_t range)
{
    uint32_t open_mm = (uint32_t)away_open_mm(c, in, e->side) + c->sensor_offset_mm;
    uint8_t shift = e->tries < 6u ? e->tries : 6u;
    uint32_t budget = ((uint32_t)QNAV_ESCAPE_AWAY_MARGINS * c->margin_mm) << shift;
    uint16_t prev = e->prev_mm;
    e->prev_mm = range;
    if (open_mm < (uint32_t)QNAV_ESCAPE_OPEN_MARGINS * c->margin_mm) {
        /* what the range changed by while the away hand was closed does not count */
        int32_t f = (int32_t)e->from_mm + (int32_t)range - (int32_t)prev;
        e->from_mm = (uint16_t)(f < 0 ? 0 : (f > 65535 ? 65535 : f));
        return 0u;
    }
    return (uint8_t)((uint32_t)range > (uint32_t)e->from_mm + budget);
}

/*
 * Is this side's time up? Past follow_limit the follow goes on while the robot still gets
 * nearer to the destination (by half a margin within escape_stall_ticks, as while going):
 * a follow rounding the far end of a long wall toward the destination is not turned back
 * at its last corner.
 */
static uint8_t time_up(const qnav_clearance_t *c, qnav_escape_t *e, uint16_t range)
{
    uint16_t limit = follow_limit(c, e->tries);
    uint16_t progress = progress_mm(c);
    if (++e->ticks < limit) {
        return 0u;
    }
    if (e->over_mm == 0u || (uint32_t)range + progress <= e->over_mm) {
        e->over_mm = range;
        e->ticks = limit > c->esc_stall_ticks ? (uint16_t)(limit - c->esc_stall_ticks) : 0u;
        return 0u;
    }
    return 1u;
}

uint16_t qnav_escape_goal(const qnav_clearance_t *c, const uint8_t *lvl,
                          const qnav_ctrl_input_t *in, qnav_escape_t *e)
{
    uint16_t goal = qnav_whole_deg(in->goal_bearing_cdeg);
    uint16_t range = in->goal_range_mm;
    uint16_t progress = progress_mm(c);
    *e = in->escape;
    if (c->esc_stall_ticks == 0u || range == 0u) {
        qnav_escape_clear(e);
        return goal;
    }
    if (e->side != 0) {
        uint8_t round = gone_round(c, e, range, goal);
        if (round != 0u || (way_opened(c, in, e, goal, range) != 0u &&
                            !blocked(c, lvl, (int16_t)goal))) {
            if (round != 0u) {
                e->last_side = 0; /* gone round an island: the next stall chooses afresh */
                e->stall_mm = 0u;
            }
            e->side = 0;
            e->hit_mm = range; /* where this follow ended: a stall far nearer is a new obstacle */
            e->best_mm = range;
            e->ticks = 0u;
            if (round != 0u) {
                e->tries = 0u;
            } /* else the tries are kept until the next stall: a side given up stays given up */
            return goal;
        }
        if (time_up(c, e, range) != 0u || led_away(c, in, e, range) != 0u) {
            start_follow(e, (int8_t)-e->side, range); /* give this side up: the other, for longer */
            if (e->tries < 255u) {
                ++e->tries;
            }
        }
        return skirt(c, lvl, e->side);
    }
    if (e->best_mm == 0u || (uint32_t)range + progress <= e->best_mm) {
        e->best_mm = range;
        e->ticks = 0u;
        return goal;
    }
    if (++e->ticks < c->esc_stall_ticks) {
        return goal;
    }
    if (e->stall_mm != 0u && (uint32_t)e->best_mm + progress > e->stall_mm && e->last_side != 0) {
        /* no nearer than when the last follow began: it led back here, go the other way
         * round; unless the last follow already was the other way, after the first side was
         * given up (tries): then the first side is known to lead away and this one, left
         * early (a leave on a noisy reading, docs/architecture.md "Leaving"), goes on, for
         * as long as its try allows */
        if (e->tries == 0u) {
            e->last_side = (int8_t)-e->last_side;
        }
    } else {
        if ((uint32_t)e->best_mm + QNAV_ESCAPE_NEW_MARGINS * c->margin_mm < e->hit_mm) {
            e->last_side = 0; /* far nearer than where the last follow ended: another obstacle */
        }
        e->tries = 0u;
    }
    e->stall_mm = e->best_mm;
    start_follow(e, e->last_side != 0 ? e->last_side : choose_side(c, lvl, goal), range);
    e->hit_mm = rest_mm(c, in, goal, e->best_mm, QNAV_ESCAPE_LEAVE_HALF_DEG);
    return skirt(c, lvl, e->side);
}

void qnav_escape_keep_moving(const qnav_clearance_t *c, const uint8_t *lvl,
                             const qnav_escape_t *e, uint16_t goal, qnav_ctrl_output_t *out)
{
    qnav_q1_15_t cap;
    if (e->side == 0) {
        return;
    }
    if (out->speed >= QNAV_ESCAPE_CRAWL) {
        /* the follow drives: as fast as the robot can stop within the clearance of the
         * chosen path, of straight ahead and of the boundary (the side it turns into when
         * the follow turns back) */
        int16_t at = 0;
        uint16_t path = wrap(out->heading_deg);
        uint8_t level = nearest_on_side(lvl, e->side, &at);
        if (lvl[path] < level) {
            level = lvl[path];
        }
        if (lvl[0] < level) {
            level = lvl[0];
        }
        cap = qnav_clearance_speed_cap(c, level);
        if (out->speed < cap) {
            out->speed = cap;
        }
        return;
    }
    out->heading_deg = qnav_signed_deg(goal);
    out->flags = (uint8_t)(out->flags & (uint8_t)~QNAV_FLAG_NO_PATH);
    if (blocked(c, lvl, (int16_t)goal)) {
        out->speed = 0; /* turn in place toward it */
        return;
    }
    cap = qnav_clearance_turn_cap(c, lvl, goal);
    out->speed = QNAV_ESCAPE_CRAWL < cap ? QNAV_ESCAPE_CRAWL : cap;
    if (out->quality < out->speed) {
        out->quality = out->speed;
    }
}

void qnav_escape_hold_turn(uint16_t prev, qnav_ctrl_output_t *out)
{
    const qnav_deg_t p = qnav_signed_deg(prev);
    const qnav_deg_t h = out->heading_deg;
    if (p > 0 && h < -90 && p - h > 180) {
        out->heading_deg = 179;
    } else if (p < 0 && h > 90 && h - p > 180) {
        out->heading_deg = -179;
    }
}

/* Half the width of the free window a robot that stood is sent into, degrees: a way at a
 * free run's very edge is one the robot faces only after a turn its drive may not make
 * (a degree or two), with the blocked paths beside it straight ahead. */
#define QNAV_ESCAPE_UNSTAND_HALF_DEG 5

/* The path nearest ref (0..359) whose paths within QNAV_ESCAPE_UNSTAND_HALF_DEG either side
 * are all free, in *path (on a tie the first found walking up from the lowest blocked path,
 * and a run's lower end); 0 when no run of free paths is that wide. One walk round the
 * circle, from a blocked path, run by run. */
static uint8_t free_window(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t ref,
                           uint16_t *path)
{
    const int16_t h = QNAV_ESCAPE_UNSTAND_HALF_DEG;
    int16_t from = -1; /* a blocked path to start at */
    int16_t k;
    int16_t run = 0;
    uint16_t best_d = 0xFFFFu;
    for (k = 0; k < (int16_t)QNAV_PATHS; ++k) {
        if (blocked(c, lvl, k)) {
            from = k;
            break;
        }
    }
    if (from < 0) {
        *path = ref; /* all free */
        return 1u;
    }
    /* paths from + 1 .. from + 360 (the last is from itself, blocked: it ends the last run) */
    for (k = 1; k <= (int16_t)QNAV_PATHS; ++k) {
        if (!blocked(c, lvl, (int16_t)(from + k))) {
            ++run;
            continue;
        }
        if (run >= 2 * h + 1) {
            /* candidates: the run's paths at least h inside both its ends */
            const int16_t lo = (int16_t)(from + k - run + h);
            const int16_t hi = (int16_t)(from + k - 1 - h);
            int16_t d_lo = (int16_t)wrap((int16_t)((int16_t)ref - lo)); /* ref above lo by */
            int16_t p;
            uint16_t d;
            if (d_lo <= hi - lo) {
                p = (int16_t)(lo + d_lo); /* ref inside the candidates */
            } else {
                /* outside: the nearer of the two ends */
                const uint16_t to_lo = (uint16_t)(360 - d_lo);
                const uint16_t to_hi = (uint16_t)(d_lo - (hi - lo));
                p = to_lo <= to_hi ? lo : hi;
            }
            d = qnav_angle_dist_deg(wrap(p), ref);
            if (d < best_d) {
                best_d = d;
                *path = wrap(p);
            }
        }
        run = 0;
    }
    return (uint8_t)(best_d != 0xFFFFu);
}

void qnav_escape_stood(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t prev,
                       qnav_ctrl_output_t *out)
{
    qnav_escape_t *e = &out->escape;
    uint16_t path;
    qnav_q1_15_t cap;
    if (e->stood < 255u) {
        ++e->stood;
    }
    if (c->esc_stall_ticks == 0u || e->stood <= 2u * (uint16_t)c->esc_stall_ticks) {
        /* the escape's own stall (after one stall time) acts first */
        return;
    }
    /* stood twice the stall time: the way in the middle of a free window nearest the last
     * decision (the robot turns on toward one way: a new one each tick kept it turning to
     * and fro); none: stand (it turns in place) */
    if (!free_window(c, lvl, prev, &path)) {
        return;
    }
    out->heading_deg = qnav_signed_deg(path);
    out->flags = (uint8_t)(out->flags & (uint8_t)~QNAV_FLAG_NO_PATH);
    cap = qnav_clearance_turn_cap(c, lvl, path);
    out->speed = QNAV_ESCAPE_CRAWL < cap ? QNAV_ESCAPE_CRAWL : cap; /* 0 until it faces it */
    if (out->quality < out->speed) {
        out->quality = out->speed;
    }
}
