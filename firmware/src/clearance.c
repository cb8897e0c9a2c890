/*
 * Body-aware clearance: VFH+-style enlargement of the sector readings into per-path
 * distance levels, and the speed guard (see clearance.h; docs/architecture.md,
 * "Clearance that respects the body"). Integer arithmetic only; the per-level tables are
 * made at init so that the step does no multiply or division here.
 */
#include "clearance.h"
#include "ctrl_internal.h"

#include <string.h>

#include "qnav/flash.h"

/* sin(g degrees) in units of 2^-15, g = 0..90 (sin 90 stored as 32767). Made by:
 * python3 -c "import math;print([min(32767,round(math.sin(math.radians(g))*32768)) for g in range(91)])" */
static const uint16_t sin_deg_q15[91] QNAV_FLASH = {
    0, 572, 1144, 1715, 2286, 2856, 3425, 3993, 4560, 5126, 5690, 6252,
    6813, 7371, 7927, 8481, 9032, 9580, 10126, 10668, 11207, 11743, 12275, 12803,
    13328, 13848, 14365, 14876, 15384, 15886, 16384, 16877, 17364, 17847, 18324, 18795,
    19261, 19720, 20174, 20622, 21063, 21498, 21926, 22348, 22763, 23170, 23571, 23965,
    24351, 24730, 25102, 25466, 25822, 26170, 26510, 26842, 27166, 27482, 27789, 28088,
    28378, 28660, 28932, 29197, 29452, 29698, 29935, 30163, 30382, 30592, 30792, 30983,
    31164, 31336, 31499, 31651, 31795, 31928, 32052, 32166, 32270, 32365, 32449, 32524,
    32588, 32643, 32688, 32723, 32748, 32763, 32767,
};

/* Control tick the speed guard allows for reacting, ms (DESIGN.md §4: 0.1 s). */
#define QNAV_GUARD_REACTION_MS 100u

/*
 * The level of a range (docs/qformats.md): (r * S + 2^15) >> 16, capped at L - 1. A range
 * at or beyond the maximum is at the farthest level without a product (a sector that saw
 * nothing). Below it, S fits 16 bits for every maximum range of at least L mm, so the
 * product is a 16 x 16 bit one (avr-gcc: __umulhisi3, four MULs, instead of the 32 x 16
 * bit __muluhisi3); maximum ranges below L mm add r * level_scale_hi, r < L - 1, within 16
 * bits. Inline for the step's sector loop.
 */
static inline uint8_t level_of(const qnav_clearance_t *c, qnav_mm_t range_mm)
{
    uint32_t level;
    if (range_mm >= c->max_range_mm) {
        return QNAV_DIST_LEVELS - 1u;
    }
    level = ((uint32_t)range_mm * c->level_scale + 32768u) >> 16;
    if (c->level_scale_hi != 0u) {
        level += (uint16_t)(range_mm * c->level_scale_hi);
    }
    return (uint8_t)(level > QNAV_DIST_LEVELS - 1u ? QNAV_DIST_LEVELS - 1u : level);
}

uint8_t qnav_clearance_level_of(const qnav_clearance_t *c, qnav_mm_t range_mm)
{
    return level_of(c, range_mm);
}

/* The smallest range (mm) that maps to level or above: the nearest an obstacle read at
 * that level can be, so both tables below err on the safe side. */
static uint32_t level_floor_mm(const qnav_clearance_t *c, uint8_t level)
{
    uint32_t lo = 0;
    uint32_t hi = c->max_range_mm;
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2u;
        if (qnav_clearance_level_of(c, (qnav_mm_t)mid) >= level) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

/* The nearest an obstacle read at level can be, from the robot's centre (readings start
 * at the transducers), at most 65535 mm. */
static uint32_t level_distance_mm(const qnav_clearance_t *c, uint8_t level)
{
    uint32_t d = level_floor_mm(c, level) + c->sensor_offset_mm;
    return d > 65535u ? 65535u : d;
}

/* Smallest whole degree g with sin(g) >= margin / d (90 when d <= margin). */
static uint8_t enlarge_deg(uint32_t margin_mm, uint32_t d_mm)
{
    uint8_t g;
    if (margin_mm == 0u) {
        return 0;
    }
    if (d_mm <= margin_mm) {
        return 90;
    }
    /* d < 2^16 and margin < d, so both products stay below 2^31 */
    for (g = 0; g < 90u; ++g) {
        if ((uint32_t)QNAV_FLASH_READ_U16(&sin_deg_q15[g]) * d_mm >= margin_mm * 32768u) {
            return g;
        }
    }
    return 90;
}

/* A reading placed on the central part of its wedge (wedge_pct) leaves its wedge's edges
 * unpainted, where the obstacle may lie: safe only while its enlargement covers that edge by
 * the time the robot must brake for it, so the edge left unpainted is at most the
 * enlargement at the distance the speed guard needs from full speed,
 * r + d_s + 2 v T + v^2 / (2 a) (a reaction tick, and a tick more: the robot is anywhere
 * within v T of that distance on the first tick that sees it nearer), in degrees; 90
 * without the guard. At the profiles' default
 * sectors it does not bind; a Pioneer at 8 sectors (45 deg wedges, the 16-sector placement)
 * touched something in 0.43 of its episodes (docs/architecture.md, "Wedge placement"). */
static uint8_t wedge_cover_deg(const qnav_ctrl_config_t *cfg)
{
    const uint32_t v = cfg->v_max_mm_s, a = cfg->decel_mm_s2;
    uint32_t d;
    if (v == 0u || a == 0u) {
        return 90u;
    }
    /* v, a < 2^16: v^2 < 2^32 */
    d = (uint32_t)cfg->body_radius_mm + cfg->safety_mm + 2u * v * QNAV_GUARD_REACTION_MS / 1000u +
        v * v / (2u * a);
    return enlarge_deg((uint32_t)cfg->body_radius_mm + cfg->pass_mm, d > 65535u ? 65535u : d);
}

/*
 * The enlargement of one reading: the smallest whole degree g with sin g >= margin / D, D the
 * reading's own distance from the centre (range + sensor offset, at most 65535 mm), the same
 * definition as enlarge_deg(), at most its level's gamma (enlarge_deg[] at init, from the
 * level's smallest range): a level spans up to 161 mm of range (5 m sonar, 32 levels), and
 * at 0.7-1.2 m from a Pioneer the level's floor widens each side by up to 5 degrees more
 * than the reading does, which closes gaps the robot fits through (docs/architecture.md,
 * "The reading's own distance, and braking that does not wait for a turn"). The reading
 * lies below the next level's smallest range, so its gamma is at least that level's: the
 * answer is searched by halving between the two (none when they agree), not walked down
 * from the top a degree at a time (sin g * D >= margin holds from the answer on).
 * @par Cost: one 16 x 16 bit product per halving, ceil(log2(spread + 1)) for the spread of
 * degrees between the two levels' gammas: 0 or 1 beyond about a metre, 2-13 nearer and up
 * to 45 at the nearest two levels (32 levels, 2.5-5 m sonars, margins of 170-400 mm),
 * so at most 6 products where the walk took up to spread + 1; they stay below 2^31 as in
 * enlarge_deg(). level < QNAV_DIST_LEVELS - 1.
 */
static uint8_t reading_gamma(const qnav_clearance_t *c, qnav_mm_t range_mm, uint8_t level)
{
    uint8_t hi = c->enlarge_deg[level];
    uint8_t lo = c->enlarge_deg[level + 1u];
    uint32_t need = (uint32_t)c->pass_margin_mm << 15;
    uint16_t d = (uint16_t)(range_mm + c->sensor_offset_mm); /* 16 x 16 bit products below */
    if (d < range_mm) {
        d = 65535u; /* the sum passed 65535 */
    }
    while (lo < hi) {
        uint8_t mid = (uint8_t)(lo + (uint8_t)((uint8_t)(hi - lo) >> 1));
        if ((uint32_t)QNAV_FLASH_READ_U16(&sin_deg_q15[mid]) * (uint32_t)d >= need) {
            hi = mid;
        } else {
            lo = (uint8_t)(mid + 1u);
        }
    }
    return hi;
}

static uint32_t isqrt32(uint32_t x)
{
    uint32_t r = 0;
    uint32_t bit = (uint32_t)1 << 30;
    while (bit > x) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return r;
}

/* Largest speed (Q1.15 of v_max) that stops within s_mm after one reaction tick:
 * v T + v^2 / (2 a) <= s, so v = sqrt((a T)^2 + 2 a s) - a T; for an s whose stop_speed()
 * is below full speed, so that (a T)^2 + 2 a s fits 32 bits (a, v_max <= 65535; a T = a / 10
 * exactly, a 16-bit division). */
static qnav_q1_15_t stop_speed_within(uint32_t s_mm, uint32_t v_max_mm_s, uint32_t decel_mm_s2)
{
    uint32_t at = (uint16_t)((uint16_t)decel_mm_s2 / (1000u / QNAV_GUARD_REACTION_MS));
    uint32_t v = isqrt32(at * at + 2u * decel_mm_s2 * s_mm) - at;
    if (v >= v_max_mm_s) {
        return QNAV_Q1_15_MAX;
    }
    return (qnav_q1_15_t)((v * 32768u) / v_max_mm_s);
}

/* The same for any s_mm <= 65535: a <= 65535 and s <= 65535, so 2 a s may pass 2^32; such a
 * cap is above any v_max. */
static qnav_q1_15_t stop_speed(uint32_t s_mm, uint32_t v_max_mm_s, uint32_t decel_mm_s2)
{
    uint32_t at = decel_mm_s2 / (1000u / QNAV_GUARD_REACTION_MS);
    if (s_mm > (0xFFFFFFFFu - at * at) / (2u * decel_mm_s2)) {
        return QNAV_Q1_15_MAX;
    }
    return stop_speed_within(s_mm, v_max_mm_s, decel_mm_s2);
}

/* The clearance (mm) a path at level leaves for stopping: the nearest its obstacle can be,
 * less the robot's radius and safety distance. A sonar reads its minimum range for
 * anything that near or nearer, so a level that holds that range may hide an obstacle at
 * the transducers: its floor would promise room the robot may not have (the Pioneer's
 * 0.1 m reads at level 1, floor 81 mm, and crept into walls at 0.14 m/s). */
static uint32_t stop_room_mm(const qnav_clearance_t *c, uint8_t level)
{
    uint32_t d = level <= c->guard_min_level ? c->sensor_offset_mm : level_distance_mm(c, level);
    return d > c->margin_mm ? d - c->margin_mm : 0u;
}

/* The speed guard's cap at level, computed (at init for every level; the step's is below). */
static qnav_q1_15_t level_cap(const qnav_clearance_t *c, uint8_t level)
{
    if (c->v_max_mm_s == 0u || c->decel_mm_s2 == 0u || level >= QNAV_DIST_LEVELS - 1u) {
        return QNAV_Q1_15_MAX; /* no guard, or nothing seen within range */
    }
    return stop_speed(stop_room_mm(c, level), c->v_max_mm_s, c->decel_mm_s2);
}

void qnav_clearance_init(qnav_clearance_t *c, const qnav_ctrl_config_t *cfg)
{
    uint32_t margin = (uint32_t)cfg->body_radius_mm + cfg->safety_mm;
    uint32_t pass = (uint32_t)cfg->body_radius_mm + cfg->pass_mm;
    uint8_t level;
    c->margin_mm = margin > 65535u ? 65535u : (uint16_t)margin;
    c->pass_margin_mm = pass > 65535u ? 65535u : (uint16_t)pass;
    c->sensor_offset_mm = cfg->sensor_offset_mm;
    c->v_max_mm_s = cfg->v_max_mm_s;
    c->decel_mm_s2 = cfg->decel_mm_s2;
    c->guard_min_level = qnav_clearance_level_of(c, cfg->range_min_mm);
    c->range_min_mm = cfg->range_min_mm;
    /* a sonar with no minimum range reads the obstacle's own distance */
    c->dead_zone_deg = cfg->range_min_mm == 0u ? 0u : enlarge_deg(cfg->body_radius_mm, c->margin_mm);
    for (level = 0; level < QNAV_DIST_LEVELS; ++level) {
        c->enlarge_deg[level] = enlarge_deg(pass, level_distance_mm(c, level));
    }
    /* where the cap leaves 0, and from where on it is full speed (level L - 1 always is) */
    c->guard_from_level = 0;
    while (level_cap(c, c->guard_from_level) == 0) {
        ++c->guard_from_level;
    }
    c->guard_full_level = QNAV_DIST_LEVELS - 1u;
    while (c->guard_full_level > 0u &&
           level_cap(c, (uint8_t)(c->guard_full_level - 1u)) == QNAV_Q1_15_MAX) {
        --c->guard_full_level;
    }
}

/* The cap is 0 below guard_from_level and full speed from guard_full_level on (both found
 * at init from the cap itself), so only the levels between compute it: a binary search, a
 * square root and two divisions, for one level on the TekBot's profile (2), five on the
 * Pioneer's (2-6; level 1 holds its sonar's minimum range). A table of every level's cap would be 62 bytes of RAM. */
qnav_q1_15_t qnav_clearance_speed_cap(const qnav_clearance_t *c, uint8_t level)
{
    if (level >= c->guard_full_level) {
        return QNAV_Q1_15_MAX;
    }
    if (level < c->guard_from_level) {
        return 0;
    }
    /* below full speed at init, so within stop_speed_within()'s range */
    return stop_speed_within(stop_room_mm(c, level), c->v_max_mm_s, c->decel_mm_s2);
}

qnav_q1_15_t qnav_clearance_turn_cap(const qnav_clearance_t *c, const uint8_t *lvl, uint16_t path)
{
    uint8_t level = lvl[path] < lvl[0] ? lvl[path] : lvl[0];
    return qnav_clearance_speed_cap(c, level);
}

qnav_status_t qnav_clearance_setup(qnav_clearance_t *c, const qnav_ctrl_config_t *cfg)
{
    if (cfg->n_sectors < 1u || cfg->n_sectors > QNAV_MAX_SECTORS) {
        return QNAV_E_SECTORS;
    }
    if (cfg->max_range_mm == 0u || cfg->range_min_mm >= cfg->max_range_mm) {
        return QNAV_E_RANGE;
    }
    c->n_sectors = cfg->n_sectors;
    c->max_range_mm = cfg->max_range_mm;
    {
        uint32_t scale = ((uint32_t)(QNAV_DIST_LEVELS - 1) * 65536u + cfg->max_range_mm / 2u) /
                         cfg->max_range_mm;
        c->level_scale = (uint16_t)(scale & 0xFFFFu);
        c->level_scale_hi = (uint8_t)(scale >> 16);
    }
    c->sector_paths = (uint16_t)(QNAV_PATHS / cfg->n_sectors);
    c->sector_rem = (uint16_t)(QNAV_PATHS - c->sector_paths * cfg->n_sectors);
    if (cfg->wedge_pct > 100u) {
        return QNAV_E_WEDGE;
    }
    /* paths left out at each edge of a sector: (100 - pct)% of half its 360/N wedge, at
     * most so many that its middle path stays, and with the speed guard on at most what a
     * reading's enlargement covers from where the robot must brake (wedge_cover_deg) */
    {
        uint16_t shrink = (uint16_t)(((uint32_t)(100u - cfg->wedge_pct) * QNAV_PATHS) /
                                     (200u * cfg->n_sectors));
        uint16_t keep = (uint16_t)((c->sector_paths - 1u) / 2u);
        uint8_t cover = wedge_cover_deg(cfg);
        shrink = shrink < keep ? shrink : keep;
        c->wedge_shrink = (uint8_t)(shrink < cover ? shrink : cover);
    }
    c->wedge_near_level = qnav_clearance_level_of(
        c, cfg->wedge_near_mm < cfg->max_range_mm ? cfg->wedge_near_mm : cfg->max_range_mm);
    c->first_sector_paths = (uint8_t)((QNAV_PATHS / 2u + cfg->n_sectors - 1u) / cfg->n_sectors);
    qnav_clearance_init(c, cfg);
    return QNAV_OK;
}

/* Lower lvl[p..p+k-1] to at most level (no wrap; k <= 360). On AVR two bytes per
 * iteration by hand, 8.5 cycles a byte against 11 from avr-gcc (checked by the shared
 * vectors under simavr); on x86 SSE2 windows of 16 (below); elsewhere a branch-free min
 * the compiler can vectorise. */
#if defined(__AVR__)
static void lower(uint8_t *lvl, uint16_t p, uint16_t k, uint8_t level)
{
    uint8_t *q = lvl + p;
    uint8_t pairs = (uint8_t)(k >> 1);
    if ((k & 1u) != 0u) {
        *q = *q < level ? *q : level;
        ++q;
    }
    if (pairs != 0u) {
        __asm__ volatile("1: ld __tmp_reg__, %a0\n\t"
                         "cp %2, __tmp_reg__\n\t"
                         "brsh 2f\n\t"
                         "mov __tmp_reg__, %2\n\t"
                         "2: st %a0+, __tmp_reg__\n\t"
                         "ld __tmp_reg__, %a0\n\t"
                         "cp %2, __tmp_reg__\n\t"
                         "brsh 3f\n\t"
                         "mov __tmp_reg__, %2\n\t"
                         "3: st %a0+, __tmp_reg__\n\t"
                         "dec %1\n\t"
                         "brne 1b\n\t"
                         : "+z"(q), "+r"(pairs)
                         : "r"(level)
                         : "memory");
    }
}
#elif defined(QNAV_LEVELS_SSE2)
/* Sixteen levels an instruction (x86-64 hosts: the simulator and evolution). Lowering a
 * byte twice leaves it as lowering it once, so a run of 16 or more ends with a window
 * that overlaps the one before it, and a shorter run is one window with the bytes outside
 * it masked to 0xFF (a no-op under min). A window lies inside the 360 levels: at p when
 * it fits, else at the array's last 16 bytes. Checked against the byte loop by the shared
 * vectors and test_clearance. */
static const uint8_t keep_mask[48] = {
    0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
    0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF,
};

static inline void lower16(uint8_t *q, __m128i bound)
{
    _mm_storeu_si128((__m128i *)(void *)q, _mm_min_epu8(qnav_levels16(q), bound));
}

static void lower(uint8_t *lvl, uint16_t p, uint16_t k, uint8_t level)
{
    const __m128i bound = _mm_set1_epi8((char)level);
    if (k >= 16u) {
        uint8_t *q = lvl + p;
        uint8_t *last = q + k - 16u;
        for (; q < last; q += 16) {
            lower16(q, bound);
        }
        lower16(last, bound);
    } else if (k != 0u) {
        uint16_t at = p + 16u <= QNAV_PATHS ? p : (uint16_t)(QNAV_PATHS - 16u);
        uint16_t s = (uint16_t)(p - at); /* the run is bytes s..s+k-1 of the window */
        __m128i outside = _mm_or_si128(qnav_levels16(keep_mask + 16u - s),
                                       qnav_levels16(keep_mask + 32u - s - k));
        lower16(lvl + at, _mm_max_epu8(bound, outside));
    }
}
#else
static void lower(uint8_t *lvl, uint16_t p, uint16_t k, uint8_t level)
{
    uint8_t *q = lvl + p;
    uint8_t *end = q + k;
    for (; q != end; ++q) {
        *q = *q < level ? *q : level;
    }
}
#endif

/* Lower the level of the k paths from p on (wrapping past 359; k <= 360) to level. */
static void paint(uint8_t *lvl, uint16_t p, uint16_t k, uint8_t level)
{
    if (p + k <= QNAV_PATHS) {
        lower(lvl, p, k, level);
    } else {
        lower(lvl, p, (uint16_t)(QNAV_PATHS - p), level);
        lower(lvl, 0u, (uint16_t)(p + k - QNAV_PATHS), level);
    }
}

/*
 * Paint one piece (n paths from first on, all of one sector) at level, widened by its
 * gamma on both sides, except where a neighbouring piece already covers it at a level no
 * higher. gamma only shrinks as the reading grows, so a left neighbour at a level <= this
 * one's whose gamma is no smaller (always, unless both readings share a level and the
 * neighbour's is the farther) covers this piece's left widening and as far as its own
 * right widening reaches (gamma_prev + gamma paths); a right neighbour at a strictly lower
 * level (a nearer reading: gamma_next >= gamma) covers this piece's right widening back to
 * where its own left widening starts (gamma_next + gamma paths). Ties leave the overlap to
 * the left piece's right widening, so each skipped path is painted by a chain of
 * neighbours ending in one that paints it (docs/architecture.md, "Clearance that respects
 * the body"). Walls of similar readings paint about n paths a piece instead of
 * n + 2 gamma.
 */
static void paint_piece(uint8_t *lvl, uint16_t first, uint16_t n, uint8_t level, uint8_t gamma,
                        uint8_t prev, uint8_t prev_gamma, uint8_t next, uint8_t next_gamma)
{
    uint16_t k = (uint16_t)(n + 2u * gamma);
    uint16_t skip_left = 0;
    uint16_t skip_right = 0;
    uint16_t p = (uint16_t)(first >= gamma ? first - gamma : first + QNAV_PATHS - gamma);
    if (k >= QNAV_PATHS) {
        paint(lvl, 0u, QNAV_PATHS, level); /* the whole circle */
        return;
    }
    if (prev <= level && prev_gamma >= gamma) {
        skip_left = (uint16_t)(prev_gamma + gamma);
    }
    if (next < level) {
        skip_right = (uint16_t)(next_gamma + gamma);
    }
    if (skip_left + skip_right >= k) {
        return;
    }
    p = (uint16_t)(p + skip_left);
    if (p >= QNAV_PATHS) {
        p = (uint16_t)(p - QNAV_PATHS);
    }
    paint(lvl, p, (uint16_t)(k - skip_left - skip_right), level);
}

/*
 * A piece when readings sit on the central part of their wedge (wedge_shrink > 0): the
 * reading blocks the piece less wedge_shrink paths at each edge that is a sector's edge
 * (cut_left, cut_right; sector 0's split at path 0 is no edge), then widened by gamma. The
 * blocked arc is [first + cut_l - gamma, first + n - cut_r + gamma); it may be empty. The
 * neighbour skipping above assumes pieces that reach their edges, so every piece paints.
 */
static void paint_piece_central(uint8_t *lvl, const qnav_clearance_t *c, uint16_t first,
                                uint16_t n, uint8_t level, uint8_t gamma8, uint8_t cut_left,
                                uint8_t cut_right)
{
    int16_t gamma = (int16_t)gamma8;
    int16_t shrink = level >= c->wedge_near_level ? (int16_t)c->wedge_shrink : 0;
    int16_t lo = (int16_t)((int16_t)first + (cut_left ? shrink : 0) - gamma);
    int16_t hi = (int16_t)((int16_t)(first + n) - (cut_right ? shrink : 0) + gamma);
    if (hi <= lo) {
        return;
    }
    if (hi - lo >= (int16_t)QNAV_PATHS) {
        paint(lvl, 0u, QNAV_PATHS, level);
        return;
    }
    if (lo < 0) {
        lo = (int16_t)(lo + (int16_t)QNAV_PATHS);
        hi = (int16_t)(hi + (int16_t)QNAV_PATHS);
    }
    if (lo >= (int16_t)QNAV_PATHS) {
        lo = (int16_t)(lo - (int16_t)QNAV_PATHS);
        hi = (int16_t)(hi - (int16_t)QNAV_PATHS);
    }
    paint(lvl, (uint16_t)lo, (uint16_t)(hi - lo), level);
}

/* The level of a sector's reading (one beyond the maximum range flagged in *flags). */
static inline uint8_t sector_level(const qnav_clearance_t *c, qnav_mm_t range_mm, uint8_t *flags)
{
    if (range_mm > c->max_range_mm) {
        *flags |= QNAV_FLAG_RANGE_CLIPPED;
    }
    return level_of(c, range_mm);
}

/* The level sector p saw: the farthest for the one the destination makes irrelevant. */
static inline uint8_t seen_level(const qnav_clearance_t *c, const qnav_mm_t *p,
                                 const qnav_mm_t *skip, uint8_t *flags)
{
    return p == skip ? (uint8_t)(QNAV_DIST_LEVELS - 1u) : sector_level(c, *p, flags);
}

uint16_t qnav_clearance_reach_sector(const qnav_clearance_t *c, const qnav_ctrl_input_t *in)
{
    uint16_t k;
    qnav_mm_t r;
    if (in->goal_range_mm == 0u || (uint32_t)in->goal_range_mm + c->margin_mm >=
                                        (uint32_t)c->max_range_mm + c->sensor_offset_mm) {
        return c->n_sectors; /* unknown, or no reading can lie beyond it (most ticks) */
    }
    k = qnav_ctrl_sector_of_path(c->n_sectors, qnav_whole_deg(in->goal_bearing_cdeg));
    r = in->ranges_mm[k];
    if (r >= c->max_range_mm ||
        (uint32_t)r + c->sensor_offset_mm < (uint32_t)in->goal_range_mm + c->margin_mm) {
        return c->n_sectors;
    }
    return k;
}

/*
 * A sector's enlargement: its reading's own (reading_gamma); none for a sector that saw
 * nothing within range, which is never painted. A reading at the sonar's minimum range says
 * only that the obstacle is that near or nearer: as near as the safety distance the robot
 * keeps, r + d_s from the centre, where the paths that would touch it (pass within r) lie
 * within asin(r / (r + d_s)) of it (dead_zone_deg: 68 deg for the Pioneer 3-DX, whose
 * sonar reads 0.1 m for anything nearer from its rim). Where the minimum range lies within
 * r + d_s of the centre the reading's own enlargement is already at least that, and nothing
 * changes (docs/architecture.md, "A reading at the sonar's minimum range").
 */
static inline uint8_t gamma_of(const qnav_clearance_t *c, qnav_mm_t range_mm, uint8_t level)
{
    uint8_t g;
    if (level == QNAV_DIST_LEVELS - 1u) {
        return 0u;
    }
    g = reading_gamma(c, range_mm, level);
    return range_mm <= c->range_min_mm && g < c->dead_zone_deg ? c->dead_zone_deg : g;
}

/* Every path at the farthest level. On AVR four bytes per iteration: avr-libc's memset
 * takes about 6 cycles a byte on the ATmega128, this loop under 3 (and GCC would turn the
 * loop back into a memset call); out of line, because inlined into the sector loop it gets
 * no pointer register with a displacement and costs 1 000 cycles more. Elsewhere the C
 * library's memset, which stores words. */
#if defined(__AVR__)
__attribute__((optimize("no-tree-loop-distribute-patterns"), noinline))
static void fill_clear(uint8_t *lvl)
{
    uint8_t *p = lvl;
    uint8_t i;
    for (i = 0; i < QNAV_PATHS / 4u; ++i) {
        p[0] = (uint8_t)(QNAV_DIST_LEVELS - 1u);
        p[1] = (uint8_t)(QNAV_DIST_LEVELS - 1u);
        p[2] = (uint8_t)(QNAV_DIST_LEVELS - 1u);
        p[3] = (uint8_t)(QNAV_DIST_LEVELS - 1u);
        p += 4;
    }
}
#else
static void fill_clear(uint8_t *lvl)
{
    memset(lvl, QNAV_DIST_LEVELS - 1, QNAV_PATHS);
}
#endif

/* Sector lengths follow from path * N + 180 wrapping past 360: a sector whose first path
 * has phase p = path * N + 180 - 360 * sector (0 <= p < N) holds q = 360 / N paths, or q + 1
 * when p < 360 - q * N; sector 0 is cut in two pieces, paths 0.. and the last ones before
 * 360. Pieces are painted in path order, each knowing its neighbours' levels (the piece
 * before piece 0 holds path 359). */
uint8_t qnav_clearance_levels(const qnav_clearance_t *c, const qnav_mm_t *ranges, uint16_t skip,
                              uint8_t *lvl)
{
    const qnav_mm_t *next_range = ranges + 1; /* the sector after the current piece's */
    const qnav_mm_t *end = ranges + c->n_sectors;
    const qnav_mm_t *skip_at = skip < c->n_sectors ? ranges + skip : end; /* end: none */
    uint16_t first = 0;                       /* the current piece: paths first..stop - 1 */
    uint16_t stop = c->first_sector_paths;
    uint16_t phase = (uint16_t)(stop * c->n_sectors - QNAV_PATHS / 2u); /* of the next sector */
    uint8_t flags = 0;
    uint8_t level0 = seen_level(c, ranges, skip_at, &flags);
    uint8_t gamma0 = gamma_of(c, ranges[0], level0);
    uint8_t level = level0;
    uint8_t gamma = gamma0;
    /* path 359 lies in sector 0 (its last piece) when N <= 180, else in sector N - 1 */
    uint8_t prev = level0;
    uint8_t prev_gamma = gamma0;
    if (c->n_sectors > QNAV_DTHETA_MAX) {
        prev = seen_level(c, end - 1, skip_at, &flags);
        prev_gamma = gamma_of(c, end[-1], prev);
    }
    fill_clear(lvl);
    for (;;) {
        /* after the last sector comes sector 0's last piece, after that piece 0 */
        uint8_t next = level0;
        uint8_t next_gamma = gamma0;
        if (next_range != end) {
            next = seen_level(c, next_range, skip_at, &flags);
            next_gamma = gamma_of(c, *next_range, next);
            ++next_range;
        }
        if (level == QNAV_DIST_LEVELS - 1u) {
            /* nothing seen in this sector */
        } else if (c->wedge_shrink == 0u) {
            paint_piece(lvl, first, (uint16_t)(stop - first), level, gamma, prev, prev_gamma,
                        next, next_gamma);
        } else {
            /* sector 0 is cut at path 0 (piece 0's left, its last piece's right) */
            paint_piece_central(lvl, c, first, (uint16_t)(stop - first), level, gamma,
                                (uint8_t)(first != 0u), (uint8_t)(stop < QNAV_PATHS));
        }
        if (stop >= QNAV_PATHS) {
            return flags;
        }
        first = stop;
        stop = (uint16_t)(stop + c->sector_paths);
        if (phase < c->sector_rem) {
            ++stop;
            phase = (uint16_t)(phase + c->n_sectors - c->sector_rem);
        } else {
            phase = (uint16_t)(phase - c->sector_rem);
        }
        if (stop > QNAV_PATHS) {
            stop = QNAV_PATHS;
        }
        prev = level;
        prev_gamma = gamma;
        level = next;
        gamma = next_gamma;
    }
}
