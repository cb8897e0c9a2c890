# Toolchain file for the ATmega128 (avr-gcc, avr-libc) at 16 MHz. Release builds use -O2:
# measured against -Os on the controller step it is faster in cycles for a few hundred
# bytes of flash (see docs/performance.md, "## libqnav"). Target test binaries run under
# simavr through cmake/run-simavr, which CTest uses as the cross-compiling emulator.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR avr)

set(QNAV_MCU atmega128 CACHE STRING "AVR part (avr-gcc -mmcu)")
set(QNAV_F_CPU 16000000 CACHE STRING "AVR clock, Hz")

find_program(CMAKE_C_COMPILER avr-gcc REQUIRED)
find_program(CMAKE_ASM_COMPILER avr-gcc)
find_program(CMAKE_AR avr-ar REQUIRED)
find_program(CMAKE_RANLIB avr-ranlib REQUIRED)
find_program(CMAKE_OBJCOPY avr-objcopy)
find_program(CMAKE_SIZE avr-size)
find_program(QNAV_NM avr-nm)

set(CMAKE_C_FLAGS_INIT "-mmcu=${QNAV_MCU} -DF_CPU=${QNAV_F_CPU}UL -ffunction-sections -fdata-sections")
# Cached here, not as *_INIT: CMake appends its own -O3 (Release) to *_INIT flags.
set(CMAKE_C_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "C flags, Release")
set(CMAKE_C_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "C flags, MinSizeRel")
set(CMAKE_C_FLAGS_DEBUG "-Og -g" CACHE STRING "C flags, Debug")
# .mmcu (simavr's tags from avr_mcu_section.h) is moved out of the flash image: left
# where binutils puts it, between .text and .data, simavr loads .data at the wrong place.
set(CMAKE_EXE_LINKER_FLAGS_INIT "-mmcu=${QNAV_MCU} -Wl,--gc-sections -Wl,--section-start=.mmcu=0x910000")

# Compiler checks cannot run an AVR program; link a static library instead.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CMAKE_CROSSCOMPILING_EMULATOR "${CMAKE_CURRENT_LIST_DIR}/run-simavr;-m;${QNAV_MCU};-f;${QNAV_F_CPU}")

set(CMAKE_FIND_ROOT_PATH /usr/lib/avr)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
