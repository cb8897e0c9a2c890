/*
 * The ATmega128 TekBot's hardware layer: sets up timers, USART0, ADC, PWM and encoder
 * interrupts, and fills a qnav_board_hal_t with functions over them (hal_avr.c).
 */
#ifndef QNAV_TEKBOT_HAL_AVR_H
#define QNAV_TEKBOT_HAL_AVR_H

#include "qnav/board_hal.h"

/* Configure the peripherals, fill hal, enable interrupts. */
void qnav_tekbot_hal_avr_init(qnav_board_hal_t *hal);

#endif /* QNAV_TEKBOT_HAL_AVR_H */
