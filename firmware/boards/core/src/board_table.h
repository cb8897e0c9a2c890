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

#endif /* QNAV_BOARD_TABLE_H */
