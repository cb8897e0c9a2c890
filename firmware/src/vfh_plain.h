/*
 * VFH+'s binary histogram in both of the x86 hosts' bodies (vfh.c): sixteen levels at a
 * time, as qnav_vfh_step() takes it there, and the byte loop that every other target
 * keeps, the reference the tests compare it with. On x86 hosts (SSE2) only.
 */
#ifndef QNAV_VFH_PLAIN_H
#define QNAV_VFH_PLAIN_H

#include "clearance.h"
#include "qnav/vfh.h"

#if defined(QNAV_LEVELS_SSE2)
/* The histogram of the 360 path levels lvl into st's sector bits (hysteresis from st's
 * bits before); the number of blocked sectors. */
uint16_t qnav_vfh_histogram(const qnav_vfh_t *v, qnav_vfh_state_t *st, const uint8_t *lvl);
/* The same through the byte loop: the same bits and count. */
uint16_t qnav_vfh_histogram_plain(const qnav_vfh_t *v, qnav_vfh_state_t *st, const uint8_t *lvl);
#endif

#endif /* QNAV_VFH_PLAIN_H */
