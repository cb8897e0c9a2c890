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
#include <simavr/parts/uart_pty.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>

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
        {NULL, 0, NULL, 0}};
    const char *elf = NULL, *link_path = NULL;
    double seconds = 0.0;
    elf_firmware_t fw;
    avr_t *avr;
    static uart_pty_t pty;
    avr_irq_t *adc[8];
    int64_t t0;
    uint64_t last_scene = (uint64_t)-1;
    int c, k, state = cpu_Running;

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
            printf("usage: qnav-simavr-board --elf tekbot.elf [--link PATH] [--seconds S]\n");
            return 0;
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
    uart_pty_connect(&pty, '0');
    if (link_path != NULL) {
        unlink(link_path);
        if (symlink(pty.pty.slavename, link_path) != 0) {
            fprintf(stderr, "qnav-simavr-board: --link %s: %s\n", link_path, strerror(errno));
            return 2;
        }
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
     * ends that thread; only the links made here (and simavr's own) are removed. */
    if (link_path != NULL) {
        unlink(link_path);
    }
    {
        char target[128];
        ssize_t n = readlink("/tmp/simavr-uart0", target, sizeof target - 1);
        if (n > 0) {
            target[n] = '\0';
            if (strcmp(target, pty.pty.slavename) == 0) {
                unlink("/tmp/simavr-uart0");
            }
        }
    }
    return state == cpu_Crashed ? 1 : 0;
}
