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

/*
 * Feature switches: 1 compiles a kind into libqnav, 0 leaves its code out of a firmware
 * that does not use it (flash per configuration: docs/performance.md). The API stays the
 * same: a policy, table or controller of a left-out kind is refused with
 * QNAV_E_KIND_DISABLED (qnav_policy_validate: QNAV_POLICY_E_KIND_DISABLED), and
 * qnav_vfh_* are not in the library. The CMake options of the same names (ON/OFF) leave
 * the sources out and pass these; a build without CMake leaves out the files named here
 * (they stop with #error when compiled with their switch at 0).
 *   QNAV_WITH_NETWORK  the evolved network policy: src/policy_net.c
 *   QNAV_WITH_PROB     the probabilistic policy: src/policy_prob.c
 *   QNAV_WITH_TABLE    table mode, compiled key tables (qnav_ctrl_init_table, _build_table)
 *   QNAV_WITH_VFH      the VFH+ controller: src/vfh.c (the nav table's "vfh" row refuses)
 * src/sigmoid_lut.c (5.3 KB) is needed with QNAV_WITH_NETWORK or QNAV_WITH_TABLE: a table of
 * pre-activation keys turns its chosen key into a quality through the sigmoid.
 * The switches change no struct layout.
 */
#ifndef QNAV_WITH_NETWORK
#define QNAV_WITH_NETWORK 1
#endif
#ifndef QNAV_WITH_PROB
#define QNAV_WITH_PROB 1
#endif
#ifndef QNAV_WITH_TABLE
#define QNAV_WITH_TABLE 1
#endif
#ifndef QNAV_WITH_VFH
#define QNAV_WITH_VFH 1
#endif

#if (QNAV_WITH_NETWORK != 0 && QNAV_WITH_NETWORK != 1) ||                                    \
    (QNAV_WITH_PROB != 0 && QNAV_WITH_PROB != 1) ||                                          \
    (QNAV_WITH_TABLE != 0 && QNAV_WITH_TABLE != 1) || (QNAV_WITH_VFH != 0 && QNAV_WITH_VFH != 1)
#error "QNAV_WITH_NETWORK, QNAV_WITH_PROB, QNAV_WITH_TABLE and QNAV_WITH_VFH must be 0 or 1"
#endif
#if !QNAV_WITH_NETWORK && !QNAV_WITH_PROB && !QNAV_WITH_TABLE && !QNAV_WITH_VFH
#error "every QNAV_WITH_* switch is 0: libqnav would have no controller left"
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
