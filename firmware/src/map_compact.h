/*
 * The map's compact layout (qnav/map.h, qnav_map_config_t.compact; docs/architecture.md,
 * "A map in 4 bits a cell"): what map.c asks of a cell and of the plan, kept in four bit
 * planes. map.c owns the sonar's geometry and the guide; this file owns the bits.
 */
#ifndef QNAV_MAP_COMPACT_H
#define QNAV_MAP_COMPACT_H

#include <stddef.h>
#include <stdint.h>

#include "qnav/map.h"

/* A compact map's rows are at most this many bytes (8 cells each): the plan's growth keeps
 * three rows on the stack. */
#define QNAV_CMAP_ROW_BYTES_MAX 24u

/* The evidence value map.c's marking sees for a cell that was seen free: free at its floor,
 * so no reading changes it (as in the full layout). */
#define QNAV_MAP_FREE_FLOOR (-4)

/* (i, j) is a cell of the map. */
static inline int qnav_map_in(const qnav_map_t *m, int32_t i, int32_t j)
{
    return i >= 0 && j >= 0 && i < (int32_t)m->nx && j < (int32_t)m->ny;
}

/* The index of cell (i, j) of the map. */
static inline uint32_t qnav_map_at(const qnav_map_t *m, int32_t i, int32_t j)
{
    return (uint32_t)j * m->nx + (uint32_t)i;
}

/* Bytes of the four planes of an nx x ny map. */
size_t qnav_cmap_bytes(uint32_t nx, uint32_t ny);
/* Point the planes at buf (qnav_cmap_bytes() of it) and forget everything. */
void qnav_cmap_attach(qnav_map_t *m, void *buf);
void qnav_cmap_reset(qnav_map_t *m);

/* A cell's evidence as the full layout would hold it: 0 unknown, 1 one arc, 2 occupied,
 * QNAV_MAP_FREE_FLOOR seen free. */
int8_t qnav_cmap_evidence(const qnav_map_t *m, int32_t i, int32_t j);
/* Which of cells 8b .. 8b + 7 of row j were seen free: cell 8b + k in bit k (0 past the
 * row's end). */
uint8_t qnav_cmap_free_bits(const qnav_map_t *m, int32_t b, int32_t j);
/* On hosts (little-endian, neither the ATmega128 nor a Cortex-M, whose benches measure the
 * byte at a time): which cells of row j were seen free, cell i in bit i, for rows of 4 to 8
 * bytes (0 past the row's end). */
#if !defined(__AVR__) && !(defined(__ARM_ARCH_PROFILE) && __ARM_ARCH_PROFILE == 'M') &&          \
    defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define QNAV_CMAP_FREE_ROWS 1
uint64_t qnav_cmap_free_row(const qnav_map_t *m, int32_t j);
#else
#define QNAV_CMAP_FREE_ROWS 0
#endif
/* Seen free; one more arc's evidence (occupied at the second). Both set m->dirty when the
 * cell became or stopped being occupied. */
void qnav_cmap_clear(qnav_map_t *m, int32_t i, int32_t j);
void qnav_cmap_arc(qnav_map_t *m, int32_t i, int32_t j);
/* Every cell not seen free becomes unknown: what an arc marked, and one arc's evidence. */
void qnav_cmap_forget_occupied(qnav_map_t *m);
/* The cell cannot hold the robot's centre (occupied: cells are wider than its reach). */
int qnav_cmap_blocked(const qnav_map_t *m, int32_t i, int32_t j);

/* Cell (i, j) takes what cell (i + di, j + dj) was seen as (unknown when that lies outside
 * the map): the map moved by (di, dj) cells. The plan is left as it was: start another. */
void qnav_cmap_shift(qnav_map_t *m, int32_t di, int32_t dj);

/* A new plan toward the destination's cell c (nothing settled but it). */
void qnav_cmap_plan_start(qnav_map_t *m, uint32_t c);
/* The plan must grow for the robot's cell (ri, rj) (or to be whole, ri < 0). */
int qnav_cmap_needs_growth(const qnav_map_t *m, int32_t ri, int32_t rj);
/* Settle the plan as far as the robot's cell (ri, rj) needs (as map.c's settle_for), or
 * all of it when ri < 0. */
void qnav_cmap_settle(qnav_map_t *m, int32_t ri, int32_t rj);
/* The plan's cost from cell (i, j) (10 a side, 14 a diagonal, along its way);
 * QNAV_MAP_UNREACHED when the cell is not settled. */
uint32_t qnav_cmap_cost(const qnav_map_t *m, int32_t i, int32_t j);
/* Cell (i, j) occupied, whatever it was seen as (a refusal: refuse_compact in map.c). */
void qnav_cmap_occupy(qnav_map_t *m, int32_t i, int32_t j);
/* The plan's cost (10 a side, 14 a diagonal, along its way) from cell (i, j), or, when
 * (i, j) is not settled and is blocked or the plan is whole, from the best settled cell
 * within two (*bi, *bj: that cell); QNAV_MAP_UNREACHED when none is (or the plan is still
 * growing toward an open cell). */
uint32_t qnav_cmap_cost_near(qnav_map_t *m, int32_t i, int32_t j, int32_t *bi,
                             int32_t *bj);
/* One step along the plan from settled cell (*i, *j) toward the destination; 0 at the
 * destination's cell or when (*i, *j) is not settled. */
int qnav_cmap_descend(const qnav_map_t *m, int32_t *i, int32_t *j);

#endif
