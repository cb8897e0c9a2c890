# The ATmega128 board images' linker script: avr-gcc's own for the part, with the board's
# flash page writer (input section .qnav_boot, firmware/boards/tekbot/src/hal_avr.c) placed
# at 0x1FC00, the start of the smallest boot loader section, so it lies in the boot section
# whatever BOOTSZ is: a real ATmega128 executes SPM only from there. It stays inside .text
# (not an output section of its own) because simavr loads only .text and .data, and the
# image tested should be the image flashed. The script is made at configure time from the
# installed toolchain (nothing is downloaded); a toolchain whose script has no "_etext"
# line in .text is refused here rather than building an image without the writer in place.
function(qnav_avr_boot_ldscript out_var avr_gcc mcu)
  execute_process(COMMAND ${avr_gcc} -mmcu=${mcu} -Wl,--verbose -x c /dev/null -o /dev/null
                  OUTPUT_VARIABLE verbose ERROR_QUIET RESULT_VARIABLE rc)
  string(FIND "${verbose}" "==================================================" first)
  string(FIND "${verbose}" "==================================================" last REVERSE)
  if(first LESS 0 OR last LESS_EQUAL first)
    message(FATAL_ERROR "${avr_gcc} -Wl,--verbose printed no linker script for ${mcu}")
  endif()
  math(EXPR start "${first} + 50")
  math(EXPR len "${last} - ${start}")
  string(SUBSTRING "${verbose}" ${start} ${len} script)
  string(FIND "${script}" "_etext = . ;" at)
  if(at LESS 0)
    message(FATAL_ERROR "${avr_gcc}'s linker script for ${mcu} has no '_etext = . ;' line")
  endif()
  string(REPLACE "_etext = . ;"
    ". = ALIGN(2);\n    . = 0x1FC00; /* qnav: the boot loader section (moving back fails the link) */\n    KEEP(*(.qnav_boot))\n    _etext = . ;"
    script "${script}")
  set(path ${CMAKE_BINARY_DIR}/qnav-${mcu}-boot.ld)
  file(WRITE ${path} "${script}")
  set(${out_var} ${path} PARENT_SCOPE)
endfunction()
