/*
 * Reference hardware layer for an ATmega128 TekBot at 16 MHz (qnav/board_hal.h):
 *   tick    Timer0 compare interrupt every 1 ms
 *   UART    USART0 (PE0 RXD, PE1 TXD), 57600 baud 8N1 with U2X (-0.8 % error),
 *           interrupt-driven receive into a 256-byte ring, polled transmit
 *   sonar   analog sonars (MaxBotix LV-EZ class, AN output ~ Vcc/512 per inch) on
 *           ADC0..ADC7, sector k on ADC(k mod 8); AVcc reference. Up to 16: sectors 8..15
 *           through a 2:1 analog multiplexer in front of the ADC whose select line is PB2
 *           (low: sonars 0..7, high: 8..15)
 *   motors  Timer1 8-bit fast PWM on OC1A (PB5, left) and OC1B (PB6, right); direction on
 *           PB0 (left) and PB1 (right), high = forward
 *   heading wheel-encoder odometry: INT0 (PD0, left) and INT1 (PD1, right), the sign of
 *           each tick taken from that wheel's direction pin; the same counts are the
 *           odometry the core dead-reckons from. The heading per count comes from the
 *           robot's profile (track and encoder scale, qnav/robots.h)
 *   storage the 4 KiB EEPROM (avr-libc eeprom_*_block; a byte takes 8.5 ms to write)
 *   table   46 pages of program memory, page-aligned below 64 KiB, where the core compiles
 *           an uploaded network (qnav/board.h, "Table mode on the board"), written with
 *           SPM by a routine the linker places in the boot loader section (0x1FC00, inside
 *           the boot section for every BOOTSZ setting), the only place SPM works
 * Pin choices and scale factors are the knobs at the top; docs/hil.md lists the wiring.
 */
#include <avr/boot.h>
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>

#include "qnav/board.h"
#include "qnav/drive.h"
#include "qnav/robots.h"

#include "hal_avr.h"

#ifndef QNAV_TEKBOT_BAUD
#define QNAV_TEKBOT_BAUD 57600UL
#endif
/* avr-libc rounds the divider to the nearest rate, picks U2X when it is closer, and warns
 * (an error with -Werror) when the rate is more than 2 % off. */
#define BAUD QNAV_TEKBOT_BAUD
#include <util/setbaud.h>
/* mm of range per ADC count (x10): LV-EZ at 5 V: 9.8 mV/in, 4.88 mV/count -> 12.7 mm */
#ifndef QNAV_TEKBOT_MM_PER_COUNT_X10
#define QNAV_TEKBOT_MM_PER_COUNT_X10 127UL
#endif
/* heading change per differential encoder tick, 1e-6 deg: um_per_count / track_mm rad of
 * the robot's profile (TekBot: 6872 um per count, 180 mm track -> 2.19 deg) */
#define UDEG_PER_TICK ((int64_t)QNAV_BOARD_ROBOT_UDEG_PER_COUNT)

/* sonars per ADC bank, and banks behind the PB2 multiplexer */
#define SONAR_BANK 8u
#define SONAR_MAX 16u


/* Receive ring: it must hold what arrives at line rate while the main loop is busy with a
 * tick (the step, up to 100 000 cycles = 6.3 ms, and the polled transmit of scan, heartbeat
 * and command, about 120 bytes = 21 ms at 57600 baud): about 160 bytes. 64 bytes lost the
 * middle of a policy upload (3 chunks and a commit, about 200 bytes, sent at once) whenever
 * it landed in that window. 256 (an 8-bit index) costs 192 bytes of the 4 KiB. */
#ifndef QNAV_TEKBOT_RX_RING
#define QNAV_TEKBOT_RX_RING 256u
#endif
#define RX_RING QNAV_TEKBOT_RX_RING
#if RX_RING > 256u || RX_RING < 2u
#error "QNAV_TEKBOT_RX_RING: 2..256 (the ring's index is 8 bits)"
#endif

static volatile uint32_t g_ms;
static volatile uint8_t g_rx[RX_RING];
static volatile uint8_t g_rx_head;
static volatile uint8_t g_rx_tail;
/* Interrupt-shared hardware state: the only writable file-scope variables of the firmware
 * (an ISR has no context pointer). */
static volatile int32_t g_left;  /* left encoder counts, forward positive */
static volatile int32_t g_right; /* right encoder counts */

ISR(TIMER0_COMP_vect)
{
    g_ms++;
}

ISR(USART0_RX_vect)
{
    uint8_t b = UDR0;
    uint8_t next = (uint8_t)((g_rx_head + 1u) % RX_RING);
    if (next != g_rx_tail) { /* full: the byte is lost and the frame's CRC catches it */
        g_rx[g_rx_head] = b;
        g_rx_head = next;
    }
}

ISR(INT0_vect)
{
    g_left += (PORTB & _BV(PB0)) ? 1 : -1;
}

ISR(INT1_vect)
{
    g_right += (PORTB & _BV(PB1)) ? 1 : -1;
}

static uint32_t avr_millis(void *ctx)
{
    uint32_t t;
    uint8_t sreg = SREG;
    (void)ctx;
    cli();
    t = g_ms;
    SREG = sreg;
    return t;
}

static uint16_t adc_read(uint8_t ch)
{
    ADMUX = (uint8_t)(_BV(REFS0) | (ch & 0x07u));
    ADCSRA |= _BV(ADSC);
    while (ADCSRA & _BV(ADSC)) {
    }
    return ADCW;
}

static uint16_t avr_sonar_read(void *ctx, qnav_mm_t *ranges_mm, uint16_t max)
{
    uint16_t k;
    uint16_t n = max < SONAR_MAX ? max : SONAR_MAX;
    (void)ctx;
    for (k = 0; k < n; ++k) {
        uint32_t mm;
        if (k == SONAR_BANK) {
            PORTB |= _BV(PB2); /* the second bank; a 74HC4053 settles in well under the
                                  ADC's 1.5-cycle sample-and-hold delay */
        }
        mm = ((uint32_t)adc_read((uint8_t)(k % SONAR_BANK)) * QNAV_TEKBOT_MM_PER_COUNT_X10) / 10u;
        ranges_mm[k] = (qnav_mm_t)(mm > 65535u ? 65535u : mm);
    }
    PORTB &= (uint8_t)~_BV(PB2);
    return n;
}

static qnav_cdeg_t avr_heading_cdeg(void *ctx)
{
    int32_t odo;
    int32_t a;
    uint8_t sreg = SREG;
    (void)ctx;
    cli();
    odo = g_right - g_left; /* left forward turns clockwise */
    SREG = sreg;
    a = (int32_t)(((int64_t)odo * UDEG_PER_TICK / 10000) % 36000L);
    if (a >= 18000L) {
        a -= 36000L;
    } else if (a < -18000L) {
        a += 36000L;
    }
    return (qnav_cdeg_t)a;
}

static uint8_t duty(qnav_q1_15_t v)
{
    uint16_t m = (uint16_t)(v < 0 ? -(int32_t)v : v);
    return (uint8_t)(m >> 7); /* Q1.15 magnitude -> 0..255 */
}

static void avr_odometry(void *ctx, int32_t *left, int32_t *right)
{
    uint8_t sreg = SREG;
    (void)ctx;
    cli();
    *left = g_left;
    *right = g_right;
    SREG = sreg;
}

static void avr_drive(void *ctx, qnav_deg_t heading_deg, qnav_q1_15_t speed, qnav_q1_15_t rolling)
{
    qnav_q1_15_t left;
    qnav_q1_15_t right;
    (void)ctx;
    qnav_drive_mix(heading_deg, speed, rolling, QNAV_BOARD_ROBOT_TURN_FULL_DEG, &left, &right);
    if (left >= 0) {
        PORTB |= _BV(PB0);
    } else {
        PORTB &= (uint8_t)~_BV(PB0);
    }
    if (right >= 0) {
        PORTB |= _BV(PB1);
    } else {
        PORTB &= (uint8_t)~_BV(PB1);
    }
    OCR1A = duty(left);
    OCR1B = duty(right);
}

static int16_t avr_uart_read(void *ctx)
{
    int16_t b = -1;
    uint8_t sreg = SREG;
    (void)ctx;
    cli();
    if (g_rx_tail != g_rx_head) {
        b = g_rx[g_rx_tail];
        g_rx_tail = (uint8_t)((g_rx_tail + 1u) % RX_RING);
    }
    SREG = sreg;
    return b;
}

static void avr_uart_write(void *ctx, const uint8_t *bytes, uint16_t n)
{
    uint16_t i;
    (void)ctx;
    for (i = 0; i < n; ++i) {
        while (!(UCSR0A & _BV(UDRE0))) {
        }
        UDR0 = bytes[i];
    }
}

static uint8_t avr_nvm_read(void *ctx, uint16_t addr, uint8_t *out, uint16_t n)
{
    (void)ctx;
    if ((uint32_t)addr + n > (uint32_t)E2END + 1u) {
        return 0;
    }
    eeprom_read_block(out, (const void *)(uintptr_t)addr, n);
    return 1;
}

static uint8_t avr_nvm_write(void *ctx, uint16_t addr, const uint8_t *bytes, uint16_t n)
{
    (void)ctx;
    if ((uint32_t)addr + n > (uint32_t)E2END + 1u) {
        return 0;
    }
    eeprom_update_block(bytes, (void *)(uintptr_t)addr, n); /* unchanged bytes not rewritten */
    return 1;
}

/* The table area: in .progmem (below 64 KiB, where LPM reaches), page-aligned; zeros in
 * the image, which no record takes for a table. */
#define TABLE_PAGES ((QNAV_BOARD_TABLE_BYTES + SPM_PAGESIZE - 1u) / SPM_PAGESIZE)
static const uint8_t g_table_area[TABLE_PAGES * SPM_PAGESIZE]
    __attribute__((aligned(SPM_PAGESIZE), section(".progmem.qnav_table"), used)) = {0};

/* Erase and write one flash page at byte address addr from bytes (SPM_PAGESIZE). In the
 * boot loader section (.qnav_boot, placed by the image's linker script): a real ATmega128
 * executes SPM only from there. Interrupts stay off: the vectors lie in the RWW section,
 * which cannot be read while a page of it is erased or written (about 9 ms in all). */
__attribute__((section(".qnav_boot"), noinline, used)) static void
boot_write_page(uint32_t addr, const uint8_t *bytes)
{
    const uint8_t sreg = SREG;
    uint16_t i;
    cli();
    eeprom_busy_wait();
    boot_page_erase(addr);
    boot_spm_busy_wait();
    for (i = 0; i < SPM_PAGESIZE; i += 2u) {
        boot_page_fill(addr + i, (uint16_t)(bytes[i] | ((uint16_t)bytes[i + 1u] << 8)));
    }
    boot_page_write(addr);
    boot_spm_busy_wait();
    boot_rww_enable();
    SREG = sreg;
}

static uint8_t avr_table_write_page(void *ctx, uint16_t page, const uint8_t *bytes)
{
    const uint16_t first = (uint16_t)(page * SPM_PAGESIZE);
    uint16_t i;
    (void)ctx;
    if (page >= TABLE_PAGES) {
        return 0;
    }
    boot_write_page((uint32_t)(uintptr_t)&g_table_area[first], bytes);
    for (i = 0; i < SPM_PAGESIZE; ++i) {
        if (pgm_read_byte(&g_table_area[first + i]) != bytes[i]) {
            return 0;
        }
    }
    return 1;
}

void qnav_tekbot_hal_avr_init(qnav_board_hal_t *hal)
{
    /* Timer0: CTC, clk/64, 250 counts = 1 ms at 16 MHz */
    TCCR0 = (uint8_t)(_BV(WGM01) | _BV(CS02));
    OCR0 = (uint8_t)((F_CPU / 64UL / 1000UL) - 1UL);
    TIMSK |= _BV(OCIE0);

    /* USART0: 8N1, receive interrupt */
    UBRR0H = UBRRH_VALUE;
    UBRR0L = UBRRL_VALUE;
    UCSR0A = USE_2X ? _BV(U2X0) : 0u;
    UCSR0C = (uint8_t)(_BV(UCSZ01) | _BV(UCSZ00));
    UCSR0B = (uint8_t)(_BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0));

    /* Timer1: 8-bit fast PWM, clk/8 (7.8 kHz), non-inverting on OC1A/OC1B */
    DDRB |= (uint8_t)(_BV(PB0) | _BV(PB1) | _BV(PB2) | _BV(PB5) | _BV(PB6));
    OCR1A = 0;
    OCR1B = 0;
    TCCR1A = (uint8_t)(_BV(COM1A1) | _BV(COM1B1) | _BV(WGM10));
    TCCR1B = (uint8_t)(_BV(WGM12) | _BV(CS11));

    /* ADC: enabled, clk/128 = 125 kHz */
    ADCSRA = (uint8_t)(_BV(ADEN) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0));

    /* encoders: falling edges on INT0/INT1 with pull-ups */
    PORTD |= (uint8_t)(_BV(PD0) | _BV(PD1));
    EICRA = (uint8_t)(_BV(ISC01) | _BV(ISC11));
    EIMSK |= (uint8_t)(_BV(INT0) | _BV(INT1));

    hal->ctx = 0;
    hal->millis = avr_millis;
    hal->sonar_read = avr_sonar_read;
    hal->heading_cdeg = avr_heading_cdeg;
    hal->odometry_read = avr_odometry;
    hal->drive = avr_drive;
    hal->nvm_read = avr_nvm_read;
    hal->nvm_write = avr_nvm_write;
    hal->nvm_bytes = (uint16_t)(E2END + 1u);
    hal->uart_read = avr_uart_read;
    hal->uart_write = avr_uart_write;
    hal->table_area = g_table_area;
    hal->table_page_bytes = SPM_PAGESIZE;
    hal->table_pages = (uint16_t)TABLE_PAGES;
    hal->table_write_page = avr_table_write_page;
    sei();
}
