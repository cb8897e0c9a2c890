/*
 * The map and its plan (qnav/map.h; docs/architecture.md, "A map and a plan").
 *
 * What a sonar reading says: a sector reports the nearest obstacle point inside its wedge,
 * so every point of the wedge nearer than the reading is free, and somewhere on the arc at
 * the reading lies an obstacle. A cell inside the wedge and nearer than the reading (less
 * the range noise and most of a cell) is marked free; a cell on the arc that has never been
 * seen free gains one count of occupied evidence; a cell seen free stays free until a
 * reading ends in it again after it was forgotten (free evidence is kept, the arc's is
 * weak: at most one of the arc's cells holds the obstacle, and the others are carved free
 * by the wedges that see past them as the robot moves and turns). Cells nearer than the body
 * radius and safety distance to an occupied cell are blocked; the plan is Dijkstra's from
 * the destination's cell over the rest (8 neighbours, 10 per side, 14 per diagonal, no
 * corner cutting past a blocked cell), unknown cells passable.
 */
#include "qnav/map.h"

#include <stddef.h>
#include <string.h>

#include "escape.h"
#include "map_align.h"
#include "map_compact.h"
#include "map_plain.h"
#include "qnav/trig.h"

#define EVIDENCE_FREE_MIN QNAV_MAP_FREE_FLOOR
#define EVIDENCE_MAX 3
#define EVIDENCE_REFUSED 100 /* a cell the robot could not pass: kept until the refusal lapses */
/* An arc is marked occupied from 3/4 of a cell plus at most this many % of the reading
 * nearer than the reading, however noisy the sonar: a noisy sonar's readings of one
 * obstacle spread over its noise, and arcs as thick as that closed passages (measured:
 * docs/architecture.md, "The map's range noise"). */
#define OCCUPIED_BAND_PCT 5
#define STEP_SIDE 10u
#define STEP_DIAG 14u
#define NOT_QUEUED UINT16_C(0xFFFF)
typedef char unreached_and_not_queued_are_all_ones[QNAV_MAP_UNREACHED == 0xFFFFu && NOT_QUEUED == 0xFFFFu ? 1 : -1];
#define MAX_CELLS UINT32_C(65000)
#define MAX_REACH_MM 40000u
/* The full layout's memory holds uint16_t (1 on an AVR, 2 elsewhere); the compact one,
 * bytes. */
typedef struct {
    char c;
    uint16_t u;
} u16_alignment_t;

/* QNAV_MAP_CONFIG_FIELDS lays out as qnav_map_config_t: a struct of the list's fields has
 * the same size, and each field the same place and size (a field the list leaves out moves
 * the ones after it, or on the ATmega128 the size). */
#define MIRROR_FIELD(name, bits) uint##bits##_t name;
typedef struct {
    QNAV_MAP_CONFIG_FIELDS(MIRROR_FIELD)
} config_mirror_t;
#define SAME_PLACE(name, bits)                                                              \
    &&offsetof(config_mirror_t, name) == offsetof(qnav_map_config_t, name) &&             \
        sizeof(((const config_mirror_t *)0)->name) == sizeof(((const qnav_map_config_t *)0)->name)
typedef char config_fields_listed[sizeof(config_mirror_t) == sizeof(qnav_map_config_t)
                                          QNAV_MAP_CONFIG_FIELDS(SAME_PLACE)
                                      ? 1
                                      : -1];
#undef SAME_PLACE
#undef MIRROR_FIELD

/* Buckets of the plan's queue: the largest step (14 + near_cost) + 1. */
#define BUCKETS 270u

void qnav_map_config_default(qnav_map_config_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    cfg->cell_mm = 100u;
    cfg->reach_mm = 2000u;
    cfg->look_mm = 1000u;
    cfg->jump_mm = 1000u;
    cfg->plan_ticks = 10u;
    cfg->noise_pct = 5u;
    cfg->near_mm = 200u;
    cfg->arc_cdeg = 2250u;
    cfg->arc_width_mm = 0u;
    cfg->sight = 1u;
    cfg->escape_grow = 1u;
    cfg->near_cost = 10u;
    cfg->unknown_cost = 0u;
    cfg->align_samples = 0u;
    cfg->turn_back_ticks = 0u;
    cfg->refuse_ticks = 30u;
    cfg->refuse_life_ticks = 200u;
    cfg->compact = 0u;
    cfg->grow_steps = 16u;
    cfg->forget_reach_mm = 0u;
    cfg->opening_mm = 0u;
}

uint32_t qnav_map_cells(uint32_t width_mm, uint32_t height_mm, uint16_t cell_mm)
{
    uint32_t nx, ny;
    if (cell_mm == 0u) {
        return 0u;
    }
    nx = (width_mm + cell_mm - 1u) / cell_mm;
    ny = (height_mm + cell_mm - 1u) / cell_mm;
    if (nx == 0u || ny == 0u || nx > MAX_CELLS || ny > MAX_CELLS / nx) {
        return 0u;
    }
    return nx * ny;
}

size_t qnav_map_size(const qnav_map_config_t *cfg, uint32_t width_mm, uint32_t height_mm)
{
    uint32_t cells;
    if (cfg == NULL) {
        return 0u;
    }
    cells = qnav_map_cells(width_mm, height_mm, cfg->cell_mm);
    if (cells == 0u) {
        return 0u;
    }
    if (cfg->compact) {
        const uint32_t nx = (width_mm + cfg->cell_mm - 1u) / cfg->cell_mm;
        return qnav_cmap_bytes(nx, cells / nx);
    }
    /* the queue's heads, then cost, next, prev: 2 bytes each; evidence, blocked: 1 */
    return (size_t)BUCKETS * 2u + (size_t)cells * 8u;
}

/* Cells across the largest square map of cfg that len bytes hold (0: none). */
static uint32_t square_cells(const qnav_map_config_t *cfg, size_t len)
{
    uint32_t lo = 0u, hi = 256u; /* lo fits (or is 0), hi does not */
    while (hi - lo > 1u) {
        const uint32_t n = (lo + hi) / 2u, side = n * cfg->cell_mm;
        const size_t need = qnav_map_size(cfg, side, side);
        if (need != 0u && need <= len) {
            lo = n;
        } else {
            hi = n;
        }
    }
    return lo;
}

/* The range from which a range peak marks no arc: where a wedge of n sectors spans more
 * than 2 opening_mm across, opening_mm / sin(180 deg / n), saturated; 0 when none is left
 * out (opening_mm 0, or one sector: its neighbours are itself). */
static uint16_t peak_range(uint16_t opening_mm, uint16_t n_sectors)
{
    int16_t c, s;
    uint32_t r;
    if (opening_mm == 0u || n_sectors < 2u) {
        return 0u;
    }
    qnav_cos_sin_q14((int32_t)(INT32_C(18000) / (int32_t)n_sectors), &c, &s);
    r = ((uint32_t)opening_mm << 14) / (uint32_t)(s > 0 ? s : 1);
    return (uint16_t)(r > 65535u ? 65535u : (r == 0u ? 1u : r));
}

/* How far readings clear and mark (qnav_map_t.seen_mm): the reach, but no farther than a
 * reading at the sonar's range clears (as any reading: 3/4 cell and its noise short of
 * it). That reading clears its wedge out to the reach, and beyond it would clear cells no
 * reading saw, forgetting walls marked from nearer (docs/architecture.md, "A reach beyond
 * the sonar"). */
static uint16_t seen_range(const qnav_map_config_t *cfg, const qnav_ctrl_config_t *ctrl)
{
    int32_t seen = (int32_t)ctrl->max_range_mm + (int32_t)ctrl->sensor_offset_mm;
    seen -= (int32_t)cfg->cell_mm * 3 / 4 + seen * (int32_t)cfg->noise_pct / 100;
    return (uint16_t)(seen < 0 ? 0 : (seen < (int32_t)cfg->reach_mm ? seen : (int32_t)cfg->reach_mm));
}

static int32_t abs32(int32_t v)
{
    return v < 0 ? -v : v;
}

/* Cells between a placed map's edge and the robot: the cells its readings mark (reach_mm)
 * stay inside the map. */
static int32_t edge_cells(const qnav_map_config_t *cfg)
{
    return ((int32_t)cfg->reach_mm + (int32_t)cfg->cell_mm - 1) / (int32_t)cfg->cell_mm;
}

/* What a placed map keeps between its edge and the robot at least, mm, in whole cells, even
 * midway to a goal nearly a square away: the plan has no way outside the map, and a robot
 * in its edge cell whose way on lies past that edge finds none, forgets, and finds the same
 * again (a closed aisle at difficulty 1; docs/architecture.md, "The board's map: placed,
 * and following the robot"). 3 cells of the TekBot's 0.30 m, 2 of the Pioneer's 0.5 m. */
#define ROBOT_IN_MM 900

/* The placement rule along one axis: the corner of a map side_mm across midway between the
 * robot at r and the goal at g when both lie a cell inside it, moved so that the robot
 * lies ROBOT_IN_MM inside (the goal then in the edge cell or past it); else the robot a
 * cell more than the readings' reach inside it and the rest toward the goal (the plan then
 * leads to the edge cell nearest the goal, and the map follows the robot there). 0 when
 * the map is too small to keep the robot that far in. */
static int place_axis(const qnav_map_config_t *cfg, int32_t r, int32_t g, int32_t side,
                      int32_t *corner)
{
    const int32_t cell = (int32_t)cfg->cell_mm, in = (edge_cells(cfg) + 1) * cell;
    if (abs32(g - r) <= side - 2 * cell) {
        const int32_t keep = (ROBOT_IN_MM + cell - 1) / cell * cell;
        int32_t c = r / 2 + g / 2 - side / 2;
        if (2 * keep <= side) { /* a square too small to keep it that far in: midway */
            if (c > r - keep) {
                c = r - keep;
            } else if (c < r + keep - side) {
                c = r + keep - side;
            }
        }
        *corner = c;
        return 1;
    }
    if (2 * in > side) {
        return 0;
    }
    *corner = g > r ? r - in : r + in - side;
    return 1;
}

int qnav_map_place(const qnav_map_config_t *cfg, size_t len, int32_t rx_mm, int32_t ry_mm,
                   int32_t gx_mm, int32_t gy_mm, int32_t *x0_mm, int32_t *y0_mm,
                   uint32_t *side_mm)
{
    int32_t cell, side;
    if (cfg == NULL || x0_mm == NULL || y0_mm == NULL || side_mm == NULL || cfg->cell_mm == 0u) {
        return 0;
    }
    cell = (int32_t)cfg->cell_mm;
    side = (int32_t)square_cells(cfg, len) * cell;
    if (side == 0 || !place_axis(cfg, rx_mm, gx_mm, side, x0_mm) ||
        !place_axis(cfg, ry_mm, gy_mm, side, y0_mm)) {
        return 0;
    }
    *side_mm = (uint32_t)side;
    return 1;
}

qnav_status_t qnav_map_init(qnav_map_t *m, const qnav_map_config_t *cfg,
                            const qnav_ctrl_config_t *ctrl, int32_t x0_mm, int32_t y0_mm,
                            uint32_t width_mm, uint32_t height_mm, void *buf, size_t len)
{
    uint32_t cells;
    uint8_t *p = (uint8_t *)buf;
    if (m == NULL || cfg == NULL || ctrl == NULL) {
        return QNAV_E_NULL;
    }
    cells = qnav_map_cells(width_mm, height_mm, cfg->cell_mm);
    if (cfg->cell_mm < 20u || cfg->cell_mm > 1000u || cfg->plan_ticks == 0u || cells == 0u ||
        cfg->reach_mm > MAX_REACH_MM ||
        cfg->arc_cdeg > 36000u || (cfg->refuse_ticks > 0u && cfg->refuse_life_ticks == 0u) ||
        len < qnav_map_size(cfg, width_mm, height_mm) ||
        (!cfg->compact && (uintptr_t)buf % offsetof(u16_alignment_t, u) != 0u) ||
        ctrl->n_sectors == 0u || ctrl->n_sectors > QNAV_MAX_SECTORS || ctrl->max_range_mm == 0u) {
        return QNAV_E_MAP;
    }
    /* a step costs at most STEP_DIAG + 255 (the queue's buckets); the compact layout blocks
     * occupied cells only, and has no bits for near or unknown costs (nor for refusals: it
     * marks refused cells occupied, refuse_compact) */
    if (cfg->compact > 1u ||
        (uint32_t)cfg->near_cost + cfg->unknown_cost > 255u ||
        (cfg->compact && (cfg->near_cost != 0u || cfg->unknown_cost != 0u ||
                          (uint32_t)ctrl->body_radius_mm + ctrl->safety_mm >= cfg->cell_mm ||
                          (width_mm + cfg->cell_mm - 1u) / cfg->cell_mm >
                              8u * QNAV_CMAP_ROW_BYTES_MAX))) {
        return QNAV_E_MAP;
    }
    if (buf == NULL) {
        return QNAV_E_NULL;
    }
    {
        const qnav_map_config_t keep = *cfg; /* cfg may be m's own */
        memset(m, 0, sizeof *m);
        m->cfg = keep;
    }
    m->scan_sectors = ctrl->n_sectors;
    /* a compact map reads 64 sectors or more as 32 wedges; between 33 and 63 sectors as
     * many (as 32 wedges, or as fewer centred on sectors, 36 and 40 sectors lost 11 to 28
     * points: docs/architecture.md, "A compact map's wedges") */
    m->n_sectors = cfg->compact && ctrl->n_sectors >= 2u * QNAV_MAP_WEDGES_MAX
                       ? (uint16_t)QNAV_MAP_WEDGES_MAX
                       : ctrl->n_sectors;
    m->max_range_mm = ctrl->max_range_mm;
    m->offset_mm = ctrl->sensor_offset_mm;
    m->inflate_mm = (uint16_t)((uint32_t)ctrl->body_radius_mm + ctrl->safety_mm > 65535u
                                   ? 65535u
                                   : (uint32_t)ctrl->body_radius_mm + ctrl->safety_mm);
    m->peak_mm = peak_range(cfg->opening_mm, m->n_sectors);
    m->seen_mm = seen_range(cfg, ctrl);
    m->x0_mm = x0_mm;
    m->y0_mm = y0_mm;
    m->nx = (uint16_t)((width_mm + cfg->cell_mm - 1u) / cfg->cell_mm);
    m->ny = (uint16_t)(cells / m->nx);
    qnav_align_start(m, x0_mm + (int32_t)(width_mm / 2u), y0_mm + (int32_t)(height_mm / 2u));
    if (cfg->compact) {
        qnav_cmap_attach(m, buf);
    } else {
        m->q_head = (uint16_t *)(void *)p;
        m->cost = m->q_head + BUCKETS;
        m->next = m->cost + cells;
        m->prev = m->next + cells;
        m->evidence = (int8_t *)(void *)(m->prev + cells);
        m->blocked = (uint8_t *)(m->evidence + cells);
    }
    qnav_map_reset(m);
    return QNAV_OK;
}

static uint32_t cell_count(const qnav_map_t *m)
{
    return (uint32_t)m->nx * m->ny;
}

/* qnav_map_init() made m (a map it refused, or never saw, has no cells). */
static int ready(const qnav_map_t *m)
{
    return m != NULL && m->nx != 0u;
}

void qnav_map_reset(qnav_map_t *m)
{
    uint32_t i, n;
    if (!ready(m)) {
        return;
    }
    n = cell_count(m);
    if (m->cfg.compact) {
        qnav_cmap_reset(m);
    } else {
        memset(m->evidence, 0, (size_t)n);
        memset(m->blocked, 0, (size_t)n);
        for (i = 0; i < n; ++i) {
            m->cost[i] = QNAV_MAP_UNREACHED;
        }
    }
    m->ticks = 0u;
    m->last_mm = 0u;
    m->planned = 0u;
    m->dirty = 0u;
    m->grown_mm = 0u;
    m->stall_best_mm = 0u;
    m->stall_ticks = 0u;
    m->turn_back = 0u;
    m->refused_ticks = 0u;
    m->forgot = 0u;
}

/* The full layout's qnav_cmap_shift: cell (i, j) takes cell (i + di, j + dj)'s evidence
 * (unknown from outside the map; refusals forgotten). The plan's blocked cells and costs
 * are made again by the next plan. */
static void shift_evidence(qnav_map_t *m, int32_t di, int32_t dj)
{
    const int32_t nx = (int32_t)m->nx, ny = (int32_t)m->ny;
    const int32_t istep = di > 0 ? 1 : -1, jstep = dj > 0 ? 1 : -1;
    int32_t i, j, k, l;
    for (l = 0, j = dj > 0 ? 0 : ny - 1; l < ny; ++l, j += jstep) {
        for (k = 0, i = di > 0 ? 0 : nx - 1; k < nx; ++k, i += istep) {
            const int32_t si = i + di, sj = j + dj;
            int8_t e = qnav_map_in(m, si, sj) ? m->evidence[qnav_map_at(m, si, sj)] : 0;
            m->evidence[qnav_map_at(m, i, j)] = e == EVIDENCE_REFUSED ? 0 : e;
        }
    }
}

/*
 * The plan is whole and no way leads from the robot to the destination: what the arcs
 * marked closes every door. An arc marks the cells across a wide wedge, and from afar it
 * marks a doorway's cells for the wall beside it; a cell seen free stays free, but a
 * doorway seen only from afar never is. The robot was placed where the destination can
 * be reached (or a user's room would not be asked of it): forget every cell not seen free
 * (refusals too), so the plan goes through them again and the robot sees them afresh
 * from where it then stands (docs/architecture.md, "A map that closed every way").
 */
static void forget_occupied(qnav_map_t *m)
{
    uint32_t c, n = cell_count(m);
    m->forgot = 1u;
    if (m->cfg.compact) {
        qnav_cmap_forget_occupied(m);
        return;
    }
    for (c = 0; c < n; ++c) {
        if (m->evidence[c] > 0) {
            m->evidence[c] = 0;
        }
    }
    m->refused_ticks = 0u;
    m->dirty = 1u;
}

/* The cell index of coordinate v in a map whose cells start at v0; -1 for any before it. */
static int32_t index_along(int32_t v, int32_t v0, int32_t cell)
{
    return v >= v0 ? (v - v0) / cell : -1;
}

/* Whole cells from corner a to corner b (rounded to the nearest). */
static int32_t cells_between(int32_t a, int32_t b, int32_t cell)
{
    const int32_t d = b - a;
    return d >= 0 ? (d + cell / 2) / cell : -((-d + cell / 2) / cell);
}

int qnav_map_follow(qnav_map_t *m, const qnav_map_pose_t *at, int32_t goal_x_mm,
                    int32_t goal_y_mm)
{
    int32_t cell, edge, ri, rj, x0, y0, di, dj;
    qnav_map_pose_t in_grid;
    const qnav_map_pose_t *pose = &in_grid;
    if (!ready(m) || at == NULL) {
        return 0;
    }
    in_grid = qnav_align_pose(m, at);
    qnav_align_point(m, &goal_x_mm, &goal_y_mm);
    cell = (int32_t)m->cfg.cell_mm;
    edge = edge_cells(&m->cfg);
    ri = index_along(pose->x_mm, m->x0_mm, cell);
    rj = index_along(pose->y_mm, m->y0_mm, cell);
    if (ri >= edge && rj >= edge && ri < (int32_t)m->nx - edge && rj < (int32_t)m->ny - edge) {
        return 0;
    }
    if (!place_axis(&m->cfg, pose->x_mm, goal_x_mm, (int32_t)m->nx * cell, &x0) ||
        !place_axis(&m->cfg, pose->y_mm, goal_y_mm, (int32_t)m->ny * cell, &y0)) {
        return 0;
    }
    di = cells_between(m->x0_mm, x0, cell);
    dj = cells_between(m->y0_mm, y0, cell);
    if (di == 0 && dj == 0) {
        return 0;
    }
    if (m->cfg.compact) {
        qnav_cmap_shift(m, di, dj);
    } else {
        shift_evidence(m, di, dj);
    }
    m->x0_mm += di * cell;
    m->y0_mm += dj * cell;
    m->planned = 0u; /* plan again over the moved map */
    m->refused_ticks = 0u;
    return 1;
}

/* The cell holding world point (x, y), clamped into the map. */
static void cell_of(const qnav_map_t *m, int32_t x_mm, int32_t y_mm, int32_t *i, int32_t *j)
{
    int32_t a = (x_mm - m->x0_mm) / (int32_t)m->cfg.cell_mm;
    int32_t b = (y_mm - m->y0_mm) / (int32_t)m->cfg.cell_mm;
    if (x_mm < m->x0_mm) {
        a = -1;
    }
    if (y_mm < m->y0_mm) {
        b = -1;
    }
    *i = a < 0 ? 0 : (a >= (int32_t)m->nx ? (int32_t)m->nx - 1 : a);
    *j = b < 0 ? 0 : (b >= (int32_t)m->ny ? (int32_t)m->ny - 1 : b);
}

static int32_t centre_x(const qnav_map_t *m, int32_t i)
{
    return m->x0_mm + i * (int32_t)m->cfg.cell_mm + (int32_t)m->cfg.cell_mm / 2;
}

static int32_t centre_y(const qnav_map_t *m, int32_t j)
{
    return m->y0_mm + j * (int32_t)m->cfg.cell_mm + (int32_t)m->cfg.cell_mm / 2;
}

/*
 * Direction of (x, y), |x|, |y| < 2^16, in 0.01 deg, 0..35999, within 0.25 deg: in each
 * octant atan(t) ~ 45 t + 15.64 t (1 - t) deg for t = min / max in [0, 1] (largest error
 * 0.22 deg), one division. The map needs a cell's sector, not its exact direction: a cell
 * within a quarter degree of a sector's edge may take the neighbour's reading, and the
 * CORDIC's 16 steps per cell were most of the map's time.
 */
static int32_t direction_cdeg(int32_t x, int32_t y)
{
    const uint32_t ax = (uint32_t)(x < 0 ? -x : x), ay = (uint32_t)(y < 0 ? -y : y);
    const uint32_t hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    uint32_t t, a;
    if (hi == 0u) {
        return 0;
    }
    t = (lo << 15) / hi;                                        /* Q15, 0..32768 */
    a = (4500u * t + ((1564u * t) >> 15) * (32768u - t)) >> 15; /* 0..4500 */
    if (ay > ax) {
        a = 9000u - a;
    }
    if (x < 0) {
        a = 18000u - a;
    }
    return y < 0 ? (int32_t)(36000u - a) % 36000 : (int32_t)a;
}

/* The sector whose wedge holds robot-frame direction a, 0..35999 (0.01 deg). */
static uint16_t sector_of(const qnav_map_t *m, int32_t a_cdeg)
{
    /* sector k is centred on k * 360 / N: round a * N / 360 deg (a in [0, 36000)) */
    const uint32_t k = ((uint32_t)a_cdeg * m->n_sectors + 18000u) / 36000u;
    return (uint16_t)(k == m->n_sectors ? 0u : k);
}

/* How far robot-frame direction a (0.01 deg) lies from a sector's centre, 0.01 deg. */
static int32_t off_centre(int32_t a_cdeg, int32_t centre_cdeg)
{
    int32_t d = a_cdeg - centre_cdeg; /* both in [0, 36000) */
    if (d < -INT32_C(18000)) {
        d += INT32_C(36000);
    } else if (d >= INT32_C(18000)) {
        d -= INT32_C(36000);
    }
    return d < 0 ? -d : d;
}

/* Cell (i, j)'s evidence: < 0 seen free (EVIDENCE_FREE_MIN: at its floor), 0 unknown, then
 * the arcs' counts; EVIDENCE_REFUSED refused. */
static int8_t evidence_at(const qnav_map_t *m, int32_t i, int32_t j)
{
    return m->cfg.compact ? qnav_cmap_evidence(m, i, j) : m->evidence[qnav_map_at(m, i, j)];
}

/* Seen free: any occupied evidence is dropped, free evidence grows to its floor. */
static void mark_clear(qnav_map_t *m, int32_t i, int32_t j)
{
    int8_t *c, v;
    if (m->cfg.compact) {
        qnav_cmap_clear(m, i, j);
        return;
    }
    c = &m->evidence[qnav_map_at(m, i, j)];
    v = (int8_t)((*c > 0 ? 0 : *c) - 1);
    if (*c == EVIDENCE_REFUSED) {
        return;
    }
    if (*c >= QNAV_MAP_OCCUPIED) {
        m->dirty = 1u;
    }
    *c = v < EVIDENCE_FREE_MIN ? (int8_t)EVIDENCE_FREE_MIN : v;
}

/* One more arc's evidence on a cell never seen free. */
static void mark_arc(qnav_map_t *m, int32_t i, int32_t j)
{
    int8_t *c;
    if (m->cfg.compact) {
        qnav_cmap_arc(m, i, j);
        return;
    }
    c = &m->evidence[qnav_map_at(m, i, j)];
    *c = (int8_t)(*c + 1 > EVIDENCE_MAX ? EVIDENCE_MAX : *c + 1);
    if (*c == QNAV_MAP_OCCUPIED) {
        m->dirty = 1u;
    }
}

/* Readings this near the robot's centre mark cells: after a forget only those within
 * forget_reach_mm (the map's "Marking near after a forget"), else every one. */
static int32_t marks_within(const qnav_map_t *m)
{
    return m->forgot && m->cfg.forget_reach_mm != 0u ? (int32_t)m->cfg.forget_reach_mm : INT32_MAX;
}

/* 1 when sector k's reading, rc from the robot's centre, may mark an arc: not a range
 * peak (farther than both neighbouring sectors' readings) as far as peak_mm or farther,
 * where a wide wedge reads an opening's two sides (qnav_map_config_t.opening_mm). */
static int may_mark(const qnav_map_t *m, const qnav_mm_t *ranges_mm, uint16_t k, int32_t rc)
{
    const uint16_t n = m->n_sectors;
    const qnav_mm_t r = ranges_mm[k];
    if (m->peak_mm == 0u || rc < (int32_t)m->peak_mm) {
        return 1;
    }
    return !(ranges_mm[k == 0u ? n - 1u : k - 1u] < r && ranges_mm[k + 1u == n ? 0u : k + 1u] < r);
}

/* One sector's reading and what follows from it for the cells in its wedge: cells in a row
 * often share a sector, and each costs divisions (an AVR's are hundreds of cycles). */
typedef struct {
    uint16_t k;    /* the sector; UINT16_MAX: none yet */
    int32_t rc;    /* the reading from the robot's centre, mm */
    int32_t lo;    /* cells nearer than this are seen clear */
    int32_t band;  /* cells from this to rc + 3/4 cell may take the arc */
    int32_t centre; /* the wedge's centre line, robot frame, 0.01 deg */
    int marks;     /* the reading may mark an arc: near enough (marks_within), and not a
                      far range peak (may_mark) */
} reading_t;

/* 9 000 / pi, rounded: a width w across at range r is a half-angle of w / 2 / r radians,
 * w * CDEG_PER_RAD_HALF / r in 0.01 deg. */
#define CDEG_PER_RAD_HALF 2865u

/* 1 when a cell off_cdeg off reading r's centre line lies on its arc: within arc_half, and
 * within the arc's width at r's range, off_cdeg <= width_k / rc with width_k =
 * arc_width_mm * CDEG_PER_RAD_HALF (0: no bound), compared as a product (no division on
 * an AVR): off_cdeg <= 18 000 and rc < 2^17 (a range and the sonar's offset, each below
 * 2^16), so the product is below 2^32. */
static int on_arc(int32_t off_cdeg, const reading_t *r, int32_t arc_half, uint32_t width_k)
{
    return off_cdeg <= arc_half &&
           (width_k == 0u || (uint32_t)off_cdeg * (uint32_t)r->rc <= width_k);
}

static void read_sector(const qnav_map_t *m, const qnav_mm_t *ranges_mm, uint16_t k,
                        int32_t three_quarters, int32_t band_pct, int32_t mark_reach,
                        reading_t *r)
{
    r->k = k;
    r->rc = (int32_t)ranges_mm[k] + (int32_t)m->offset_mm;
    /* not seen clear within 3/4 cell and the noise of the reading, occupied from band */
    r->lo = r->rc - three_quarters - r->rc * (int32_t)m->cfg.noise_pct / 100;
    r->band = r->rc - three_quarters - r->rc * band_pct / 100;
    r->centre = (int32_t)((uint32_t)k * 36000u / m->n_sectors);
    r->marks = r->rc <= mark_reach && may_mark(m, ranges_mm, k, r->rc);
}

static void observe_wedges(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at);

/* On hosts the marking takes a shorter way to the same marks (observe_fast); the ATmega128
 * and the Cortex-M4 keep observe_wedges, whose stack and cycles their benches measure. */
#if !defined(__AVR__) && !(defined(__ARM_ARCH_PROFILE) && __ARM_ARCH_PROFILE == 'M') &&          \
    defined(__GNUC__)
#define HOST_MARK 1
static void observe_fast(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at);
#define OBSERVE(m, r, at, plain) ((plain) ? observe_wedges(m, r, at) : observe_fast(m, r, at))
#define PLAIN_PARAM , int plain
#define PLAIN_ARG(p) , (p)
#else
#define HOST_MARK 0
#define OBSERVE(m, r, at, plain) observe_wedges(m, r, at)
#define PLAIN_PARAM
#define PLAIN_ARG(p)
#endif

/* The scan's scan_sectors readings as the map's n_sectors wedges (fewer): wedge w, centred
 * on w * 360 / n_sectors degrees, takes the least reading of the sectors whose centres lie
 * within half a wedge of its centre, a sector on the boundary in both. A wedge narrower
 * than a cell judges each cell by the one sector through its centre, which along a wall
 * seen at a slant reads far past the wall's own cell and carves it free for good; wedges
 * whose reading is their nearest point, as a 16- or 32-sector sonar's is, do not (measured:
 * docs/results.md, "A compact map's wedges"). Out of line, so that its array is on the
 * stack only for such a scan. */
#if defined(__AVR__)
__attribute__((noinline))
#endif
static void observe_grouped(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at
                            PLAIN_PARAM)
{
    qnav_mm_t wedge[QNAV_MAP_WEDGES_MAX];
    /* 16-bit throughout: n <= 360 and g <= 32, so a turn is at most 11 520 units */
    const uint16_t n = m->scan_sectors, g = m->n_sectors, turn = (uint16_t)(n * g);
    uint16_t k, w;
    for (w = 0; w < g; ++w) {
        wedge[w] = m->max_range_mm;
    }
    for (k = 0; k < n; ++k) {
        /* sector k's centre is k * g and wedge w's w * n, in 1 / (n * g) of a turn; the
         * nearest wedge and the ones beside it may hold it (on a boundary, two do) */
        const uint16_t near = (uint16_t)((uint16_t)((uint16_t)(k * g * 2u) + n) / (uint16_t)(2u * n));
        for (w = (uint16_t)(near + g - 1u); w <= near + g + 1u; ++w) {
            const uint16_t ww = (uint16_t)(w % g);
            int16_t d = (int16_t)((uint16_t)(k * g + turn - ww * n) % turn); /* [0, turn) */
            if (d > (int16_t)(turn / 2u)) {
                d = (int16_t)(d - (int16_t)turn);
            }
            if ((uint16_t)(2 * (d < 0 ? -d : d)) <= n && ranges_mm[k] < wedge[ww]) {
                wedge[ww] = ranges_mm[k];
            }
        }
    }
    OBSERVE(m, wedge, at, plain);
}

void qnav_map_observe(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at)
{
    if (!ready(m) || ranges_mm == NULL || at == NULL) {
        return;
    }
    if (m->scan_sectors > m->n_sectors) {
        observe_grouped(m, ranges_mm, at PLAIN_ARG(0));
        return;
    }
    OBSERVE(m, ranges_mm, at, 0);
}

#if HOST_MARK
void qnav_map_observe_plain(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at)
{
    if (!ready(m) || ranges_mm == NULL || at == NULL) {
        return;
    }
    if (m->scan_sectors > m->n_sectors) {
        observe_grouped(m, ranges_mm, at, 1);
        return;
    }
    observe_wedges(m, ranges_mm, at);
}
#endif

/* Which of cells 8b .. 8b + 7 of row j a reading may change, cell 8b + k in bit k (the
 * bits of cells past the row's end say nothing): not free at its floor, nor refused.
 * *arcs: which may take an arc's evidence (never seen free). */
static uint8_t unsettled(const qnav_map_t *m, int32_t b, int32_t j, uint8_t *arcs)
{
    uint8_t todo = 0u, k;
    if (m->cfg.compact) {
        *arcs = (uint8_t)~qnav_cmap_free_bits(m, b, j);
        return *arcs;
    }
    *arcs = 0u;
    for (k = 0; k < 8u && b * 8 + k < (int32_t)m->nx; ++k) {
        const int8_t c = m->evidence[qnav_map_at(m, b * 8 + k, j)];
        if (c != EVIDENCE_FREE_MIN && c != EVIDENCE_REFUSED) {
            todo = (uint8_t)(todo | (1u << k));
            *arcs = (uint8_t)(*arcs | (c >= 0 ? 1u << k : 0u));
        }
    }
    return todo;
}

/* qnav_map_observe() for a scan of the map's own n_sectors wedges.
 *
 * Squares are unsigned 32-bit (a 64-bit product costs an AVR hundreds of cycles): with
 * reach_mm at most MAX_REACH_MM and cells at most 1 000 mm, a cell's offset from the robot
 * is at most 41 000 mm along each axis, and the squared distance of a cell within reach at
 * most 2 x 41 000^2 < 2^32. A distance beyond the reach is compared as such, not squared.
 */
static void observe_wedges(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at)
{
    int32_t i0, i1, j0, j1, i, j, reach, mark_reach, three_quarters, heading, arc_half, band_pct;
    uint32_t reach2;
    const uint32_t width_k = (uint32_t)m->cfg.arc_width_mm * CDEG_PER_RAD_HALF; /* < 2^28 */
    reading_t last;
    qnav_map_pose_t in_grid;
    const qnav_map_pose_t *pose = &in_grid;
    if (qnav_align_observe(m, ranges_mm, at)) {
        qnav_map_reset(m); /* what the old grid held, forgotten: its cells lie another way */
    }
    in_grid = qnav_align_pose(m, at);
    memset(&last, 0, sizeof last);
    last.k = UINT16_MAX;
    three_quarters = (int32_t)m->cfg.cell_mm * 3 / 4;
    reach = (int32_t)m->seen_mm;
    reach2 = (uint32_t)reach * (uint32_t)reach;
    mark_reach = marks_within(m);
    band_pct = m->cfg.noise_pct < OCCUPIED_BAND_PCT ? (int32_t)m->cfg.noise_pct : OCCUPIED_BAND_PCT;
    heading = qnav_wrap_cdeg(pose->heading_cdeg);
    arc_half = INT32_C(18000) / (int32_t)m->n_sectors; /* the whole wedge, or the set arc */
    if ((int32_t)m->cfg.arc_cdeg / 2 < arc_half) {
        arc_half = (int32_t)m->cfg.arc_cdeg / 2;
    }
    cell_of(m, pose->x_mm - reach, pose->y_mm - reach, &i0, &j0);
    cell_of(m, pose->x_mm + reach, pose->y_mm + reach, &i1, &j1);
    for (j = j0; j <= j1; ++j) {
        const int32_t dy = centre_y(m, j) - pose->y_mm;
        const uint32_t dy2 = (uint32_t)(dy < 0 ? -dy : dy) * (uint32_t)(dy < 0 ? -dy : dy);
        int32_t dx = centre_x(m, i0) - pose->x_mm - (int32_t)m->cfg.cell_mm;
        uint8_t todo = 0u, arcs = 0u; /* cells i.. of i's byte (unsettled), cell i in bit 0 */
        if (dy2 > reach2) {
            continue;
        }
        for (i = i0; i <= i1; ++i, todo >>= 1, arcs >>= 1) {
            uint32_t d2;
            uint16_t k;
            int32_t rel;
            dx += (int32_t)m->cfg.cell_mm;
            if (i == i0 || (i & 7) == 0) {
                /* a byte's cells at once: a compact map's without a call each */
                todo = (uint8_t)(unsettled(m, i >> 3, j, &arcs) >> (i & 7));
                arcs = (uint8_t)(arcs >> (i & 7));
            }
            if ((todo & 1u) == 0u) {
                continue; /* no reading changes it: free at its floor, or refused */
            }
            d2 = (uint32_t)(dx < 0 ? -dx : dx) * (uint32_t)(dx < 0 ? -dx : dx) + dy2;
            if (d2 > reach2 || d2 == 0) {
                continue;
            }
            /* heading is in [-18000, 18000): rel in (-18000, 54000) before the wrap */
            rel = direction_cdeg(dx, dy) - heading;
            rel += rel < 0 ? INT32_C(36000) : (rel >= INT32_C(36000) ? -INT32_C(36000) : 0);
            k = sector_of(m, rel);
            if (ranges_mm[k] >= m->max_range_mm) {
                /* nothing in the wedge: free out to the reach */
                mark_clear(m, i, j);
                continue;
            }
            if (k != last.k) {
                read_sector(m, ranges_mm, k, three_quarters, band_pct, mark_reach, &last);
            }
            if (last.lo > 0 && (last.lo > reach || d2 < (uint32_t)last.lo * (uint32_t)last.lo)) {
                mark_clear(m, i, j);
            } else if (last.marks && (arcs & 1u) != 0u &&
                       (last.rc + three_quarters > reach ||
                        d2 <= (uint32_t)(last.rc + three_quarters) * (uint32_t)(last.rc + three_quarters)) &&
                       (last.band <= 0 ||
                        (last.band <= reach && d2 >= (uint32_t)last.band * (uint32_t)last.band)) &&
                       on_arc(off_centre(rel, last.centre), &last, arc_half, width_k)) {
                mark_arc(m, i, j);
            }
        }
    }
}

#if HOST_MARK
/* What sector k's reading does to a cell d2 (squared mm) from the robot's centre, as
 * observe_wedges' tests decide it: the cell is seen clear when d2 < clear_below, else it
 * may take an arc's evidence when arc_from <= d2 <= arc_to (none when arc_from > arc_to)
 * and on_arc() holds for r (of which only rc and centre are set). The squares are those
 * observe_wedges compares, or UINT32_MAX / 0 where it decides by the distance alone (a d2
 * within reach is below 2^32 - 1). */
typedef struct {
    uint32_t clear_below, arc_from, arc_to;
    reading_t r;
} wedge_rule_t;

#define RULES_MAX 64u

/* read_sector()'s reading of sector k as a rule. */
static void rule_of(const qnav_map_t *m, const qnav_mm_t *ranges_mm, uint16_t k,
                    int32_t three_quarters, int32_t band_pct, int32_t mark_reach, int32_t reach,
                    wedge_rule_t *w)
{
    const int32_t rc = (int32_t)ranges_mm[k] + (int32_t)m->offset_mm;
    int32_t lo, band, top;
    w->arc_from = UINT32_MAX;
    w->arc_to = 0u;
    if (ranges_mm[k] >= m->max_range_mm) {
        w->clear_below = UINT32_MAX; /* nothing in the wedge: free out to the reach */
        return;
    }
    lo = rc - three_quarters - rc * (int32_t)m->cfg.noise_pct / 100;
    band = rc - three_quarters - rc * band_pct / 100;
    w->clear_below = lo <= 0 ? 0u : lo > reach ? UINT32_MAX : (uint32_t)lo * (uint32_t)lo;
    if (rc > mark_reach || band > reach || !may_mark(m, ranges_mm, k, rc)) {
        return;
    }
    top = rc + three_quarters;
    w->arc_to = top > reach ? UINT32_MAX : (uint32_t)top * (uint32_t)top;
    w->arc_from = band <= 0 ? 0u : (uint32_t)band * (uint32_t)band;
    w->r.rc = rc;
    w->r.centre = (int32_t)((uint32_t)k * 36000u / m->n_sectors);
}

/* direction_cdeg()'s octants, o = (y < 0) * 4 + (x < 0) * 2 + (|y| > |x|): the direction is
 * OCTANT_AT[o] + OCTANT_TURN[o] * a modulo 36 000, a = the octant's own angle (0..4500). */
static const int32_t OCTANT_AT[8] = {0, 9000, 18000, 9000, 0, 27000, 18000, 27000};
static const int32_t OCTANT_TURN[8] = {1, -1, -1, 1, -1, 1, 1, -1};

/* A cell dx (mm) across from the robot is within reach on a row that leaves rem (mm^2). */
static int in_reach(int32_t dx, uint32_t rem)
{
    const uint32_t a = (uint32_t)(dx < 0 ? -dx : dx);
    return a * a <= rem;
}

/* A row's cells i0 .. i1 within reach, *ia .. *ib (none: *ia > *ib), moved there from the
 * last row's (or from i0 .. i1). Cell i lies dx0 + (i - i0) * cell across from the robot
 * and is within reach when dx^2 <= rem: every row's cells within reach are those whose
 * |dx| is at most a bound, intervals about one column that hold each other. */
static void row_ends(int32_t dx0, int32_t cell, uint32_t rem, int32_t i0, int32_t i1, int32_t *ia,
                     int32_t *ib)
{
    int32_t a = *ia, b = *ib;
    if (a > b) { /* the last row had none: from this row's cell nearest the robot */
        a = b = dx0 >= 0 ? i0 : (-dx0 / cell > i1 - i0 ? i1 : i0 + -dx0 / cell);
    }
    if (in_reach(dx0 + (a - i0) * cell, rem)) {
        while (a > i0 && in_reach(dx0 + (a - 1 - i0) * cell, rem)) {
            --a;
        }
    } else {
        while (a <= i1 && !in_reach(dx0 + (a - i0) * cell, rem)) {
            ++a;
        }
    }
    if (a > i1) {
        b = a - 1; /* none */
    } else {
        b = b < a ? a : b;
        if (in_reach(dx0 + (b - i0) * cell, rem)) {
            while (b < i1 && in_reach(dx0 + (b + 1 - i0) * cell, rem)) {
                ++b;
            }
        } else {
            while (!in_reach(dx0 + (b - i0) * cell, rem)) { /* ends at latest at a */
                --b;
            }
        }
    }
    *ia = a;
    *ib = b;
}

/* What observe_fast works out once a scan. */
typedef struct {
    wedge_rule_t rules[RULES_MAX];
    int32_t from[8]; /* OCTANT_AT less the heading, 0..35999 */
    int32_t arc_half;
    uint32_t width_k;
} scan_rules_t;

/* A row's cells as mark_cell() needs them: dy along from the robot (ady = |dy|, dy2 = dy^2),
 * cell i0 dx0 across, and the octants' starts and turns on dy's side. */
typedef struct {
    int32_t j, dx0, i0;
    uint32_t ady, dy2;
    const int32_t *from, *turn;
} mark_row_t;

/* Cell i of row r, unsettled, marked; may_arc: it may take an arc's evidence. */
static inline void mark_cell(qnav_map_t *m, const scan_rules_t *s, const mark_row_t *r, int32_t i,
                             unsigned may_arc)
{
    const int32_t dx = r->dx0 + (i - r->i0) * (int32_t)m->cfg.cell_mm;
    const uint32_t adx = (uint32_t)(dx < 0 ? -dx : dx), d2 = adx * adx + r->dy2;
    const unsigned o = (dx < 0 ? 2u : 0u) | (r->ady > adx ? 1u : 0u);
    const uint32_t hi = r->ady > adx ? r->ady : adx, lo = r->ady > adx ? adx : r->ady;
    const wedge_rule_t *w;
    uint32_t t, a;
    int32_t rel;
    if (d2 == 0u) {
        return;
    }
    t = (lo << 15) / hi;                                        /* direction_cdeg's */
    a = (4500u * t + ((1564u * t) >> 15) * (32768u - t)) >> 15; /* 0..4500 */
    rel = r->from[o] + r->turn[o] * (int32_t)a;
    rel += rel < 0 ? INT32_C(36000) : (rel >= INT32_C(36000) ? -INT32_C(36000) : 0);
    w = &s->rules[sector_of(m, rel)];
    if (d2 < w->clear_below) {
        mark_clear(m, i, r->j);
    } else if (may_arc && d2 >= w->arc_from && d2 <= w->arc_to &&
               on_arc(off_centre(rel, w->r.centre), &w->r, s->arc_half, s->width_k)) {
        mark_arc(m, i, r->j);
    }
}

/* Row r's unsettled cells ia .. ib marked. A compact map's rows of 4 to 8 bytes on hosts are
 * one word: their cells not seen free are taken from it by their set bits, without a loop
 * over its bytes (a compact map's unsettled cells are those that may take an arc). */
static void mark_row(qnav_map_t *m, const scan_rules_t *s, const mark_row_t *r, int32_t ia,
                     int32_t ib)
{
    int32_t b;
#if QNAV_CMAP_FREE_ROWS
    if (m->cfg.compact && m->row_bytes >= 4u && m->row_bytes <= 8u && ia <= ib) {
        uint64_t todo = ~qnav_cmap_free_row(m, r->j) & (~UINT64_C(0) << ia) &
                        (~UINT64_C(0) >> (63 - ib));
        while (todo != 0u) {
            const int32_t i = __builtin_ctzll(todo);
            todo &= todo - 1u;
            mark_cell(m, s, r, i, 1u);
        }
        return;
    }
#endif
    for (b = ia >> 3; b <= ib >> 3 && ia <= ib; ++b) {
        uint8_t arcs, todo = unsettled(m, b, r->j, &arcs);
        if (b == ia >> 3) {
            todo = (uint8_t)(todo & (0xFFu << (ia & 7)));
        }
        if (b == ib >> 3) {
            todo = (uint8_t)(todo & (0xFFu >> (7 - (ib & 7))));
        }
        while (todo != 0u) {
            const unsigned bit = (unsigned)__builtin_ctz(todo);
            todo = (uint8_t)(todo & (todo - 1u));
            mark_cell(m, s, r, b * 8 + (int32_t)bit, (unsigned)arcs >> bit & 1u);
        }
    }
}

/* observe_wedges() with the same marks, on hosts: each row's cells within reach found from
 * the last row's (row_ends), the unsettled ones among them taken by their set bits, every
 * sector's tests worked out once a scan (a row's cells change sector every cell or two),
 * and a cell's direction less the heading (direction_cdeg()'s) from its octant's start
 * less the heading, worked out once a scan. */
static void observe_fast(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at)
{
    int32_t i0, i1, j0, j1, j, ia, ib, reach, mark_reach, three_quarters, heading, band_pct;
    uint32_t reach2;
    const int32_t cell = (int32_t)m->cfg.cell_mm;
    scan_rules_t s;
    mark_row_t r;
    qnav_map_pose_t in_grid;
    const qnav_map_pose_t *pose = &in_grid;
    uint16_t k;
    if (m->n_sectors > RULES_MAX) {
        observe_wedges(m, ranges_mm, at);
        return;
    }
    if (qnav_align_observe(m, ranges_mm, at)) {
        qnav_map_reset(m); /* what the old grid held, forgotten: its cells lie another way */
    }
    in_grid = qnav_align_pose(m, at);
    three_quarters = cell * 3 / 4;
    reach = (int32_t)m->seen_mm;
    reach2 = (uint32_t)reach * (uint32_t)reach;
    mark_reach = marks_within(m);
    band_pct = m->cfg.noise_pct < OCCUPIED_BAND_PCT ? (int32_t)m->cfg.noise_pct : OCCUPIED_BAND_PCT;
    heading = qnav_wrap_cdeg(pose->heading_cdeg);
    s.width_k = (uint32_t)m->cfg.arc_width_mm * CDEG_PER_RAD_HALF; /* < 2^28 */
    s.arc_half = INT32_C(18000) / (int32_t)m->n_sectors;
    if ((int32_t)m->cfg.arc_cdeg / 2 < s.arc_half) {
        s.arc_half = (int32_t)m->cfg.arc_cdeg / 2;
    }
    for (k = 0; k < m->n_sectors; ++k) {
        rule_of(m, ranges_mm, k, three_quarters, band_pct, mark_reach, reach, &s.rules[k]);
    }
    for (k = 0; k < 8u; ++k) { /* heading in [-18000, 18000) */
        const int32_t f = OCTANT_AT[k] - heading;
        s.from[k] = f < 0 ? f + INT32_C(36000) : (f >= INT32_C(36000) ? f - INT32_C(36000) : f);
    }
    cell_of(m, pose->x_mm - reach, pose->y_mm - reach, &i0, &j0);
    cell_of(m, pose->x_mm + reach, pose->y_mm + reach, &i1, &j1);
    ia = i0;
    ib = i1;
    r.i0 = i0;
    r.dx0 = centre_x(m, i0) - pose->x_mm; /* cell i0's */
    for (j = j0; j <= j1; ++j) {
        const int32_t dy = centre_y(m, j) - pose->y_mm;
        r.j = j;
        r.ady = (uint32_t)(dy < 0 ? -dy : dy);
        r.dy2 = r.ady * r.ady;
        r.from = dy < 0 ? s.from + 4 : s.from;
        r.turn = dy < 0 ? OCTANT_TURN + 4 : OCTANT_TURN;
        if (r.dy2 > reach2) {
            continue;
        }
        row_ends(r.dx0, cell, reach2 - r.dy2, i0, i1, &ia, &ib);
        mark_row(m, &s, &r, ia, ib);
    }
}
#endif

/*
 * Dijkstra's queue: Dial's buckets. Every step costs at most STEP_DIAG + near_cost, so the
 * queued costs lie within that many of the least, and a ring of that many + 1 buckets,
 * each a doubly linked list of cells (next in m->next, previous in m->prev), pops cells in
 * order of cost in constant time; a binary heap took most of the plan's time.
 */
#define QUEUE_HEAD UINT16_C(0xFFFE) /* prev[] of the first cell of its bucket */
#define QUEUE_END UINT16_C(0xFFFF)  /* next[] of the last cell of its bucket */
typedef char buckets_fit_the_largest_step[BUCKETS == STEP_DIAG + 255u + 1u ? 1 : -1];

/* The bucket of a queued cost: costs queued lie in [q_cost, q_cost + q_count), and q_cost's
 * bucket is q_slot (q_cost mod q_count, kept without a division). */
static uint32_t bucket_of(const qnav_map_t *m, uint32_t cost)
{
    const uint32_t b = m->q_slot + (cost - m->q_cost);
    return b >= m->q_count ? b - m->q_count : b;
}

static void queue_push(qnav_map_t *m, uint16_t cell)
{
    uint16_t *head = &m->q_head[bucket_of(m, m->cost[cell])];
    m->next[cell] = *head;
    m->prev[cell] = QUEUE_HEAD;
    if (*head != QUEUE_END) {
        m->prev[*head] = cell;
    }
    *head = cell;
}

static void queue_unlink(qnav_map_t *m, uint16_t cell)
{
    const uint16_t prev = m->prev[cell], next = m->next[cell];
    if (prev == QUEUE_HEAD) {
        m->q_head[bucket_of(m, m->cost[cell])] = next;
    } else {
        m->next[prev] = next;
    }
    if (next != QUEUE_END) {
        m->prev[next] = prev;
    }
    m->prev[cell] = NOT_QUEUED;
}

/* Cells within the body's reach of an occupied cell cannot hold the robot's centre
 * (BLOCKED); cells within near_mm more cost more to cross (NEAR), so the plan keeps off
 * walls and wall ends where it has room. */
#define BLOCKED 2u
#define NEAR 1u
static void mark_blocked(qnav_map_t *m)
{
    const int32_t cell = (int32_t)m->cfg.cell_mm;
    const int32_t outer = (int32_t)m->inflate_mm + (int32_t)m->cfg.near_mm;
    const int32_t n = (outer + cell - 1) / cell;
    const int64_t r2 = (int64_t)m->inflate_mm * m->inflate_mm;
    const int64_t o2 = (int64_t)outer * outer;
    const int32_t nx = (int32_t)m->nx, ny = (int32_t)m->ny;
    int32_t i, j, a, b;
    memset(m->blocked, 0, (size_t)cell_count(m));
    for (j = 0; j < ny; ++j) {
        for (i = 0; i < nx; ++i) {
            /* the disc of radius n cells about (i, j), cut to the map */
            const int32_t a0 = i < n ? -i : -n, a1 = nx - 1 - i < n ? nx - 1 - i : n;
            const int32_t b0 = j < n ? -j : -n, b1 = ny - 1 - j < n ? ny - 1 - j : n;
            if (m->evidence[qnav_map_at(m, i, j)] < QNAV_MAP_OCCUPIED) {
                continue;
            }
            for (b = b0; b <= b1; ++b) {
                uint8_t *row = &m->blocked[qnav_map_at(m, i, j + b)];
                const int64_t bb = (int64_t)b * b * cell * cell;
                for (a = a0; a <= a1; ++a) {
                    const int64_t d2 = bb + (int64_t)a * a * cell * cell;
                    if (d2 <= r2) {
                        row[a] = BLOCKED;
                    } else if (d2 <= o2 && row[a] < NEAR) {
                        row[a] = NEAR;
                    }
                }
            }
        }
    }
}

/* A new plan: every cell unreached but the destination's, queued. Cells are settled by
 * settle_one(), as far as they are needed. */
static void plan_start(qnav_map_t *m, int32_t goal_x_mm, int32_t goal_y_mm)
{
    uint32_t n = cell_count(m), c;
    int32_t gi, gj;
    m->goal_x_mm = goal_x_mm;
    m->goal_y_mm = goal_y_mm;
    m->planned = 1u;
    m->ticks = 0u;
    m->dirty = 0u;
    cell_of(m, goal_x_mm, goal_y_mm, &gi, &gj);
    if (m->cfg.compact) {
        qnav_cmap_plan_start(m, qnav_map_at(m, gi, gj));
        return;
    }
    mark_blocked(m);
    /* every cost QNAV_MAP_UNREACHED, every cell NOT_QUEUED: both all ones */
    memset(m->cost, 0xFF, (size_t)n * sizeof m->cost[0]);
    memset(m->prev, 0xFF, (size_t)n * sizeof m->prev[0]);
    m->q_count = (uint16_t)(STEP_DIAG + m->cfg.near_cost + m->cfg.unknown_cost + 1u);
    for (c = 0; c < m->q_count; ++c) {
        m->q_head[c] = QUEUE_END;
    }
    c = qnav_map_at(m, gi, gj);
    m->cost[c] = 0u;
    m->q_cost = 0u;
    m->q_slot = 0u;
    queue_push(m, (uint16_t)c);
    m->q_queued = 1u;
}

/* Cell c's cost is final: taken from the queue. */
static int settled(const qnav_map_t *m, uint32_t c)
{
    return m->cost[c] != QNAV_MAP_UNREACHED && m->prev[c] == NOT_QUEUED;
}

/* Lower cell 'to''s cost to 'here' + step (+ near_cost beside a wall, + unknown_cost when
 * no reading has marked it) when that is less, and queue it; a blocked cell is never
 * entered. */
static inline void relax(qnav_map_t *m, uint32_t here, uint32_t to, uint32_t step)
{
    uint32_t nc;
    if (m->blocked[to] == BLOCKED) {
        return;
    }
    nc = here + step + (m->blocked[to] == NEAR ? m->cfg.near_cost : 0u) +
         (m->evidence[to] == 0 ? m->cfg.unknown_cost : 0u);
    if (nc >= m->cost[to]) {
        return;
    }
    if (m->prev[to] != NOT_QUEUED) {
        queue_unlink(m, (uint16_t)to);
        m->q_queued--;
    }
    m->cost[to] = (uint16_t)(nc >= QNAV_MAP_UNREACHED ? QNAV_MAP_UNREACHED - 1u : nc);
    queue_push(m, (uint16_t)to);
    m->q_queued++;
}

/*
 * One step of Dijkstra's from where the plan stopped: the cheapest queued cell, when its
 * cost is at most 'bound', is taken from the queue (its cost final: *popped) and its 8
 * neighbours relaxed (a diagonal only when neither cell it passes is blocked: no corner
 * cutting); 0 when no queued cell costs that little. Cells leave the queue in order of
 * cost, so when a cell is taken every cheaper cell has been: steepest descent from a taken
 * cell sees the costs a whole plan would give.
 */
static inline int settle_one(qnav_map_t *m, uint32_t bound, uint16_t *popped)
{
    const uint32_t nx = m->nx;
    uint32_t at, here, i, j;
    int w, e, s, n;
    if (m->q_queued == 0u) {
        return 0;
    }
    while (m->q_head[m->q_slot] == QUEUE_END) {
        m->q_cost++;
        m->q_slot = (uint16_t)(m->q_slot + 1u == m->q_count ? 0u : m->q_slot + 1u);
    }
    if (m->q_cost > bound) {
        return 0;
    }
    at = m->q_head[m->q_slot];
    queue_unlink(m, (uint16_t)at);
    m->q_queued--;
    here = m->cost[at];
    i = at % nx;
    j = at / nx;
    /* which neighbours exist, and which can be passed (for the diagonals) */
    w = i > 0u;
    e = i + 1u < nx;
    s = j > 0u;
    n = j + 1u < m->ny;
    if (w) {
        relax(m, here, at - 1u, STEP_SIDE);
        w = m->blocked[at - 1u] != BLOCKED;
    }
    if (e) {
        relax(m, here, at + 1u, STEP_SIDE);
        e = m->blocked[at + 1u] != BLOCKED;
    }
    if (s) {
        relax(m, here, at - nx, STEP_SIDE);
        s = m->blocked[at - nx] != BLOCKED;
    }
    if (n) {
        relax(m, here, at + nx, STEP_SIDE);
        n = m->blocked[at + nx] != BLOCKED;
    }
    if (s && w) {
        relax(m, here, at - nx - 1u, STEP_DIAG);
    }
    if (s && e) {
        relax(m, here, at - nx + 1u, STEP_DIAG);
    }
    if (n && w) {
        relax(m, here, at + nx - 1u, STEP_DIAG);
    }
    if (n && e) {
        relax(m, here, at + nx + 1u, STEP_DIAG);
    }
    *popped = (uint16_t)at;
    return 1;
}

/* The compact layout's plan as far as cell (ri, rj) needs (all of it: ri < 0). Its step
 * counts modulo 3 lead the way exactly when grown over one state of the cells, so a plan
 * whose growth is not bounded starts again when it must grow after a cell became or
 * stopped being occupied (1: it did). A bounded growth (grow_steps) goes on over the
 * ticks it takes: starting again could starve it while the robot keeps seeing new cells,
 * and a way misread where a cell changed meanwhile lasts until the next plan (the walks
 * along it are bounded: map_compact.c). */
static int settle_compact(qnav_map_t *m, int32_t ri, int32_t rj)
{
    int again = 0;
    if (m->dirty && (ri < 0 || m->cfg.grow_steps == 0u) && qnav_cmap_needs_growth(m, ri, rj)) {
        plan_start(m, m->goal_x_mm, m->goal_y_mm);
        again = 1;
    }
    qnav_cmap_settle(m, ri, rj);
    return again;
}

/* The whole plan: every cell's cost final. */
static void settle_all(qnav_map_t *m)
{
    uint16_t c;
    if (m->cfg.compact) {
        (void)settle_compact(m, -1, 0);
        return;
    }
    while (settle_one(m, UINT32_MAX, &c)) {
    }
}

/*
 * Settle as much of the plan as the robot's cell (ri, rj) needs this tick (1: the plan
 * started again for it, compact layout only): its own cost,
 * or, when it is blocked (the robot stands near a wall) and so never reached, every cost
 * cost_near() could choose in the 5 x 5 cells about it. Their least cost c is the first of
 * them taken from the queue; cost_near() chooses at most c + 40 (4 cell sides away), and a
 * cell costing more than c + 30 lies at least a side away, beyond c + 40: so cells up to
 * c + 30 are settled, and cost_near() chooses as after a whole plan.
 */
static int settle_for(qnav_map_t *m, int32_t ri, int32_t rj)
{
    const uint32_t robot = qnav_map_at(m, ri, rj);
    uint32_t least = QNAV_MAP_UNREACHED;
    uint16_t c;
    int32_t a, b;
    if (m->cfg.compact) {
        return settle_compact(m, ri, rj);
    }
    if (m->cost[robot] != QNAV_MAP_UNREACHED || m->blocked[robot] != BLOCKED) {
        while (!settled(m, robot) && settle_one(m, UINT32_MAX, &c)) {
        }
        return 0; /* settled, or nothing queued: every cost final */
    }
    for (b = -2; b <= 2; ++b) {
        for (a = -2; a <= 2; ++a) {
            if (qnav_map_in(m, ri + a, rj + b) && settled(m, qnav_map_at(m, ri + a, rj + b)) &&
                m->cost[qnav_map_at(m, ri + a, rj + b)] < least) {
                least = m->cost[qnav_map_at(m, ri + a, rj + b)];
            }
        }
    }
    while (least == QNAV_MAP_UNREACHED && settle_one(m, UINT32_MAX, &c)) {
        const int32_t di = (int32_t)(c % m->nx) - ri, dj = (int32_t)(c / m->nx) - rj;
        if (di >= -2 && di <= 2 && dj >= -2 && dj <= 2) {
            least = m->cost[c];
        }
    }
    while (least != QNAV_MAP_UNREACHED && settle_one(m, least + 3u * STEP_SIDE, &c)) {
    }
    return 0;
}

void qnav_map_plan(qnav_map_t *m, int32_t goal_x_mm, int32_t goal_y_mm)
{
    if (!ready(m)) {
        return;
    }
    qnav_align_point(m, &goal_x_mm, &goal_y_mm);
    plan_start(m, goal_x_mm, goal_y_mm);
    settle_all(m);
}

/* Cell (i, j) cannot hold the robot's centre. */
static int blocked_at(const qnav_map_t *m, int32_t i, int32_t j)
{
    return m->cfg.compact ? qnav_cmap_blocked(m, i, j) : m->blocked[qnav_map_at(m, i, j)] == BLOCKED;
}

/* The straight line between the centres of cells (i0, j0) and (i1, j1) crosses no blocked
 * cell (sampled every half cell): the robot aiming at the second does not cut a corner. */
static int in_sight(const qnav_map_t *m, int32_t i0, int32_t j0, int32_t i1, int32_t j1)
{
    const int32_t di = i1 - i0, dj = j1 - j0;
    const int32_t n = 2 * ((di < 0 ? -di : di) > (dj < 0 ? -dj : dj) ? (di < 0 ? -di : di)
                                                                      : (dj < 0 ? -dj : dj));
    int32_t t;
    for (t = 1; t < n; ++t) {
        /* cell of the point t / n along, rounded to the nearest */
        const int32_t i = i0 + (2 * di * t + (di >= 0 ? n : -n)) / (2 * n);
        const int32_t j = j0 + (2 * dj * t + (dj >= 0 ? n : -n)) / (2 * n);
        if (blocked_at(m, i, j)) {
            return 0;
        }
    }
    return 1;
}

/* The cost of cell (i, j), or from the nearest reachable cell within two (the robot's
 * own cell may be blocked: it stands near a wall). QNAV_MAP_UNREACHED: none. */
static uint32_t cost_near(qnav_map_t *m, int32_t i, int32_t j, int32_t *bi, int32_t *bj)
{
    uint32_t best = QNAV_MAP_UNREACHED;
    int32_t a, b;
    if (m->cfg.compact) {
        return qnav_cmap_cost_near(m, i, j, bi, bj);
    }
    *bi = i;
    *bj = j;
    if (m->cost[qnav_map_at(m, i, j)] != QNAV_MAP_UNREACHED) {
        return m->cost[qnav_map_at(m, i, j)];
    }
    for (b = -2; b <= 2; ++b) {
        for (a = -2; a <= 2; ++a) {
            const int32_t ii = i + a, jj = j + b;
            uint32_t c;
            if (!qnav_map_in(m, ii, jj)) {
                continue;
            }
            c = m->cost[qnav_map_at(m, ii, jj)];
            if (c == QNAV_MAP_UNREACHED) {
                continue;
            }
            /* to that cell: 10 a side, 14 a diagonal */
            c += (uint32_t)((a < 0 ? -a : a) + (b < 0 ? -b : b)) * STEP_SIDE;
            if (c < best) {
                best = c;
                *bi = ii;
                *bj = jj;
            }
        }
    }
    return best;
}

/* A plan for a new destination; again on the plan's turn when a cell became or stopped
 * being occupied since the last (the same plan otherwise). 1 when a plan for the same
 * destination was made again. */
static int plan_when_due(qnav_map_t *m, int32_t goal_x_mm, int32_t goal_y_mm)
{
    int again = 0;
    const int new_goal = m->goal_x_mm != goal_x_mm || m->goal_y_mm != goal_y_mm;
    if (new_goal) {
        m->forgot = 0u; /* marked from afar again until the next forget */
        m->turn_back = 0u;
        m->replan_owed = 0u; /* the last goal's plan owes a new goal's escape nothing */
    }
    if (!m->planned || new_goal) {
        plan_start(m, goal_x_mm, goal_y_mm);
    } else if (++m->ticks >= m->cfg.plan_ticks) {
        if (m->dirty) {
            plan_start(m, goal_x_mm, goal_y_mm);
            again = 1;
        }
        m->ticks = 0u;
    }
    return again;
}

/* One step of steepest descent on the plan's costs from cell (*i, *j): to its cheapest
 * neighbour (8), when cheaper; 0 when none is. */
static int descend(const qnav_map_t *m, int32_t *i, int32_t *j)
{
    uint16_t here;
    int32_t a, b, ni = *i, nj = *j;
    if (m->cfg.compact) {
        return qnav_cmap_descend(m, i, j);
    }
    here = m->cost[qnav_map_at(m, *i, *j)];
    for (b = -1; b <= 1; ++b) {
        for (a = -1; a <= 1; ++a) {
            if (qnav_map_in(m, *i + a, *j + b) && m->cost[qnav_map_at(m, *i + a, *j + b)] < here) {
                here = m->cost[qnav_map_at(m, *i + a, *j + b)];
                ni = *i + a;
                nj = *j + b;
            }
        }
    }
    if (ni == *i && nj == *j) {
        return 0;
    }
    *i = ni;
    *j = nj;
    return 1;
}

/* Lapse the refusal: every refused cell back to unknown. */
static void refusal_lapses(qnav_map_t *m)
{
    uint32_t c, n = cell_count(m);
    for (c = 0; c < n; ++c) {
        if (m->evidence[c] == EVIDENCE_REFUSED) {
            m->evidence[c] = 0;
        }
    }
    m->dirty = 1u;
}

/* Cell (i, j)'s plan cost (0: the destination's cell). */
static uint32_t plan_cost(const qnav_map_t *m, int32_t i, int32_t j)
{
    return m->cfg.compact ? qnav_cmap_cost(m, i, j) : m->cost[qnav_map_at(m, i, j)];
}

/* Refuse cell (i, j). The full layout marks it refused until the refusal lapses. The
 * compact layout has no bits for a refusal and marks it occupied, until a forget
 * (qnav_map_guide) clears it with every other occupied cell: where the plan leads through a
 * stretch of wall in a cell once seen clear (a cell seen clear takes no arc, which keeps the
 * coarse cells' passages open) the robot stalled against the wall for good without it
 * (docs/architecture.md, "A compact map's refusal"). */
static void refuse_cell(qnav_map_t *m, int32_t i, int32_t j)
{
    if (m->cfg.compact) {
        qnav_cmap_occupy(m, i, j);
    } else {
        m->evidence[qnav_map_at(m, i, j)] = EVIDENCE_REFUSED;
    }
}

/* The robot made no progress along the plan for a long time though the plan kept its way:
 * the way is one the robot cannot take (a gap the controller will not pass). Refuse the
 * plan's cells from 'from' to look_mm ahead of the robot's cell, so the plan seeks another
 * way; the refusal lapses after a while (the compact layout's when the map forgets). */
static void refuse_when_stalled(qnav_map_t *m, int32_t ri, int32_t rj, uint16_t mm, int jumped)
{
    int32_t i, j, steps, k, from;
    if (m->cfg.refuse_ticks == 0u) {
        return;
    }
    if (jumped || m->stall_best_mm == 0u || (uint32_t)mm + m->cfg.cell_mm < m->stall_best_mm) {
        m->stall_best_mm = mm;
        m->stall_ticks = 0u;
        return;
    }
    if (m->grown_mm > 0u) { /* a new plan, longer: progress is measured along it */
        const uint32_t best = (uint32_t)m->stall_best_mm + m->grown_mm;
        m->stall_best_mm = (uint16_t)(best > 65535u ? 65535u : best);
    }
    if (++m->stall_ticks < m->cfg.refuse_ticks) {
        return;
    }
    (void)cost_near(m, ri, rj, &i, &j);
    steps = (int32_t)(m->cfg.look_mm / m->cfg.cell_mm);
    /* refused cells lie beyond the body's reach along the plan, so that the robot's own cell
     * stays unblocked and the plan starts where the robot stands; the full layout blocks
     * cells within the body's reach of a refused one, so its refusal starts a cell further
     * (the compact one blocks the occupied cell only: its 1 m look-ahead holds two 0.35 m
     * cells, and the second is refused) */
    from = ((int32_t)m->inflate_mm + (int32_t)m->cfg.cell_mm - 1) / (int32_t)m->cfg.cell_mm +
           (m->cfg.compact ? 0 : 1);
    for (k = 0; k < steps && descend(m, &i, &j) && plan_cost(m, i, j) != 0u; ++k) {
        if (k >= from) {
            refuse_cell(m, i, j);
        }
    }
    if (!m->cfg.compact) { /* (a compact cell marked occupied makes the map dirty itself) */
        m->dirty = 1u;
        m->refused_ticks = m->cfg.refuse_life_ticks;
    }
    m->ticks = m->cfg.plan_ticks; /* plan again at once */
    m->stall_best_mm = 0u;
    m->stall_ticks = 0u;
}

/* The signed bearing of (x, y) from the pose, robot frame, 0.01 deg; *d its distance, mm. */
static int32_t bearing_to(const qnav_map_pose_t *pose, int32_t x_mm, int32_t y_mm, uint32_t *d)
{
    return qnav_wrap_cdeg((int32_t)qnav_atan2_cdeg(y_mm - pose->y_mm, x_mm - pose->x_mm, d) -
                          qnav_wrap_cdeg(pose->heading_cdeg));
}

/* The input's goal bearing and planned distance: toward (x, y), a sub-goal whose own way
 * to the destination is via_mm, seen from pose (the bearing unchanged when there). The
 * straight part makes the distance shrink as the robot drives within a cell: a cell's own
 * cost stands still across it (a 0.4 m cell is a second of driving), and the escape took
 * that for a stall (docs/architecture.md, "The planned distance"). */
static void aim(qnav_ctrl_input_t *in, const qnav_map_pose_t *pose, int32_t x_mm, int32_t y_mm,
                uint32_t via_mm)
{
    uint32_t d = 0u;
    if (x_mm != pose->x_mm || y_mm != pose->y_mm) {
        in->goal_bearing_cdeg = (qnav_cdeg_t)bearing_to(pose, x_mm, y_mm, &d);
    }
    d += via_mm;
    in->goal_range_mm = (qnav_mm_t)(d == 0u ? 1u : (d > 65535u ? 65535u : d));
}

/* The cost of the cell a plan step from (i, j) to (ni, nj) reaches, from cost, the way's
 * from (i, j): the full layout keeps it; the compact one's way from (i, j) is its steps
 * (qnav_cmap_descend), 10 a side and 14 a diagonal. */
static uint32_t step_cost(const qnav_map_t *m, uint32_t cost, int32_t i, int32_t j, int32_t ni,
                          int32_t nj)
{
    uint32_t step;
    if (!m->cfg.compact) {
        return m->cost[qnav_map_at(m, ni, nj)];
    }
    step = (ni != i && nj != j) ? STEP_DIAG : STEP_SIDE;
    return cost > step ? cost - step : 0u;
}

/* What the escape memory grows by on this guided tick, mm (0: nothing), the planned
 * distance being mm and the straight one straight_mm:
 * - a new plan, longer where the robot is (by less than a jump: the caller drops a jump).
 *   A plan begun on an earlier tick is new on the first tick it guides from: a compact
 *   plan grows grow_steps a tick and may reach the robot ticks after it began
 *   (docs/architecture.md, "A plan that reaches the robot late");
 * - the first guided tick: the escape has measured the straight distance until now, and
 *   the plan's longer way is no step back (in an empty arena the escape took it for a stall
 *   and followed the walls). */
static uint16_t plan_growth(qnav_map_t *m, uint32_t mm, uint32_t straight_mm)
{
    const uint8_t replanned = m->replan_owed;
    m->replan_owed = 0u;
    if (!m->cfg.escape_grow) {
        return 0u;
    }
    if (replanned && m->last_mm != 0u && mm > m->last_mm) {
        return (uint16_t)(mm - m->last_mm);
    }
    if (m->last_mm == 0u && straight_mm != 0u && mm > straight_mm) {
        return (uint16_t)(mm - straight_mm);
    }
    return 0u;
}

/* A sub-goal lies behind the robot beyond this, ahead within AHEAD_CDEG (0.01 deg). */
#define BEHIND_CDEG 9000
#define AHEAD_CDEG 6000

static int32_t bearing_off(const qnav_ctrl_input_t *in)
{
    return in->goal_bearing_cdeg < 0 ? -(int32_t)in->goal_bearing_cdeg : in->goal_bearing_cdeg;
}

/* How far (x, y) lies off the pose's heading, 0.01 deg, 0..18000. */
static int32_t off_heading(const qnav_map_pose_t *pose, int32_t x_mm, int32_t y_mm)
{
    uint32_t d;
    const int32_t b = bearing_to(pose, x_mm, y_mm, &d);
    return b < 0 ? -b : b;
}

/* 1 while the last sub-goal stands against this tick's plan, in: a plan longer by more than
 * jump_mm whose sub-goal lies behind the robot while the last lay ahead waits
 * cfg.turn_back_ticks guided ticks (this one the first), once until a sub-goal lies ahead
 * again (docs/architecture.md, "A turn back waits a second"). */
static int turn_back_waits(qnav_map_t *m, const qnav_map_pose_t *pose, const qnav_ctrl_input_t *in)
{
    if (m->cfg.turn_back_ticks == 0u) {
        return 0;
    }
    if (m->turn_back == QNAV_MAP_TURNED_BACK) {
        if (bearing_off(in) < AHEAD_CDEG) {
            m->turn_back = 0u;
        }
        return 0;
    }
    if (m->turn_back == 0u) {
        if (m->last_mm == 0u || bearing_off(in) <= BEHIND_CDEG ||
            in->goal_range_mm <= (uint32_t)m->last_mm + m->cfg.jump_mm ||
            off_heading(pose, m->sub_x_mm, m->sub_y_mm) >= AHEAD_CDEG) {
            return 0;
        }
        m->turn_back = m->cfg.turn_back_ticks;
    }
    if (--m->turn_back == 0u) {
        m->turn_back = QNAV_MAP_TURNED_BACK;
    }
    return 1;
}

/* The input aimed at this tick's sub-goal (x, y), via_mm from the destination, direct its
 * QNAV_MAP_DIRECT or 0, which becomes the map's last sub-goal; or at the last, which stands
 * while a turn back waits. The aimed sub-goal's direct flag. */
static int aim_sub_goal(qnav_map_t *m, const qnav_map_pose_t *pose, qnav_ctrl_input_t *in,
                        int32_t x_mm, int32_t y_mm, uint16_t via_mm, int direct)
{
    aim(in, pose, x_mm, y_mm, via_mm);
    if (turn_back_waits(m, pose, in)) {
        aim(in, pose, m->sub_x_mm, m->sub_y_mm, m->sub_mm);
        return m->sub_direct;
    }
    m->sub_x_mm = x_mm;
    m->sub_y_mm = y_mm;
    m->sub_mm = via_mm;
    m->sub_direct = (uint8_t)direct;
    return direct;
}

int qnav_map_guide(qnav_map_t *m, const qnav_map_pose_t *at, int32_t goal_x_mm,
                   int32_t goal_y_mm, qnav_ctrl_input_t *in)
{
    int32_t i, j, ri, rj, steps, sx, sy;
    uint32_t cost, mm, sub, straight_mm;
    int jumped, direct = 0;
    qnav_map_pose_t in_grid;
    const qnav_map_pose_t *pose = &in_grid;
    if (!ready(m) || at == NULL || in == NULL) {
        return 0;
    }
    in_grid = qnav_align_pose(m, at);
    qnav_align_point(m, &goal_x_mm, &goal_y_mm);
    if (m->refused_ticks > 0u && --m->refused_ticks == 0u) {
        refusal_lapses(m);
    }
    straight_mm = in->goal_range_mm;
    m->replan_owed = (uint8_t)(m->replan_owed | plan_when_due(m, goal_x_mm, goal_y_mm));
    cell_of(m, pose->x_mm, pose->y_mm, &ri, &rj);
    m->replan_owed = (uint8_t)(m->replan_owed | settle_for(m, ri, rj));
    cost = cost_near(m, ri, rj, &i, &j);
    if (cost == QNAV_MAP_UNREACHED && m->cfg.compact && m->q_queued && m->last_mm != 0u) {
        /* a compact plan still growing toward the robot (grow_steps a tick): the last
         * sub-goal stands */
        aim(in, pose, m->sub_x_mm, m->sub_y_mm, m->sub_mm);
        m->grown_mm = 0u;
        return QNAV_MAP_GUIDED | m->sub_direct;
    }
    if (cost == QNAV_MAP_UNREACHED) {
        if (m->q_queued == 0u) {
            forget_occupied(m);
            plan_start(m, goal_x_mm, goal_y_mm);
        }
        m->last_mm = 0u;
        m->grown_mm = 0u;
        return 0;
    }
    /* steepest descent for look_mm */
    sub = cost;
    for (steps = (int32_t)(m->cfg.look_mm / m->cfg.cell_mm); steps > 0; --steps) {
        int32_t ni = i, nj = j;
        if (!descend(m, &ni, &nj) || (m->cfg.sight && !in_sight(m, ri, rj, ni, nj))) {
            break;
        }
        sub = step_cost(m, sub, i, j, ni, nj);
        i = ni;
        j = nj;
    }
    if (m->cfg.compact ? qnav_map_at(m, i, j) == m->goal_cell : m->cost[qnav_map_at(m, i, j)] == 0u) {
        sx = goal_x_mm; /* the plan ends in the destination's cell: aim at the destination */
        sy = goal_y_mm;
        direct = QNAV_MAP_DIRECT;
        sub = 0u;
    } else {
        sx = centre_x(m, i);
        sy = centre_y(m, j);
    }
    sub = sub * m->cfg.cell_mm / STEP_SIDE;
    sub = sub > 65535u ? 65535u : sub;
    direct = aim_sub_goal(m, pose, in, sx, sy, (uint16_t)sub, direct);
    mm = in->goal_range_mm;
    jumped = m->last_mm != 0u && mm > (uint32_t)m->last_mm + m->cfg.jump_mm;
    m->grown_mm = plan_growth(m, mm, straight_mm);
    if (jumped) {
        m->grown_mm = 0u;
    }
    qnav_escape_follow_plan(&in->escape, jumped, m->grown_mm);
    m->last_mm = (uint16_t)mm;
    refuse_when_stalled(m, ri, rj, (uint16_t)mm, jumped);
    return QNAV_MAP_GUIDED | direct |
           (jumped ? QNAV_MAP_ESCAPE_CLEARED : (m->grown_mm != 0u ? QNAV_MAP_ESCAPE_GROWN : 0));
}

/* The index of the cell holding pose-frame point (x, y); -1 outside the map. */
static int32_t index_of(const qnav_map_t *m, int32_t x_mm, int32_t y_mm)
{
    int32_t i, j;
    if (!ready(m)) {
        return -1;
    }
    qnav_align_point(m, &x_mm, &y_mm);
    if (x_mm < m->x0_mm || y_mm < m->y0_mm) {
        return -1;
    }
    i = (x_mm - m->x0_mm) / (int32_t)m->cfg.cell_mm;
    j = (y_mm - m->y0_mm) / (int32_t)m->cfg.cell_mm;
    return i < (int32_t)m->nx && j < (int32_t)m->ny ? j * (int32_t)m->nx + i : -1;
}

uint16_t qnav_map_grown_mm(const qnav_map_t *m)
{
    return m == NULL ? 0u : m->grown_mm;
}

int8_t qnav_map_evidence(const qnav_map_t *m, int32_t x_mm, int32_t y_mm)
{
    const int32_t k = index_of(m, x_mm, y_mm);
    if (k < 0) {
        return 0;
    }
    return evidence_at(m, k % (int32_t)m->nx, k / (int32_t)m->nx);
}

uint16_t qnav_map_cost(qnav_map_t *m, int32_t x_mm, int32_t y_mm)
{
    const int32_t k = index_of(m, x_mm, y_mm);
    if (k < 0) {
        return QNAV_MAP_UNREACHED;
    }
    settle_all(m);
    if (m->cfg.compact) {
        return (uint16_t)qnav_cmap_cost(m, k % (int32_t)m->nx, k / (int32_t)m->nx);
    }
    return m->cost[k];
}
