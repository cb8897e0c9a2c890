/*
 * qnav-simavr-board: the TekBot firmware image itself (tekbot.elf, built for the ATmega128)
 * running cycle by cycle in simavr, with its USART0 on a pseudo-terminal (simavr's
 * uart_pty part), so navbridge talks to the real board code without hardware. Sonar
 * voltages are fed into ADC0..7 from a slowly changing scene; the encoders stay still, so
 * the heading reads 0. Simulated time is held to the wall clock so the board's 10 Hz tick
 * and link timeout mean what they say.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include <errno.h>
#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <simavr/avr_adc.h>
#include <simavr/avr_uart.h>
#include <simavr/parts/uart_pty.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>

#include "ptylink.h"
#include "qnav/cli.h"

static volatile sig_atomic_t g_quit = 0;

/* simavr keeps the firmware image and its symbol table allocated until exit, and its
 * uart_pty thread cannot be joined: in sanitizer builds, leak checking here would only
 * report simavr's own allocations (this program allocates nothing itself). */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "detect_leaks=0";
}

static void on_signal(int sig)
{
    g_quit = sig;
}

static int64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* the accessors of the part's fifo (its header only declares the type) */
DEFINE_FIFO(uint8_t, uart_pty_fifo);

/* The USART's flow control, as uart_pty_connect() registers it: bytes from the pty wait in
 * the part's fifo and go on to the MCU while the USART has room (xon), from this hook. */
static void on_uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
    uart_pty_t *p = (uart_pty_t *)param;
    (void)irq;
    (void)value;
    p->xon = 1;
    while (p->xon && !uart_pty_fifo_isempty(&p->pty.out)) {
        avr_raise_irq(p->irq + IRQ_UART_PTY_BYTE_OUT, uart_pty_fifo_read(&p->pty.out));
    }
}

static void on_uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)value;
    ((uart_pty_t *)param)->xon = 0;
}

/* USART0 <-> the pty, what uart_pty_connect(p, '0') does minus the fixed, shared link
 * /tmp/simavr-uart0 that it unlinks and remakes (two boards would take each other's, and
 * it deletes whatever file has that name). The pty's own /dev/pts/N name is unique. */
static void connect_uart0(avr_t *avr, uart_pty_t *p)
{
    uint32_t flags = 0;
    avr_irq_t *src = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT);
    avr_irq_t *dst = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    avr_irq_t *xon = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON);
    avr_irq_t *xoff = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF);
    /* binary frames: no copy of the UART on stdout */
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)AVR_UART_FLAG_STDIO;
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    if (src != NULL && dst != NULL) {
        avr_connect_irq(src, p->irq + IRQ_UART_PTY_BYTE_IN);
        avr_connect_irq(p->irq + IRQ_UART_PTY_BYTE_OUT, dst);
    }
    if (xon != NULL) {
        avr_irq_register_notify(xon, on_uart_xon, p);
    }
    if (xoff != NULL) {
        avr_irq_register_notify(xoff, on_uart_xoff, p);
    }
}

/* Sonar k's voltage for a range in mm at 5 V: 12.7 mm per ADC count of 4.883 mV. */
static uint32_t range_to_mv(uint32_t mm)
{
    return (uint32_t)((double)mm / 12.7 * (5000.0 / 1024.0));
}

int main(int argc, char **argv)
{
    static const struct option opts[] = {
        {"elf", required_argument, NULL, 'e'},    {"link", required_argument, NULL, 'l'},
        {"seconds", required_argument, NULL, 's'}, {"help", no_argument, NULL, 'h'},
        {"version", no_argument, NULL, 'V'},       {NULL, 0, NULL, 0}};
    const char *elf = NULL, *link_path = NULL;
    double seconds = 0.0;
    elf_firmware_t fw;
    avr_t *avr;
    static uart_pty_t pty;
    avr_irq_t *adc[8];
    int64_t t0;
    uint64_t last_scene = (uint64_t)-1;
    int c, k, state = cpu_Running;
    char err[512];

    opterr = 0;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'e': elf = optarg; break;
        case 'l': link_path = optarg; break;
        case 's': {
            char *end = NULL;
            seconds = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(seconds >= 0.0)) {
                fprintf(stderr, "qnav-simavr-board: --seconds %s: expected a number >= 0\n",
                        optarg);
                return 2;
            }
            break;
        }
        case 'h':
            printf("usage: qnav-simavr-board --elf tekbot.elf [--link PATH] [--seconds S]\n"
                   "  --elf FILE     the TekBot firmware image (tekbot-avr.elf)\n"
                   "  --link PATH    also make PATH a symlink to the board's pty\n"
                   "  --seconds S    stop after S simulated seconds (0: run until a signal)\n"
                   "  --help, --version  this text; the version\n");
            return 0;
        case 'V': fputs(QNAV_CLI_VERSION_LINE("qnav-simavr-board"), stdout); return 0;
        default:
            fprintf(stderr, "qnav-simavr-board: %s: unknown option or missing value\n",
                    argv[optind - 1]);
            return 2;
        }
    }
    if (elf == NULL) {
        fprintf(stderr, "qnav-simavr-board: --elf: required\n");
        return 2;
    }
    if (access(elf, R_OK) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s: %s\n", elf, strerror(errno));
        return 2;
    }
    memset(&fw, 0, sizeof fw);
    if (elf_read_firmware(elf, &fw) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s: not an AVR ELF image\n", elf);
        return 2;
    }
    if (fw.mmcu[0] == '\0') {
        snprintf(fw.mmcu, sizeof fw.mmcu, "atmega128");
    }
    if (fw.frequency == 0) {
        fw.frequency = 16000000;
    }
    avr = avr_make_mcu_by_name(fw.mmcu);
    if (avr == NULL) {
        fprintf(stderr, "qnav-simavr-board: %s: simavr does not know MCU '%s'\n", elf, fw.mmcu);
        return 2;
    }
    avr_init(avr);
    avr_load_firmware(avr, &fw);
    avr->log = 0;
    avr->vcc = 5000;
    avr->avcc = 5000;
    avr->aref = 5000;

    uart_pty_init(avr, &pty);
    connect_uart0(avr, &pty);
    if (link_path != NULL &&
        qnav_ptylink_make(link_path, pty.pty.slavename, err, sizeof err) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s\n", err);
        return 2;
    }
    printf("qnav-simavr-board: %s (%s, %u Hz) with USART0 on %s%s%s\n", elf, fw.mmcu,
           (unsigned)fw.frequency, pty.pty.slavename, link_path ? " = " : "",
           link_path ? link_path : "");
    fflush(stdout);
    for (k = 0; k < 8; ++k) {
        adc[k] = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + k);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);

    t0 = mono_us();
    while (!g_quit && state != cpu_Done && state != cpu_Crashed) {
        uint64_t sim_us = avr->cycle / (fw.frequency / 1000000u);
        uint64_t scene = sim_us / 500000u; /* a new scene every 0.5 s */
        int64_t ahead;
        if (scene != last_scene) {
            /* an obstacle that walks round the robot; the rest open at 2 m .. 2.5 m */
            for (k = 0; k < 8; ++k) {
                uint32_t mm = ((uint64_t)k == scene % 8u) ? 400u : 2000u + 70u * (uint32_t)k;
                avr_raise_irq(adc[k], range_to_mv(mm));
            }
            last_scene = scene;
        }
        if (seconds > 0.0 && (double)sim_us >= seconds * 1e6) {
            break;
        }
        for (k = 0; k < 2000 && state != cpu_Done && state != cpu_Crashed; ++k) {
            state = avr_run(avr);
        }
        ahead = (int64_t)sim_us - (mono_us() - t0);
        if (ahead > 2000) {
            usleep((useconds_t)ahead);
        }
    }
    printf("qnav-simavr-board: stopped after %.2f simulated s (%s)\n",
           (double)avr->cycle / (double)fw.frequency,
           state == cpu_Crashed ? "crashed" : (g_quit ? "signal" : "done"));
    fflush(stdout);
    /* not uart_pty_stop(): in simavr 1.6 it joins a thread that never returns. Exiting
     * ends that thread; only the link made here is removed, and only if still ours. */
    qnav_ptylink_remove(link_path, pty.pty.slavename);
    return state == cpu_Crashed ? 1 : 0;
}
