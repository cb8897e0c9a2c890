# install() rules and the exported CMake package (docs/install.md). Host builds only.
#
#   PREFIX/bin/                 simevo, qnav-sim, qnav-policy, navbridge, qnav-sil-robot,
#                               qnav-simavr-board, qnav-spy
#   PREFIX/include/qnav/        the public headers (libqnav, link codec, policy files, sim)
#   PREFIX/lib/                 libqnav_ctrl.a, libqnav_link.a, libqnav_policyio.a, libqnav_sim.a
#   PREFIX/lib/cmake/qnav/      qnavConfig.cmake: find_package(qnav CONFIG) -> qnav::ctrl,
#                               qnav::link, qnav::policyio, qnav::sim
#   PREFIX/lib/pkgconfig/       qnav.pc
#   PREFIX/share/qnav/          data/ (robots, environments), experiments/, sweeps/,
#                               boards/tekbot-avr.elf (with avr-gcc), tools/ (plot
#                               scripts, qnav_log.py), python/qnav/ (generated LCM types),
#                               java/ (LCM types jar), firmware/ (sources for add_subdirectory() in a
#                               firmware project), cmake/ (toolchain files), VERSION
#
# Programs find share/qnav from their own location (qnav/paths.hpp), so the tree can be
# installed anywhere and moved.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(QNAV_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/qnav)
set(QNAV_SHARE_INSTALL_DIR ${CMAKE_INSTALL_DATADIR}/qnav)

set(qnav_libs qnav_ctrl qnav_link qnav_policyio qnav_sim)
if(QNAV_SANITIZE)
  # these static libraries are instrumented: whoever links them needs the runtimes too
  target_link_options(qnav_ctrl INTERFACE $<INSTALL_INTERFACE:-fsanitize=address,undefined>)
endif()
install(TARGETS ${qnav_libs} EXPORT qnavTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/firmware/include/qnav
                  ${PROJECT_SOURCE_DIR}/firmware/link/include/qnav
                  ${PROJECT_SOURCE_DIR}/host/policyio/include/qnav
                  ${PROJECT_SOURCE_DIR}/sim/include/qnav
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT qnavTargets NAMESPACE qnav:: DESTINATION ${QNAV_CMAKE_INSTALL_DIR})

configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/qnavConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/qnavConfig.cmake
  INSTALL_DESTINATION ${QNAV_CMAKE_INSTALL_DIR}
  PATH_VARS QNAV_SHARE_INSTALL_DIR CMAKE_INSTALL_BINDIR)
# Semantic versioning (CHANGELOG.md): before 1.0 a minor release may break the API, so
# find_package(qnav 0.Y) accepts 0.Y.z only; from 1.0 on the major number decides.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(QNAV_VERSION_COMPATIBILITY SameMinorVersion)
else()
  set(QNAV_VERSION_COMPATIBILITY SameMajorVersion)
endif()
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/qnavConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${QNAV_VERSION_COMPATIBILITY})
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/qnavConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/qnavConfigVersion.cmake
        DESTINATION ${QNAV_CMAKE_INSTALL_DIR})

if(QNAV_SANITIZE)
  set(QNAV_PC_SANITIZE "-fsanitize=address,undefined ")
endif()
configure_file(${CMAKE_CURRENT_LIST_DIR}/qnav.pc.in ${CMAKE_CURRENT_BINARY_DIR}/qnav.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/qnav.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

foreach(prog simevo qnav-sim qnav-policy navbridge qnav-sil-robot qnav-simavr-board)
  if(TARGET ${prog})
    install(TARGETS ${prog} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/ DESTINATION ${QNAV_SHARE_INSTALL_DIR}/data)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/experiments/
        DESTINATION ${QNAV_SHARE_INSTALL_DIR}/experiments)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/sweeps/ DESTINATION ${QNAV_SHARE_INSTALL_DIR}/sweeps)
if(TARGET tekbot_avr_elf)
  # the TekBot image for qnav-simavr-board (host builds with avr-gcc make it)
  install(FILES ${QNAV_TEKBOT_AVR_ELF} DESTINATION ${QNAV_SHARE_INSTALL_DIR}/boards)
endif()
install(PROGRAMS ${PROJECT_SOURCE_DIR}/tools/plot_learning.py ${PROJECT_SOURCE_DIR}/tools/plot_policy.py
                 ${PROJECT_SOURCE_DIR}/tools/plot_episodes.py ${PROJECT_SOURCE_DIR}/tools/policy_saturation.py
                 ${PROJECT_SOURCE_DIR}/tools/qnav_log.py
        DESTINATION ${QNAV_SHARE_INSTALL_DIR}/tools)
if(QNAV_LCMTYPES_PYTHON_DIR)
  install(DIRECTORY ${QNAV_LCMTYPES_PYTHON_DIR}/qnav DESTINATION ${QNAV_SHARE_INSTALL_DIR}/python)
endif()
if(QNAV_LCMTYPES_JAR)
  install(FILES ${QNAV_LCMTYPES_JAR} ${QNAV_SPY_CHECK_JAR} DESTINATION ${QNAV_SHARE_INSTALL_DIR}/java)
  install(PROGRAMS ${PROJECT_SOURCE_DIR}/tools/qnav-spy DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(FILES ${PROJECT_SOURCE_DIR}/tools/plotcommon.py ${PROJECT_SOURCE_DIR}/VERSION
        DESTINATION ${QNAV_SHARE_INSTALL_DIR}/tools)
install(FILES ${PROJECT_SOURCE_DIR}/VERSION DESTINATION ${QNAV_SHARE_INSTALL_DIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/firmware/ DESTINATION ${QNAV_SHARE_INSTALL_DIR}/firmware)
install(FILES ${PROJECT_SOURCE_DIR}/cmake/toolchain-avr-atmega128.cmake
              ${PROJECT_SOURCE_DIR}/cmake/toolchain-cortex-m4.cmake
        DESTINATION ${QNAV_SHARE_INSTALL_DIR}/cmake)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/cmake/run-simavr ${PROJECT_SOURCE_DIR}/cmake/run-qemu-cm4
        DESTINATION ${QNAV_SHARE_INSTALL_DIR}/cmake)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/cmake/cortex-m4 DESTINATION ${QNAV_SHARE_INSTALL_DIR}/cmake)
