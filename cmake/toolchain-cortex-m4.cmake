# Toolchain file for a Cortex-M4 (arm-none-eabi-gcc, newlib). Soft-float ABI: the firmware
# has no floating point. Executables link for QEMU's mps2-an386 board (cmake/cortex-m4/
# mps2-an386.ld) with semihosting (--specs=rdimon.specs) so that test programs print and
# return an exit status; CTest runs them through cmake/run-qemu-cm4.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

find_program(CMAKE_C_COMPILER arm-none-eabi-gcc REQUIRED)
find_program(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
find_program(CMAKE_AR arm-none-eabi-ar REQUIRED)
find_program(CMAKE_RANLIB arm-none-eabi-ranlib REQUIRED)
find_program(CMAKE_OBJCOPY arm-none-eabi-objcopy)
find_program(CMAKE_SIZE arm-none-eabi-size)
find_program(QNAV_NM arm-none-eabi-nm)

set(QNAV_CM4_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=soft")
set(CMAKE_C_FLAGS_INIT "${QNAV_CM4_FLAGS} -ffunction-sections -fdata-sections")
# Cached here, not as *_INIT: CMake appends its own -O3 (Release) to *_INIT flags.
set(CMAKE_C_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "C flags, Release")
set(CMAKE_C_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "C flags, MinSizeRel")
set(CMAKE_C_FLAGS_DEBUG "-Og -g" CACHE STRING "C flags, Debug")
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "${QNAV_CM4_FLAGS} --specs=rdimon.specs -T ${CMAKE_CURRENT_LIST_DIR}/cortex-m4/mps2-an386.ld -Wl,--gc-sections")

set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CMAKE_CROSSCOMPILING_EMULATOR "${CMAKE_CURRENT_LIST_DIR}/run-qemu-cm4")

set(CMAKE_FIND_ROOT_PATH /usr/lib/arm-none-eabi)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
