/*
 * Table mode on the board (private to the core; qnav/board.h, "Table mode on the board").
 */
#ifndef QNAV_BOARD_TABLE_H
#define QNAV_BOARD_TABLE_H

#include "qnav/board.h"

/* The controller was just made from bot->policy (start-up, commit, or a fallback): use the
 * HAL's area in table mode now when it holds this policy's table whole, else schedule a
 * build (a 2-input network and an area), else leave the area alone. */
void qnav_board_table_start(qnav_board_t *bot);

/* An upload's chunk or commit arrived: a build under way gives the shared buffer up (qnav/board.h,
 * qnav_board_t.buf) and waits for qnav_board_table_resume. */
void qnav_board_table_yield(qnav_board_t *bot);

/* The upload ended (a commit, refused or not, or the link lost): a build it stopped starts
 * again. */
void qnav_board_table_resume(qnav_board_t *bot);

#endif /* QNAV_BOARD_TABLE_H */
