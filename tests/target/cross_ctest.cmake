# Configures, builds and runs CTest for a build dir of its own, so the host test command
# also runs the ATmega128 and Cortex-M4 builds (the shared vectors under simavr and qemu,
# the MCU symbol check) and libqnav's feature-switch configurations
# (tests/firmware/switches). Fails on any failure. TOOLCHAIN is optional (none: the host);
# OPTIONS are cache settings separated by commas (QNAV_WITH_VFH=OFF,...).
#   cmake -DSOURCE=dir -DBINARY=dir [-DTOOLCHAIN=file] [-DOPTIONS=a=b,...] -DGENERATOR=name
#         -P cross_ctest.cmake
cmake_minimum_required(VERSION 3.25)
foreach(v SOURCE BINARY GENERATOR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "cross_ctest.cmake: ${v} must be set")
  endif()
endforeach()
set(configure -S ${SOURCE} -B ${BINARY} -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release)
if(TOOLCHAIN)
  list(APPEND configure --toolchain ${TOOLCHAIN})
endif()
string(REPLACE "," ";" options "${OPTIONS}")
foreach(o IN LISTS options)
  list(APPEND configure -D${o})
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} ${configure} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring ${BINARY} (${TOOLCHAIN} ${OPTIONS}) failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} -j2 RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building ${BINARY} failed")
endif()
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${BINARY} --output-on-failure
                        --no-tests=error
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "tests of the build in ${BINARY} failed")
endif()
