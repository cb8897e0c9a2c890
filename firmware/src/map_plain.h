/*
 * The map's marking without the host's shortcuts (map.c): the reference that the tests
 * compare qnav_map_observe() with. On hosts only; the ATmega128 and the Cortex-M4 always
 * mark this way.
 */
#ifndef QNAV_MAP_PLAIN_H
#define QNAV_MAP_PLAIN_H

#include "qnav/map.h"

/* qnav_map_observe() through the plain marking (observe_wedges): the same map after it. */
void qnav_map_observe_plain(qnav_map_t *m, const qnav_mm_t *ranges_mm, const qnav_map_pose_t *at);

#endif /* QNAV_MAP_PLAIN_H */
