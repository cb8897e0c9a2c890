/*
 * A map of what the sonar has seen, and a plan over it (docs/architecture.md, "A map and
 * a plan"). The path-quality step has no memory of place: in a world of dead ends, doors
 * and gaps it searches by following walls, and a wrong first side costs more than a world's
 * time limit. The map remembers which cells the sonar has seen free and which it has seen
 * a reading end in; a plan over it (unknown cells taken as free) gives the controller a
 * sub-goal a little way along the shortest known-passable way to the destination instead
 * of the destination itself. The controller, its policy and its escape memory are
 * unchanged: the map only rewrites the input's goal bearing and range.
 *
 * Fixed point, no heap: the caller gives the memory (qnav_map_size()) and keeps it; the
 * robot's pose (millimetres, 0.01 deg, in the frame the destination is given in) comes from
 * the caller's odometry or the simulator. One map per destination and world: reset it
 * when either changes.
 *
 * Use: qnav_map_init() once -> every tick qnav_map_observe() with the scan and the pose,
 * then qnav_map_guide() on the controller's input before qnav_ctrl_step() (or any
 * qnav_nav_t step).
 */
#ifndef QNAV_MAP_H
#define QNAV_MAP_H

#include <stddef.h>
#include <stdint.h>

#include "qnav/check.h"
#include "qnav/ctrl.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What the map is made of (docs/architecture.md, "A map and a plan"). */
typedef struct {
    uint16_t cell_mm;      /* a cell's side, mm, 20..1000; default 100 */
    uint16_t reach_mm;     /* readings mark cells out to this distance from the robot's
                              centre, mm, at most 40 000; no farther than a reading at the
                              sonar's range clears (its range and offset less 3/4 cell and
                              noise_pct): a larger value marks as that; default 2000 */
    uint16_t look_mm;      /* the sub-goal lies this far along the plan, mm; default 1000 */
    uint16_t jump_mm;      /* a plan longer by this than the last tick's clears the escape
                              memory (the way it was following is closed), mm; default 1000 */
    uint8_t plan_ticks;    /* ticks between plans, 1..255; default 10 */
    uint8_t noise_pct;     /* the sonar's range noise, its standard deviation in % of the
                              reading: a cell nearer than the reading by less than this many %
                              of it (plus 3/4 of a cell) is not marked clear; default 5; set
                              the sonar's own (docs/architecture.md, "The map's range noise") */
    uint8_t near_cost;     /* extra plan cost of a cell within near_mm beyond the body's
                              reach of an occupied cell (10: one more cell side); default 10 */
    uint16_t near_mm;      /* mm; default 200 (measured: docs/architecture.md) */
    uint16_t arc_cdeg;     /* a reading marks occupied only the arc cells within arc_cdeg / 2
                              of its wedge's centre line (the whole wedge when that is
                              narrower), 0.01 deg, 0..36000; default 2250: a wider wedge's
                              reading says little about where across it the obstacle is
                              (measured: docs/architecture.md, "The arc a reading marks") */
    uint16_t arc_width_mm; /* ...and at most the arc cells within arc_width_mm / 2 across the
                              wedge at the reading's range, mm; 0: no limit (default). A far
                              reading says least about where across its wedge the obstacle
                              is: one that marks only its central cells leaves a gap seen
                              from afar open until nearer readings close it (measured:
                              docs/architecture.md, "An arc no wider than a cell") */
    uint8_t sight;         /* 1: the sub-goal stops where the straight line to it from the
                              robot's cell would cross a blocked cell; default 1 */
    uint8_t escape_grow;   /* 1: when a new plan is longer where the robot is (by less than
                              jump_mm), every distance the escape memory holds grows as
                              much (qnav_escape_grow); default 1 */
    uint8_t refuse_ticks;  /* guided ticks without a cell's progress along the plan after
                              which the plan's next cells (beyond the body's reach, up to
                              look_mm) are refused: marked occupied until the refusal
                              lapses, so the plan seeks another way than one the robot
                              cannot take (compact: marked occupied until a forget, as it
                              has no bits for a refusal); 0: never; default 30 */
    uint16_t refuse_life_ticks; /* ticks a refusal lasts (every refused cell then unknown
                              again), 1..65535; default 200 */
    uint8_t compact;       /* 1: 4 bits a cell instead of 8 bytes, for a board of a few KB
                              (docs/architecture.md, "A map in 4 bits a cell"): what a cell
                              was seen as in 2 bits, a breadth-first plan in 2 (each cell's
                              step count from the destination modulo 3). Needs cells wider
                              than the body's radius and safety distance (a cell is blocked
                              when it is occupied), at most 192 cells across and near_cost
                              0; the plan counts a diagonal step as one.
                              Default 0 */
    uint8_t grow_steps;    /* compact: a tick grows the plan by at most this many steps
                              (its cost is bounded: docs/performance.md); while it has not
                              reached the robot, the last sub-goal stands. 0: no bound.
                              Default 16 */
    uint16_t forget_reach_mm; /* once the map has forgotten what closed every way (until the
                              destination changes), only readings within this distance of
                              the robot's centre mark cells occupied, mm; farther ones still
                              clear cells. A near arc is narrower than a cell, so a gap the
                              far arcs closed is seen as it is before it is marked again
                              (docs/architecture.md, "Marking near after a forget"). 0: no
                              limit; default 0 */
    uint16_t opening_mm;   /* a reading farther than both its neighbouring sectors' (a range
                              peak) marks no arc where its wedge spans more than twice this
                              across: it may be an opening whose two sides the wedge's edges
                              read, and an arc at its centre line would shut a passage the
                              robot fits through (a wide wedge in an aisle reads the side
                              walls ahead); it still clears the cells short of it, mm. 0:
                              every reading marks; default 0 (docs/architecture.md, "A
                              reading that may be an opening") */
    uint8_t unknown_cost;  /* extra plan cost of a cell no reading has marked yet (10: one
                              more cell side): the plan prefers a way seen open to one merely
                              not seen shut (docs/architecture.md, "Unknown cells cost more").
                              Full layout only (compact: 0); near_cost + unknown_cost at most
                              255; default 0 */
    uint8_t align_samples; /* the grid turns to the walls it sees: once this many readings
                              nearer than 2 m and nearer than both neighbouring sectors' (a
                              wall's nearest point, its normal along the sector) agree on
                              walls at right angles (their directions modulo 90 deg), the map
                              turns its grid to them, as far as 5 deg or more, and begins
                              again; a pose's frame (a heading sensor's) lies at no particular
                              angle to a room's walls, and a passage along a grid's diagonal
                              closes sooner (docs/architecture.md, "A grid turned to the
                              walls"). 0: the grid stays in the pose's frame; default 0 */
    uint8_t turn_back_ticks; /* a new plan longer by more than jump_mm (the way followed shut
                              in the map) whose sub-goal lies behind the robot (more than 90
                              deg off its heading) while the last one lies ahead (within 60
                              deg) is followed only after this many guided ticks: until then
                              the last sub-goal stands. What shut the way is often the
                              robot's own arcs over a lane narrower than two cells, which its
                              sonar shows open ahead; a way really shut the controller does
                              not take whatever the sub-goal (docs/architecture.md, "A turn
                              back waits a second"). 0: at once; default 0 */
} qnav_map_config_t;

/* Every field of qnav_map_config_t in its order, with its width in bits: the one list that
 * whatever copies a configuration field by field walks (the board's CRC of it, and the
 * robot headers and map bench trace the tools write). map.c checks at build time that the
 * list lays out as the struct does (on the ATmega128, with no padding, byte for byte): a
 * field added to the struct is added here, or the build fails. */
#define QNAV_MAP_CONFIG_FIELDS(X)                                                            \
    X(cell_mm, 16) X(reach_mm, 16) X(look_mm, 16) X(jump_mm, 16) X(plan_ticks, 8)            \
    X(noise_pct, 8) X(near_cost, 8) X(near_mm, 16) X(arc_cdeg, 16) X(arc_width_mm, 16)       \
    X(sight, 8) X(escape_grow, 8) X(refuse_ticks, 8) X(refuse_life_ticks, 16) X(compact, 8)  \
    X(grow_steps, 8) X(forget_reach_mm, 16) X(opening_mm, 16) X(unknown_cost, 8)             \
    X(align_samples, 8) X(turn_back_ticks, 8)

/* A compact map reads a scan of twice this many sectors or more as this many wedges, each
 * the least reading of the sectors whose centres lie within it (docs/architecture.md, "A
 * compact map's wedges"). */
#define QNAV_MAP_WEDGES_MAX 32u

/* The robot's pose in the destination's frame. */
typedef struct {
    int32_t x_mm;
    int32_t y_mm;
    int32_t heading_cdeg;  /* direction of the robot's straight ahead (sector 0), any value */
} qnav_map_pose_t;

/* One map. Private fields: read them through the functions below. */
typedef struct {
    qnav_map_config_t cfg;
    uint16_t n_sectors;       /* the wedges the map reads the scan as: the sonar's sectors, at
                                 most QNAV_MAP_WEDGES_MAX in a compact map */
    uint16_t scan_sectors;    /* the sonar's sectors (the scan's length) */
    qnav_mm_t max_range_mm;
    qnav_mm_t offset_mm;      /* sensor offset: a reading r lies r + offset from the centre */
    uint16_t inflate_mm;      /* body radius + safety distance */
    uint16_t seen_mm;         /* readings clear and mark cells this far from the centre:
                                 cfg.reach_mm, or nearer where a reading at the sonar's
                                 range stops clearing (its range and offset less 3/4 cell
                                 and noise_pct) */
    uint16_t peak_mm;         /* a range peak this far or farther marks no arc (cfg.opening_mm
                                 over the half-wedge's sine); 0: none is left out */
    int32_t x0_mm, y0_mm;     /* the corner of cell (0, 0) in the grid's frame: the pose's
                                 turned by grid_cdeg about (pivot_x_mm, pivot_y_mm) */
    int32_t pivot_x_mm, pivot_y_mm; /* the map's centre when it was made, pose frame */
    int16_t grid_cdeg;        /* the grid's turn against the pose's frame, 0.01 deg */
    int16_t grid_cos, grid_sin; /* its cosine and sine, Q2.14 */
    uint16_t align_n;         /* readings of walls' nearest points counted ... */
    int32_t align_c, align_s; /* ... and the sums of the cosine and sine (Q2.14) of four
                                 times their directions (walls at right angles agree) */
    uint16_t nx, ny;
    /* the full layout (cfg.compact 0), in the caller's memory; NULL in the compact one */
    int8_t *evidence;         /* per cell: < 0 seen free, >= QNAV_MAP_OCCUPIED occupied */
    uint16_t *cost;           /* per cell: plan cost to the destination, 10 per cell side */
    uint16_t *next;           /* per cell: the next cell in its plan queue bucket */
    uint16_t *prev;           /* per cell: the previous one, or not queued */
    uint8_t *blocked;         /* per cell: too near an occupied cell for the body */
    uint16_t *q_head;         /* the plan queue's buckets */
    /* the compact layout: 4 bit planes of ny rows of row_bytes bytes, cell i of a row in
     * bit i % 8 of byte i / 8: what the cell was seen as (2), its plan step count modulo 3
     * plus 1, 0 unreached (2); NULL in the full layout */
    uint8_t *planes;
    uint16_t row_bytes;
    uint16_t layer;           /* the plan's last settled step count (compact) */
    uint16_t goal_cell;       /* the destination's cell (compact) */
    uint16_t rows_from, rows_to; /* the rows holding the last step count's cells (compact) */
    uint16_t way_from;        /* the cell the last cost near it was found for, while no label,
                                 no cell's occupancy and no growth changed since (compact);
                                 UINT16_MAX: none */
    uint16_t way_cost;        /* ... that cost */
    uint8_t way_i, way_j;     /* ... and the cell its way starts from */
    int32_t sub_x_mm, sub_y_mm; /* the last guided tick's sub-goal */
    uint16_t sub_mm;          /* ... its own way to the destination, mm */
    uint8_t sub_direct;       /* ... was the destination (QNAV_MAP_DIRECT) */
    int32_t goal_x_mm, goal_y_mm;
    uint16_t ticks;           /* observations since the last plan */
    uint16_t last_mm;         /* the last guided tick's planned distance; 0: none */
    uint8_t planned;          /* a plan toward goal_* exists */
    uint8_t dirty;            /* a cell became or stopped being occupied since the plan */
    uint16_t grown_mm;        /* what this tick's guide grew the escape memory by, mm */
    uint16_t stall_best_mm;   /* the least planned distance since the last refusal */
    uint16_t stall_ticks;     /* guided ticks since it last shrank by a cell */
    uint16_t refused_ticks;   /* ticks the refused cells have left; 0: none */
    uint8_t forgot;           /* forgot what closed every way since the destination was set */
    uint8_t turn_back;        /* guided ticks the last sub-goal still stands against a plan that
                                 turned back (cfg.turn_back_ticks); QNAV_MAP_TURNED_BACK once the
                                 robot follows it, until a plan's sub-goal lies ahead again */
    uint8_t replan_owed;      /* a plan began since the last guided tick: a compact plan may reach
                                 the robot ticks after it begins, and is new on the tick it does */
    /* The plan's queue, kept between ticks: a plan settles cells only until the robot's
     * is settled, and goes on from here when the robot stands on a cell not yet settled */
    uint16_t q_count;         /* buckets in use */
    uint16_t q_slot;          /* q_cost's bucket */
    uint32_t q_cost;          /* the least cost still queued may be this */
    uint32_t q_queued;        /* cells queued */
} qnav_map_t;

/* qnav_map_t.turn_back after a wait: no other until a sub-goal lies ahead again. */
#define QNAV_MAP_TURNED_BACK 0xFFu

/* Evidence at or above this marks a cell occupied. */
#define QNAV_MAP_OCCUPIED 2
/* Plan cost of an unreachable cell. */
#define QNAV_MAP_UNREACHED UINT16_C(0xFFFF)

void qnav_map_config_default(qnav_map_config_t *cfg);

/* Cells of a width_mm x height_mm world at cell_mm; 0 when too many (> 65 000) or cell_mm 0. */
uint32_t qnav_map_cells(uint32_t width_mm, uint32_t height_mm, uint16_t cell_mm);
/* Bytes of memory a map of that world with configuration cfg needs: 8 a cell and 540 for
 * the plan's queue, or with cfg->compact half a byte a cell (each row of cells a whole
 * number of bytes); 0 when it has too many cells. */
size_t qnav_map_size(const qnav_map_config_t *cfg, uint32_t width_mm, uint32_t height_mm);

/*
 * Where a robot at (rx, ry) going to (gx, gy), mm, places a map of cfg in len bytes when it
 * knows neither its room nor its goals beforehand (a board: qnav_board_place_maps; the
 * simulator with a profile's [map] bytes): the largest square of cfg's cells that len bytes
 * hold, *side_mm across, its corner at (*x0_mm, *y0_mm), centred midway between the robot
 * and the goal. Along an axis where the two do not both lie a cell inside it (a goal too
 * far), the robot lies the readings' reach and a cell inside the square and the rest of it
 * toward the goal: the plan leads to the edge cell nearest the goal, and qnav_map_follow()
 * moves the map on as the robot gets there. Returns 1, or 0 (nothing written) when no
 * square fits in len or it is too small to keep the robot that far inside.
 */
int qnav_map_place(const qnav_map_config_t *cfg, size_t len, int32_t rx_mm, int32_t ry_mm,
                   int32_t gx_mm, int32_t gy_mm, int32_t *x0_mm, int32_t *y0_mm,
                   uint32_t *side_mm);

/*
 * A map of the world [x0, x0 + width) x [y0, y0 + height) mm for a robot whose controller
 * is configured by ctrl (sectors, sonar range and offset, body): buf holds len bytes,
 * at least qnav_map_size(), aligned for uint16_t (the compact layout: any address).
 * Starts empty (every cell unknown).
 */
QNAV_CHECK_RESULT qnav_status_t qnav_map_init(qnav_map_t *m, const qnav_map_config_t *cfg,
                                              const qnav_ctrl_config_t *ctrl, int32_t x0_mm,
                                              int32_t y0_mm, uint32_t width_mm,
                                              uint32_t height_mm, void *buf, size_t len);

/*
 * A placed map (qnav_map_place) that follows the robot: once the cells its readings mark
 * (reach_mm) would reach past the map's edge, the map moves, by whole cells, to where qnav_map_place would put
 * it now (midway between the robot at pose and the goal), keeping what it saw where the old
 * and the new square overlap, and plans again. Nothing when the goal would not fit the new
 * square, or the move is less than a cell. Call before qnav_map_observe(). Returns 1 when
 * the map moved. At most one pass over the cells.
 */
int qnav_map_follow(qnav_map_t *m, const qnav_map_pose_t *pose, int32_t goal_x_mm,
                    int32_t goal_y_mm);

/* Forget everything seen (a new world or start). */
void qnav_map_reset(qnav_map_t *m);

/* Mark what this scan (n_sectors ranges, mm, from the sensor) says about the cells. */
void qnav_map_observe(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *pose);

/* Plan every cell's cost to the destination over what the map has seen (unknown cells
 * passable). At most 8 queue operations per cell. (qnav_map_guide plans only as far as it
 * needs: the same costs where it looks.) */
void qnav_map_plan(qnav_map_t *m, int32_t goal_x_mm, int32_t goal_y_mm);

/* What qnav_map_guide() did. */
#define QNAV_MAP_GUIDED 1         /* the input's goal bearing and range are the plan's */
#define QNAV_MAP_ESCAPE_CLEARED 2 /* the plan grew by jump_mm: in->escape was cleared */
#define QNAV_MAP_DIRECT 4         /* the sub-goal is the destination itself: a caller that
                                     senses the destination's bearing (a beacon) better than
                                     its pose gives it may keep its own */
#define QNAV_MAP_ESCAPE_GROWN 8   /* a new plan is longer by less than jump_mm where the
                                     robot is: in->escape's distances grew by
                                     qnav_map_grown_mm() (a stall is no progress along this
                                     plan, not along the last one's) */

/*
 * One tick, after qnav_map_observe(): plan again when plan_ticks have passed or the
 * destination moved, and when the robot's cell has a way to the destination, replace
 * in->goal_bearing_cdeg with the bearing of the point look_mm along it (seen from pose)
 * and in->goal_range_mm with the planned distance (straight to that point, then its way
 * along the plan), clearing in->escape when that grew by
 * jump_mm since the last guided tick (the way the escape was following has closed), and
 * growing in->escape's distances by what a new plan added when it grew by less.
 * Returns QNAV_MAP_* flags; 0 when the map knows no way (the input stays as it was). A
 * whole plan with no way from the robot means the arcs closed every door (the robot was
 * placed where the destination can be reached): the map forgets every cell not seen free,
 * refusals too, and plans again (docs/architecture.md, "A map that closed every way").
 */
int qnav_map_guide(qnav_map_t *m, const qnav_map_pose_t *pose, int32_t goal_x_mm,
                   int32_t goal_y_mm, qnav_ctrl_input_t *in);

/* What the last qnav_map_guide() grew the escape memory by (QNAV_MAP_ESCAPE_GROWN), mm;
 * for a caller that keeps the memory elsewhere than the input it gave (qnav_escape_grow). */
uint16_t qnav_map_grown_mm(const qnav_map_t *m);

/* The evidence (< 0 seen open, >= QNAV_MAP_OCCUPIED occupied) and plan cost of the cell holding
 * pose-frame point (x, y); for tests and pictures. Out of the map: 0 and
 * QNAV_MAP_UNREACHED. qnav_map_cost first finishes the plan qnav_map_guide() settled only
 * as far as it needed. */
int8_t qnav_map_evidence(const qnav_map_t *m, int32_t x_mm, int32_t y_mm);
uint16_t qnav_map_cost(qnav_map_t *m, int32_t x_mm, int32_t y_mm);

/* The pose-frame point of grid-frame point (*x, *y) (cell (i, j)'s corner is x0_mm + i
 * cell_mm, y0_mm + j cell_mm in the grid's frame), in place; for pictures of a turned grid
 * (qnav_map_config_t.align_samples). */
void qnav_map_grid_to_pose(const qnav_map_t *m, int32_t *x_mm, int32_t *y_mm);

#ifdef __cplusplus
}
#endif

#endif
