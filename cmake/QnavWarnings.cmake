# qnav::warnings: the one warning set of the host code (sim/ and host/), as the firmware
# has its own (firmware/CMakeLists.txt, which stays standalone for add_subdirectory() in a
# firmware project). Link it PRIVATE to every sim/ and host/ target; with QNAV_WERROR (on
# by default, as in CI) a warning stops the build. -Wswitch (in -Wall) is what makes each
# switch over a policy kind name the places a new kind must be handled.
include_guard(GLOBAL)

add_library(qnav_warnings INTERFACE)
add_library(qnav::warnings ALIAS qnav_warnings)
target_compile_options(qnav_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wdouble-promotion
  -Wformat=2
  $<$<COMPILE_LANGUAGE:C>:-Wstrict-prototypes -Wmissing-prototypes>
  $<$<BOOL:${QNAV_WERROR}>:-Werror>)
