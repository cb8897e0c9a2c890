/*
 * Where constant tables live. On AVR with QNAV_TABLES_IN_FLASH they are placed in program
 * memory and read with LPM; elsewhere they are ordinary const data. Generated policy
 * headers and the sigmoid table declare their arrays with QNAV_FLASH.
 */
#ifndef QNAV_FLASH_H
#define QNAV_FLASH_H

#include <stdint.h>
#include "qnav/qnav_config.h"

#if QNAV_TABLES_IN_FLASH
#include <avr/pgmspace.h>
#define QNAV_FLASH PROGMEM
#define QNAV_FLASH_READ_I16(p) ((int16_t)pgm_read_word(p))
#define QNAV_FLASH_READ_U16(p) ((uint16_t)pgm_read_word(p))
#else
#define QNAV_FLASH
#define QNAV_FLASH_READ_I16(p) (*(const int16_t *)(p))
#define QNAV_FLASH_READ_U16(p) (*(const uint16_t *)(p))
#endif

#endif /* QNAV_FLASH_H */
