# Configures, builds and runs CTest for one cross target (toolchain file) in a build dir
# of its own, so the host test command also runs the ATmega128 and Cortex-M4 builds, the
# shared vectors under simavr and qemu and the MCU symbol check. Fails on any failure.
#   cmake -DSOURCE=dir -DBINARY=dir -DTOOLCHAIN=file -DGENERATOR=name -P cross_ctest.cmake
cmake_minimum_required(VERSION 3.25)
foreach(v SOURCE BINARY TOOLCHAIN GENERATOR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "cross_ctest.cmake: ${v} must be set")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -G ${GENERATOR}
                        --toolchain ${TOOLCHAIN} -DCMAKE_BUILD_TYPE=Release
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring ${BINARY} with ${TOOLCHAIN} failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} -j2 RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building ${BINARY} failed")
endif()
execute_process(COMMAND ${CMAKE_CTEST_COMMAND} --test-dir ${BINARY} --output-on-failure
                        --no-tests=error
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "tests of the cross build in ${BINARY} failed")
endif()
