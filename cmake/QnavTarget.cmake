# qnav_add_target_program(NAME SOURCES src...): a plain C99 program that runs unchanged on
# the host, on the ATmega128 under simavr and on the Cortex-M4 under qemu (shared test
# vectors, benchmarks). It links libqnav and tests/target/target_io.c (output and exit
# for each platform). On AVR it finds simavr's avr_mcu_section.h (Debian libsimavr-dev).
include_guard(GLOBAL)

if(CMAKE_SYSTEM_PROCESSOR STREQUAL "avr")
  find_path(QNAV_SIMAVR_INCLUDE_DIR avr_mcu_section.h
            PATHS /usr/include/simavr/avr NO_CMAKE_FIND_ROOT_PATH NO_DEFAULT_PATH)
  if(NOT QNAV_SIMAVR_INCLUDE_DIR)
    message(FATAL_ERROR "avr_mcu_section.h not found: install Debian package libsimavr-dev")
  endif()
endif()

function(qnav_add_target_program name)
  cmake_parse_arguments(T "" "" "SOURCES" ${ARGN})
  # The warnings are set here, not beside include_guard: a variable set at the first
  # include lives in that directory's scope only, and every later includer (bench/) got
  # none.
  set(warnings -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion)
  if(QNAV_WERROR)
    list(APPEND warnings -Werror)
  endif()
  # tests/target beside this file, not PROJECT_SOURCE_DIR: a small project of its own
  # (tests/firmware/switches) uses it too
  get_filename_component(io_dir ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../tests/target ABSOLUTE)
  add_executable(${name} ${T_SOURCES} ${io_dir}/target_io.c)
  target_include_directories(${name} PRIVATE ${io_dir})
  target_link_libraries(${name} PRIVATE qnav::ctrl)
  target_compile_options(${name} PRIVATE ${warnings})
  set_target_properties(${name} PROPERTIES C_STANDARD 99 C_EXTENSIONS OFF)
  if(CMAKE_SYSTEM_PROCESSOR STREQUAL "avr")
    # avr_mcu_section.h is not -Wpedantic clean: include it as a system header.
    target_include_directories(${name} SYSTEM PRIVATE ${QNAV_SIMAVR_INCLUDE_DIR})
    target_compile_definitions(${name} PRIVATE QNAV_MCU_NAME="${QNAV_MCU}")
    # Keep simavr's .mmcu tags (console register) through --gc-sections.
    target_link_options(${name} PRIVATE -Wl,--undefined=_mmcu)
  endif()
endfunction()
