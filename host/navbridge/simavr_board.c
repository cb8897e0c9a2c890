/*
 * qnav-simavr-board: a board's firmware image itself (tekbot-avr.elf or pioneer3dx-avr.elf,
 * built for the ATmega128) running cycle by cycle in simavr, with its USART0 on a
 * pseudo-terminal served from the simulation loop, so navbridge talks to the real board
 * code without hardware. --robot names the robot the image must be built for: the board's
 * CONFIG report is compared with that profile's configuration and a board that differs is
 * refused (one line naming the field, status 1). Sonar voltages for the profile's sectors
 * are fed into ADC0..7 (sectors 8..15 through the PB2 multiplexer) from a slowly changing
 * scene; the encoders stay still, so the heading reads 0. Simulated time is held to the wall clock so the board's 10 Hz tick
 * and link timeout mean what they say. --eeprom FILE is the MCU's EEPROM across runs
 * (loaded at start, saved at exit: a run is a power cycle); --power-cut-after N stops the
 * MCU dead once N bytes of its EEPROM have changed, as a power loss in the middle of a
 * write would, and saves what had been written by then. --flash FILE keeps what the
 * firmware wrote into its own flash with SPM (the board's table area) across runs the
 * same way: saved at exit, and at start laid over the pages that are blank in the image.
 */
#define _XOPEN_SOURCE 700
#define _DEFAULT_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <pty.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <simavr/avr_adc.h>
#include <simavr/avr_eeprom.h>
#include <simavr/avr_ioport.h>
#include <simavr/avr_uart.h>
#include <simavr/sim_avr.h>
#include <simavr/sim_elf.h>

#include "ptylink.h"
#include "qnav/cli.h"
#include "qnav/clock.h"
#include "qnav/link.h"
#include "robot_board.h"

static volatile sig_atomic_t g_quit = 0;

/* simavr keeps the firmware image and its symbol table allocated until exit: in sanitizer
 * builds, leak checking here would only report simavr's own allocations (this program
 * allocates nothing itself). */
const char *__asan_default_options(void);
const char *__asan_default_options(void)
{
    return "detect_leaks=0";
}

static void on_signal(int sig)
{
    g_quit = sig;
}

/* USART0 on a pseudo-terminal, served from the simulation loop itself. Not simavr's
 * uart_pty part: its thread and the MCU's thread both take bytes out of one unlocked fifo
 * in simavr 1.6 (a race that loses or repeats link bytes under load), and its
 * uart_pty_connect() unlinks and remakes the shared /tmp/simavr-uart0 (two boards take
 * each other's, and a file of that name is deleted). The pty's /dev/pts/N name is unique. */
typedef struct {
    int master, slave;            /* slave kept open: no EIO before navbridge attaches */
    char name[64];                /* /dev/pts/N */
    avr_irq_t *to_mcu;            /* UART_IRQ_INPUT */
    int xon;                      /* the USART's input fifo has room */
    uint64_t cycles_per_byte;     /* one character (10 bits) at the link's baud rate */
    uint64_t next_byte_cycle;     /* the MCU cycle at which the next byte may arrive */
    uint8_t in[512];              /* pty -> MCU */
    size_t in_len, in_done;
    uint8_t out[4096];            /* MCU -> pty */
    size_t out_len;
} board_uart_t;

/* The board's CONFIG reports, read from what it sends, against the robot's profile. */
typedef struct {
    qnav_link_rx_t rx;
    const qnav_board_config_t *expected;
    qnav_board_map_info_t expected_map;
    int checked;                  /* a report matched */
    int refused;                  /* a report differed: diff says how */
    char diff[96];
} config_watch_t;

static config_watch_t g_watch;

static void watch_byte(config_watch_t *w, uint8_t b)
{
    qnav_link_frame_t f;
    qnav_link_config_t m;
    if (qnav_link_rx_feed(&w->rx, b, &f) && f.msg_id == QNAV_LINK_MSG_CONFIG &&
        qnav_link_config_unpack(f.payload, f.len, &m) == QNAV_LINK_OK) {
        if (qnav_robot_board_diff(&m, w->expected, &w->expected_map, w->diff, sizeof w->diff) ==
            0) {
            w->checked = 1;
        } else {
            w->refused = 1;
        }
    }
}

static void on_uart_byte(struct avr_irq_t *irq, uint32_t value, void *param)
{
    board_uart_t *u = (board_uart_t *)param;
    (void)irq;
    watch_byte(&g_watch, (uint8_t)value);
    if (u->out_len < sizeof u->out) {
        u->out[u->out_len++] = (uint8_t)value;
    } /* else: nobody reads the port, dropped like a UART with no listener */
}

/* Bytes reach the MCU no faster than the line rate, as on a real UART: a burst that
 * queued in the pty while this process was not scheduled would otherwise arrive at once
 * and overrun the firmware's receive buffer. */
static void feed_mcu(board_uart_t *u, uint64_t cycle)
{
    while (u->xon && u->in_done < u->in_len && cycle >= u->next_byte_cycle) {
        avr_raise_irq(u->to_mcu, u->in[u->in_done++]);
        u->next_byte_cycle = (cycle > u->next_byte_cycle + u->cycles_per_byte
                                  ? cycle : u->next_byte_cycle) + u->cycles_per_byte;
    }
}

static void on_uart_xon(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    (void)value;
    ((board_uart_t *)param)->xon = 1;
}

static void on_uart_xoff(struct avr_irq_t *irq, uint32_t value, void *param)
{
    (void)irq;
    if (value != 0u) { /* simavr also raises XOFF with 0 as its fifo empties */
        ((board_uart_t *)param)->xon = 0;
    }
}

static int uart_open(avr_t *avr, board_uart_t *u, uint32_t f_cpu, uint32_t baud)
{
    uint32_t flags = 0;
    struct termios tio;
    avr_irq_t *src = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT);
    avr_irq_t *xon = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON);
    avr_irq_t *xoff = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF);
    memset(u, 0, sizeof *u);
    u->to_mcu = avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
    if (src == NULL || u->to_mcu == NULL ||
        openpty(&u->master, &u->slave, u->name, NULL, NULL) != 0) {
        return -1;
    }
    if (tcgetattr(u->slave, &tio) == 0) {
        cfmakeraw(&tio);
        tcsetattr(u->slave, TCSANOW, &tio);
    }
    fcntl(u->master, F_SETFL, fcntl(u->master, F_GETFL) | O_NONBLOCK);
    /* binary frames: no copy of the UART on stdout */
    avr_ioctl(avr, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
    flags &= ~(uint32_t)AVR_UART_FLAG_STDIO;
    avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
    avr_irq_register_notify(src, on_uart_byte, u);
    u->xon = 1; /* the USART starts empty; XOFF says when its fifo is full */
    u->cycles_per_byte = (uint64_t)f_cpu * 10u / baud;
    if (xon != NULL) {
        avr_irq_register_notify(xon, on_uart_xon, u);
    }
    if (xoff != NULL) {
        avr_irq_register_notify(xoff, on_uart_xoff, u);
    }
    return 0;
}

/* Move bytes both ways without blocking: what the MCU sent to the pty, what the pty holds
 * to the MCU (as fast as the USART takes them). */
static void uart_service(board_uart_t *u, uint64_t cycle)
{
    if (u->out_len > 0) {
        ssize_t n = write(u->master, u->out, u->out_len);
        if (n > 0) {
            memmove(u->out, u->out + n, u->out_len - (size_t)n);
            u->out_len -= (size_t)n;
        }
    }
    if (u->in_done == u->in_len) {
        ssize_t n = read(u->master, u->in, sizeof u->in);
        u->in_done = 0;
        u->in_len = n > 0 ? (size_t)n : 0u;
    }
    feed_mcu(u, cycle);
}

/* Sonar k's voltage for a range in mm at 5 V: 12.7 mm per ADC count of 4.883 mV. */
static uint32_t range_to_mv(uint32_t mm)
{
    return (uint32_t)((double)mm / 12.7 * (5000.0 / 1024.0));
}

/* The sonar scene: ranges of up to 16 sectors, sectors 8..15 on the ADC while the board's
 * PB2 multiplexer select line is high (hal_avr.c). */
typedef struct {
    avr_irq_t *adc[8];
    uint32_t mm[16];
    int bank;                     /* 0: sectors 0..7 on ADC0..7, 1: sectors 8..15 */
} sonar_scene_t;

static void scene_apply(sonar_scene_t *sc)
{
    int k;
    for (k = 0; k < 8; ++k) {
        avr_raise_irq(sc->adc[k], range_to_mv(sc->mm[8 * sc->bank + k]));
    }
}

static void on_mux_select(struct avr_irq_t *irq, uint32_t value, void *param)
{
    sonar_scene_t *sc = (sonar_scene_t *)param;
    (void)irq;
    sc->bank = value != 0u;
    scene_apply(sc);
}

#define EEPROM_BYTES 4096 /* ATmega128 */

/* The first n bytes of the MCU's EEPROM into out. simavr 1.6's EEPROM ioctls return -1
 * even when they succeed, so their result is not looked at: eeprom_load checks by
 * reading back. */
static int eeprom_read(avr_t *avr, uint8_t *out, uint32_t n)
{
    avr_eeprom_desc_t d;
    d.ee = out;
    d.offset = 0;
    d.size = n;
    (void)avr_ioctl(avr, AVR_IOCTL_EEPROM_GET, &d);
    return 0;
}

/* Load FILE into the MCU's EEPROM (absent: left erased). 0, or -1 with a message. */
static int eeprom_load(avr_t *avr, const char *path, uint8_t *image)
{
    avr_eeprom_desc_t d;
    FILE *f = fopen(path, "rb");
    size_t n;
    memset(image, 0xFF, EEPROM_BYTES);
    if (f == NULL) {
        if (errno == ENOENT) {
            f = NULL; /* a new EEPROM: erased; set below so that the check runs too */
        } else {
            fprintf(stderr, "qnav-simavr-board: --eeprom %s: %s\n", path, strerror(errno));
            return -1;
        }
    }
    if (f != NULL) {
        n = fread(image, 1, EEPROM_BYTES, f);
        if (n != EEPROM_BYTES || fgetc(f) != EOF) {
            fclose(f);
            fprintf(stderr, "qnav-simavr-board: --eeprom %s: not a %d-byte EEPROM image\n",
                    path, EEPROM_BYTES);
            return -1;
        }
        fclose(f);
    }
    d.ee = image;
    d.offset = 0;
    d.size = EEPROM_BYTES;
    (void)avr_ioctl(avr, AVR_IOCTL_EEPROM_SET, &d);
    {
        static uint8_t back[EEPROM_BYTES];
        memset(back, (int)(uint8_t)~image[0], sizeof back);
        (void)eeprom_read(avr, back, EEPROM_BYTES);
        if (memcmp(back, image, EEPROM_BYTES) != 0) {
            fprintf(stderr, "qnav-simavr-board: --eeprom %s: simavr did not take the image\n",
                    path);
            return -1;
        }
    }
    return 0;
}

static int eeprom_save(avr_t *avr, const char *path)
{
    static uint8_t ee[EEPROM_BYTES];
    FILE *f = eeprom_read(avr, ee, EEPROM_BYTES) == 0 ? fopen(path, "wb") : NULL;
    if (f == NULL || fwrite(ee, 1, EEPROM_BYTES, f) != EEPROM_BYTES || fclose(f) != 0) {
        fprintf(stderr, "qnav-simavr-board: --eeprom %s: cannot save: %s\n", path,
                strerror(errno));
        return -1;
    }
    return 0;
}

/* Bytes watched for a power cut: the board keeps its policy store at the start of the
 * EEPROM (two slots of 8 + up to 132 bytes on the ATmega128). */
#define WATCHED_BYTES 512

/* EECR, the EEPROM control register, as a data-space address (ATmega128: I/O 0x1C). Every
 * EEPROM write sets it, and simavr writes the byte at that instruction: the bytes are
 * compared only after a write to it, so a power cut costs nothing between writes (comparing
 * every few instructions ran the board five times slower than the wall clock, and the
 * bridge's traffic, paced by the wall clock, then came five times denser than on a board). */
#define ATMEGA128_EECR 0x3Cu

static volatile int g_eecr_written;

static void on_eecr_write(avr_t *avr, avr_io_addr_t addr, uint8_t v, void *param)
{
    (void)avr;
    (void)addr;
    (void)v;
    (void)param;
    g_eecr_written = 1;
}

/* Watched bytes of the EEPROM that differ from the image at start. */
static long eeprom_changed(avr_t *avr, const uint8_t *start)
{
    uint8_t now[WATCHED_BYTES];
    long n = 0;
    int k;
    if (eeprom_read(avr, now, WATCHED_BYTES) != 0) {
        return 0;
    }
    for (k = 0; k < WATCHED_BYTES; ++k) {
        n += now[k] != start[k];
    }
    return n;
}

/* --flash: the flash as the firmware left it, saved at exit, and its pages laid at start
 * over the image's blank pages (all 0x00 or all 0xFF: the board's table area, never code),
 * so a run is a power cycle for what SPM wrote, while a rebuilt image keeps its code. */
#define FLASH_PAGE 256u

static int page_blank(const uint8_t *p)
{
    uint32_t i;
    for (i = 1; i < FLASH_PAGE; ++i) {
        if (p[i] != p[0]) {
            return 0;
        }
    }
    return p[0] == 0x00u || p[0] == 0xFFu;
}

/* 0, or -1 with one line. An absent FILE leaves the image as it is. */
static int flash_load(avr_t *avr, const char *path)
{
    const uint32_t size = (uint32_t)avr->flashend + 1u;
    uint8_t *saved;
    FILE *f = fopen(path, "rb");
    uint32_t at;
    if (f == NULL) {
        if (errno == ENOENT) {
            return 0;
        }
        fprintf(stderr, "qnav-simavr-board: --flash %s: %s\n", path, strerror(errno));
        return -1;
    }
    saved = malloc(size);
    if (saved == NULL || fread(saved, 1, size, f) != size || fgetc(f) != EOF) {
        fprintf(stderr, "qnav-simavr-board: --flash %s: not a %u-byte flash image\n", path,
                (unsigned)size);
        free(saved);
        fclose(f);
        return -1;
    }
    fclose(f);
    for (at = 0; at + FLASH_PAGE <= size; at += FLASH_PAGE) {
        if (page_blank(avr->flash + at)) {
            memcpy(avr->flash + at, saved + at, FLASH_PAGE);
        }
    }
    free(saved);
    return 0;
}

static int flash_save(avr_t *avr, const char *path)
{
    const size_t size = (size_t)avr->flashend + 1u;
    FILE *f = fopen(path, "wb");
    if (f == NULL || fwrite(avr->flash, 1, size, f) != size || fclose(f) != 0) {
        fprintf(stderr, "qnav-simavr-board: --flash %s: cannot save: %s\n", path,
                strerror(errno));
        return -1;
    }
    return 0;
}

/* Everything the command line says. */
typedef struct {
    const char *robot_spec;
    const char *eeprom_path;
    const char *flash_path;
    const char *elf;
    const char *link_path;
    long cut_after;
    double seconds;
    double baud;
} options_t;

static void usage(void)
{
    printf("usage: qnav-simavr-board --elf IMAGE [--robot NAME|FILE] [--link PATH]\n"
           "                         [--seconds S] [--baud N]\n"
           "                         [--eeprom FILE [--power-cut-after N]] [--flash FILE]\n"
           "  --elf FILE     the board's firmware image (tekbot-avr.elf, pioneer3dx-avr.elf)\n"
           "  --robot R      the robot profile the image must be built for (tekbot): a\n"
           "                 board reporting another configuration is refused\n"
           "  --link PATH    also make PATH a symlink to the board's pty\n"
           "  --seconds S    stop after S simulated seconds (0: run until a signal)\n"
           "  --baud N       the firmware's line rate: bytes reach USART0 no faster\n"
           "                 (57600, the TekBot's)\n"
           "  --eeprom FILE  the EEPROM: loaded at start (absent: erased), saved at exit\n"
           "  --power-cut-after N  stop dead once N EEPROM bytes have changed\n"
           "  --flash FILE   what the firmware wrote into its flash (its table area): laid\n"
           "                 over the image's blank pages at start, saved at exit\n"
           "  --help, --version  this text; the version\n");
}

/* The options with a number (--power-cut-after, --seconds, --baud) into o; 0, or 2 after
 * one line. */
static int parse_number(int c, const char *arg, options_t *o)
{
    char *end = NULL;
    switch (c) {
    case 'C':
        o->cut_after = strtol(arg, &end, 10);
        if (end == arg || *end != '\0' || o->cut_after < 1 || o->cut_after > WATCHED_BYTES) {
            fprintf(stderr, "qnav-simavr-board: --power-cut-after %s: expected a number "
                            "of EEPROM bytes in 1..%d\n", arg, WATCHED_BYTES);
            return 2;
        }
        return 0;
    case 's':
        o->seconds = strtod(arg, &end);
        if (end == arg || *end != '\0' || !(o->seconds >= 0.0)) {
            fprintf(stderr, "qnav-simavr-board: --seconds %s: expected a number >= 0\n", arg);
            return 2;
        }
        return 0;
    default: /* 'b' */
        o->baud = strtod(arg, &end);
        if (end == arg || *end != '\0' || !(o->baud >= 300.0 && o->baud <= 2000000.0)) {
            fprintf(stderr, "qnav-simavr-board: --baud %s: expected 300..2000000\n", arg);
            return 2;
        }
        return 0;
    }
}

/* The command line into o: -1 to go on, else the exit status. */
static int parse_args(int argc, char **argv, options_t *o)
{
    static const struct option opts[] = {
        {"elf", required_argument, NULL, 'e'},    {"link", required_argument, NULL, 'l'},
        {"seconds", required_argument, NULL, 's'}, {"help", no_argument, NULL, 'h'},
        {"baud", required_argument, NULL, 'b'},
        {"version", no_argument, NULL, 'V'},       {"eeprom", required_argument, NULL, 'E'},
        {"power-cut-after", required_argument, NULL, 'C'},
        {"robot", required_argument, NULL, 'r'},   {"flash", required_argument, NULL, 'F'},
        {NULL, 0, NULL, 0}};
    int c;
    memset(o, 0, sizeof *o);
    o->robot_spec = "tekbot";
    o->baud = 57600.0;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "", opts, NULL)) != -1) {
        switch (c) {
        case 'e': o->elf = optarg; break;
        case 'E': o->eeprom_path = optarg; break;
        case 'F': o->flash_path = optarg; break;
        case 'l': o->link_path = optarg; break;
        case 'r': o->robot_spec = optarg; break;
        case 'C':
        case 's':
        case 'b':
            if (parse_number(c, optarg, o) != 0) {
                return 2;
            }
            break;
        case 'h': usage(); return 0;
        case 'V': fputs(QNAV_CLI_VERSION_LINE("qnav-simavr-board"), stdout); return 0;
        default:
            fprintf(stderr, "qnav-simavr-board: %s: unknown option or missing value\n",
                    argv[optind - 1]);
            return 2;
        }
    }
    if (o->elf == NULL) {
        fprintf(stderr, "qnav-simavr-board: --elf: required\n");
        return 2;
    }
    return -1;
}

/* --robot's board configuration into expected, watched for in the board's CONFIG reports;
 * the sonar sectors the scene feeds (at most 16) into *sectors. 0, or 2 after one line. */
static int load_robot(const char *spec, qnav_board_config_t *expected, int *sectors)
{
    char rerr[QNAV_SIM_ERRLEN];
    if (qnav_robot_board_load(spec, expected, &g_watch.expected_map, rerr, sizeof rerr) !=
        QNAV_SIM_OK) {
        fprintf(stderr, "qnav-simavr-board: --robot: %s\n", rerr);
        return 2;
    }
    *sectors = expected->ctrl.n_sectors > 16u ? 16 : (int)expected->ctrl.n_sectors;
    qnav_link_rx_init(&g_watch.rx);
    g_watch.expected = expected;
    return 0;
}

/* The MCU with the image loaded (ATmega128 at 16 MHz unless the image says otherwise);
 * null after one line. */
static avr_t *make_mcu(const char *elf, elf_firmware_t *fw)
{
    avr_t *avr;
    if (access(elf, R_OK) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s: %s\n", elf, strerror(errno));
        return NULL;
    }
    memset(fw, 0, sizeof *fw);
    if (elf_read_firmware(elf, fw) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s: not an AVR ELF image\n", elf);
        return NULL;
    }
    if (fw->mmcu[0] == '\0') {
        snprintf(fw->mmcu, sizeof fw->mmcu, "atmega128");
    }
    if (fw->frequency == 0) {
        fw->frequency = 16000000;
    }
    avr = avr_make_mcu_by_name(fw->mmcu);
    if (avr == NULL) {
        fprintf(stderr, "qnav-simavr-board: %s: simavr does not know MCU '%s'\n", elf, fw->mmcu);
        return NULL;
    }
    avr_init(avr);
    avr_load_firmware(avr, fw);
    avr->log = 0;
    avr->vcc = 5000;
    avr->avcc = 5000;
    avr->aref = 5000;
    return avr;
}

/* --eeprom and --power-cut-after on the MCU; 0, or 2 after one line. */
static int attach_eeprom(const options_t *o, avr_t *avr, const elf_firmware_t *fw,
                         uint8_t *ee_start)
{
    if (o->cut_after > 0 && o->eeprom_path == NULL) {
        fprintf(stderr, "qnav-simavr-board: --power-cut-after: needs --eeprom FILE\n");
        return 2;
    }
    if (o->eeprom_path != NULL && eeprom_load(avr, o->eeprom_path, ee_start) != 0) {
        return 2;
    }
    if (o->cut_after > 0) {
        if (strcmp(fw->mmcu, "atmega128") != 0) {
            fprintf(stderr, "qnav-simavr-board: --power-cut-after: knows the ATmega128's "
                            "EEPROM only, not the %s's\n", fw->mmcu);
            return 2;
        }
        avr_register_io_write(avr, ATMEGA128_EECR, on_eecr_write, NULL);
    }
    return 0;
}

/* USART0 on a pty (and --link to it), the sonar ADCs and the multiplexer, the signals.
 * 0, or the exit status after one line. */
static int attach_io(const options_t *o, avr_t *avr, const elf_firmware_t *fw,
                     board_uart_t *uart, sonar_scene_t *scene)
{
    char err[512];
    int k;
    if (uart_open(avr, uart, fw->frequency, (uint32_t)o->baud) != 0) {
        fprintf(stderr, "qnav-simavr-board: cannot put USART0 on a pseudo-terminal: %s\n",
                strerror(errno));
        return 1;
    }
    if (o->link_path != NULL && qnav_ptylink_make(o->link_path, uart->name, err, sizeof err) != 0) {
        fprintf(stderr, "qnav-simavr-board: %s\n", err);
        return 2;
    }
    printf("qnav-simavr-board: %s (%s, %u Hz) with USART0 on %s%s%s\n", o->elf, fw->mmcu,
           (unsigned)fw->frequency, uart->name, o->link_path ? " = " : "",
           o->link_path ? o->link_path : "");
    fflush(stdout);
    for (k = 0; k < 8; ++k) {
        scene->adc[k] = avr_io_getirq(avr, AVR_IOCTL_ADC_GETIRQ, ADC_IRQ_ADC0 + k);
    }
    avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_IOPORT_GETIRQ('B'), 2), on_mux_select,
                            scene);
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    return 0;
}

/* The scene of 0.5 s step `step`: an obstacle that walks round the robot; the rest open at
 * 2 m and beyond. */
static void scene_at(sonar_scene_t *scene, uint64_t step, int sectors)
{
    int k;
    for (k = 0; k < 16; ++k) {
        scene->mm[k] = ((uint64_t)k == step % (uint64_t)sectors)
                           ? 400u : 2000u + (uint32_t)(400 / sectors) * (uint32_t)(k % sectors);
    }
    scene_apply(scene);
}

/* What ended a run. */
typedef struct {
    int state;   /* simavr's cpu state */
    int refused; /* the board's configuration differs from the robot's */
} run_end_t;

/* Run the MCU, held to the wall clock, until a signal, --seconds, a power cut, a refused
 * board or the MCU's end. */
static run_end_t run_board(const options_t *o, avr_t *avr, const elf_firmware_t *fw,
                           board_uart_t *uart, sonar_scene_t *scene, int sectors,
                           const uint8_t *ee_start)
{
    run_end_t end = {cpu_Running, 0};
    uint64_t last_scene = (uint64_t)-1;
    long changed = 0;
    int64_t t0 = qnav_mono_us();
    while (!g_quit && end.state != cpu_Done && end.state != cpu_Crashed) {
        uint64_t sim_us = avr->cycle / (fw->frequency / 1000000u);
        uint64_t step = sim_us / 500000u; /* a new scene every 0.5 s */
        int64_t ahead;
        int k;
        if (g_watch.refused) {
            fprintf(stderr, "qnav-simavr-board: board configuration differs from robot '%s': %s\n",
                    o->robot_spec, g_watch.diff);
            end.refused = 1;
            break;
        }
        if (step != last_scene) {
            scene_at(scene, step, sectors);
            last_scene = step;
        }
        if (o->seconds > 0.0 && (double)sim_us >= o->seconds * 1e6) {
            break;
        }
        for (k = 0; k < 2000 && end.state != cpu_Done && end.state != cpu_Crashed; ++k) {
            end.state = avr_run(avr);
            /* the instruction that wrote EECR wrote the byte: the cut comes right after it */
            if (g_eecr_written) {
                g_eecr_written = 0;
                if ((changed = eeprom_changed(avr, ee_start)) >= o->cut_after) {
                    break;
                }
            }
        }
        if (o->cut_after > 0 && changed >= o->cut_after) {
            printf("qnav-simavr-board: power cut after %ld changed EEPROM bytes\n", changed);
            break;
        }
        uart_service(uart, avr->cycle);
        ahead = (int64_t)sim_us - (qnav_mono_us() - t0);
        if (ahead > 2000) {
            usleep((useconds_t)ahead);
        }
    }
    return end;
}

/* How deep the stack went: RAM above .data and .bss starts zero and the firmware never
 * writes it but through the stack, so the lowest byte written there is the stack's deepest
 * point (a zero pushed exactly there would read as untouched: an estimate within a few
 * bytes). */
static void put_stack_reach(const avr_t *avr, const elf_firmware_t *fw)
{
    const uint32_t start = 0x100u + fw->datasize + fw->bsssize; /* ATmega128 SRAM from 0x100 */
    uint32_t a = start;
    while (a <= avr->ramend && avr->data[a] == 0u) {
        ++a;
    }
    printf("qnav-simavr-board: the stack reached %u bytes below the top of RAM; %u bytes above "
           ".data and .bss were never written\n",
           (unsigned)(avr->ramend + 1u - a), (unsigned)(a - start));
}

int main(int argc, char **argv)
{
    static options_t o;
    static qnav_board_config_t expected;
    static sonar_scene_t scene;
    static uint8_t ee_start[EEPROM_BYTES];
    static board_uart_t uart;
    elf_firmware_t fw;
    avr_t *avr;
    run_end_t end;
    int sectors = 0;
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0) {
        return rc;
    }
    if (load_robot(o.robot_spec, &expected, &sectors) != 0) {
        return 2;
    }
    avr = make_mcu(o.elf, &fw);
    if (avr == NULL) {
        return 2;
    }
    rc = attach_eeprom(&o, avr, &fw, ee_start);
    if (rc == 0 && o.flash_path != NULL && flash_load(avr, o.flash_path) != 0) {
        rc = 2;
    }
    if (rc == 0) {
        rc = attach_io(&o, avr, &fw, &uart, &scene);
    }
    if (rc != 0) {
        return rc;
    }
    end = run_board(&o, avr, &fw, &uart, &scene, sectors, ee_start);
    printf("qnav-simavr-board: stopped after %.2f simulated s (%s)\n",
           (double)avr->cycle / (double)fw.frequency,
           end.refused ? "refused" : end.state == cpu_Crashed ? "crashed"
                                   : (g_quit ? "signal" : "done"));
    put_stack_reach(avr, &fw);
    fflush(stdout);
    if (o.eeprom_path != NULL && eeprom_save(avr, o.eeprom_path) != 0) {
        end.state = cpu_Crashed;
    }
    if (o.flash_path != NULL && flash_save(avr, o.flash_path) != 0) {
        end.state = cpu_Crashed;
    }
    /* only the link made here is removed, and only if it is still ours */
    qnav_ptylink_remove(o.link_path, uart.name);
    return end.state == cpu_Crashed || end.refused ? 1 : 0;
}
