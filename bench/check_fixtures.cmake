# CTest bench.fixtures_match_generator: run the fixtures' generator into OUT and compare
# each header with the committed one in bench/fixtures/ (byte for byte).
# Usage: cmake -DGEN=generator -DROOT=source-tree -DOUT=folder -P check_fixtures.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
execute_process(COMMAND ${GEN} ${ROOT} ${OUT} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${GEN} failed (${rc})")
endif()
foreach(f bench_policies.h bench_scans.h bench_tables.h bench_map_trace.h)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/${f} ${ROOT}/bench/fixtures/${f}
                  RESULT_VARIABLE diff)
  if(NOT diff EQUAL 0)
    message(FATAL_ERROR "bench/fixtures/${f} differs from the generator's output ${OUT}/${f}: "
                        "regenerate (bench/fixtures/README.md)")
  endif()
endforeach()
message(STATUS "bench fixtures match their generator")
