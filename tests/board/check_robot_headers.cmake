# CTest board.robot_headers_match_profiles: write each robot's board configuration header
# with qnav-sim robot-header into OUT and compare it byte for byte with the committed one in
# firmware/boards/robots/include/qnav/ (the cross builds compile the committed headers).
# Usage: cmake -DQNAV_SIM=qnav-sim -DROOT=source-tree -DOUT=folder -P check_robot_headers.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
foreach(robot tekbot pioneer3dx)
  execute_process(COMMAND ${QNAV_SIM} robot-header --robot ${robot} ${OUT}/robot_${robot}.h
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "qnav-sim robot-header --robot ${robot} failed (${rc})")
  endif()
  set(committed ${ROOT}/firmware/boards/robots/include/qnav/robot_${robot}.h)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}/robot_${robot}.h ${committed}
                  RESULT_VARIABLE diff)
  if(NOT diff EQUAL 0)
    message(FATAL_ERROR "${committed} differs from data/robots/${robot}.toml: regenerate it with "
                        "qnav-sim robot-header --robot ${robot} "
                        "firmware/boards/robots/include/qnav/robot_${robot}.h")
  endif()
endforeach()
message(STATUS "robot headers match their profiles")
