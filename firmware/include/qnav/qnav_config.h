/*
 * Every compile-time knob of libqnav, listed once. Each can be overridden with -D on the
 * compiler line; invalid combinations stop the build with #error. Runtime settings (sector
 * count, maximum range, policy parameters) live in qnav_ctrl_config_t, not here.
 */
#ifndef QNAV_CONFIG_H
#define QNAV_CONFIG_H

/* Number of candidate paths, 1 degree apart. Fixed by the paper's action space. */
#define QNAV_PATHS 360

/* Largest wrapped angular distance between a path and the destination, in degrees. */
#define QNAV_DTHETA_MAX 180

/* Distance levels: each sector range is quantized to 0..QNAV_DIST_LEVELS-1 before a policy
 * sees it, identically in network, probabilistic and table mode. A quality table holds
 * QNAV_DIST_LEVELS * (QNAV_DTHETA_MAX + 1) entries of 2 bytes (32 levels: 11 584 bytes). */
#ifndef QNAV_DIST_LEVELS
#define QNAV_DIST_LEVELS 32
#endif

/* Largest number of hidden units a network policy may have. It sizes qnav_net_t and
 * the step's scratch arrays; the ATmega128 (4 KB RAM) defaults to 16. */
#ifndef QNAV_MAX_HIDDEN
#if defined(__AVR__)
#define QNAV_MAX_HIDDEN 16
#else
#define QNAV_MAX_HIDDEN 32
#endif
#endif

/* Hidden units of a newly made network policy when nothing else is asked for: 12, or
 * QNAV_MAX_HIDDEN when that is smaller (so every QNAV_MAX_HIDDEN in 1..32 builds). */
#ifndef QNAV_DEFAULT_HIDDEN
#if QNAV_MAX_HIDDEN < 12
#define QNAV_DEFAULT_HIDDEN QNAV_MAX_HIDDEN
#else
#define QNAV_DEFAULT_HIDDEN 12
#endif
#endif

/* Largest number of sonar sectors (any N in 1..360 is valid input). */
#define QNAV_MAX_SECTORS 360

/* 1: lookup tables and compiled quality tables are read from program memory (AVR flash);
 * 0: they are ordinary const data. Defaults to 1 on AVR. */
#ifndef QNAV_TABLES_IN_FLASH
#if defined(__AVR__)
#define QNAV_TABLES_IN_FLASH 1
#else
#define QNAV_TABLES_IN_FLASH 0
#endif
#endif

/* 1: a network controller counts its hidden-unit evaluations (one per unit and path it
 * evaluates) into a counter its caller supplies (qnav_ctrl_count_evals): the deterministic
 * cost measure of the adversarial benchmark (bench/README.md, "Adversarial search"), which
 * tracks ATmega128 cycles. It adds a pointer to qnav_ctrl_t and an addition per path
 * evaluated; 0 (default): neither. */
#ifndef QNAV_BENCH_COUNT
#define QNAV_BENCH_COUNT 0
#endif

#if QNAV_DIST_LEVELS < 2 || QNAV_DIST_LEVELS > 256
#error "QNAV_DIST_LEVELS must be in 2..256"
#endif
#if QNAV_MAX_HIDDEN < 1 || QNAV_MAX_HIDDEN > 32
#error "QNAV_MAX_HIDDEN must be in 1..32"
#endif
#if QNAV_DEFAULT_HIDDEN > QNAV_MAX_HIDDEN
#error "QNAV_DEFAULT_HIDDEN must not exceed QNAV_MAX_HIDDEN"
#endif
#if QNAV_BENCH_COUNT != 0 && QNAV_BENCH_COUNT != 1
#error "QNAV_BENCH_COUNT must be 0 or 1"
#endif
#if QNAV_TABLES_IN_FLASH && !defined(__AVR__)
#error "QNAV_TABLES_IN_FLASH is for AVR targets only"
#endif

#endif /* QNAV_CONFIG_H */
