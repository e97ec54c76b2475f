# The Debian package (issue 14): `scripts/package.sh` -> build/polyexplore_<version>_<arch>.deb.
# What goes where (docs/deployment.md):
#   /usr/bin                        daemons and tools (pex_add_executable; no benchmarks)
#   /lib/systemd/system             systemd/*.service, *.target (ExecStart=/usr/bin/...)
#   /etc/polyexplore                configs, conffiles: config/robot/X.toml where it exists,
#                                   else config/X.toml (sim.toml with an absolute world path);
#                                   lcm.env, capture.env, multicast-route.env
#   /usr/share/polyexplore/worlds   worlds/*.wkt
#   /usr/share/polyexplore/config/sim  the simulator's config set (for polyexplore-sim.target)
#   /usr/share/java/pex_types.jar   LCM types for lcm-spy
#   /usr/bin/pex-spy, pex-logplayer-gui  lcm-spy / lcm-logplayer-gui launchers (tools/spy)
# Included last from the top CMakeLists.txt, after every program is defined.
# Install rules only: no compile flags or targets of others change.

set(PEX_ETC_DIR /etc/polyexplore)
set(PEX_UNIT_DIR /lib/systemd/system)     # Debian 12's place for packaged units
set(PEX_PACKAGE_PREFIX /usr)
set(PEX_SHARE_DIR share/polyexplore)      # under the prefix (/usr)

# --- configs: the robot's values win, whole files (each robot file is complete) ---
set(_pex_pkg_dir ${CMAKE_BINARY_DIR}/packaging)
file(GLOB _pex_configs RELATIVE ${PROJECT_SOURCE_DIR}/config CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/*.toml)
file(GLOB _pex_robot_configs RELATIVE ${PROJECT_SOURCE_DIR}/config/robot CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/robot/*.toml)
# A robot file with no base file would be a typo: say so at configure time.
foreach(f ${_pex_robot_configs})
  if(NOT f IN_LIST _pex_configs)
    message(FATAL_ERROR "config/robot/${f} has no config/${f}")
  endif()
endforeach()
# sim.toml names its world relative to its own folder (../worlds/); installed, the
# worlds are in /usr/share/polyexplore/worlds: the installed copy names it absolutely.
file(READ ${PROJECT_SOURCE_DIR}/config/sim.toml _pex_sim_toml)
string(REGEX REPLACE "world_file = \"\\.\\./worlds/" "world_file = \"${PEX_PACKAGE_PREFIX}/${PEX_SHARE_DIR}/worlds/"
       _pex_sim_toml_installed "${_pex_sim_toml}")
if(_pex_sim_toml_installed STREQUAL _pex_sim_toml)
  message(FATAL_ERROR "config/sim.toml: no world_file = \"../worlds/...\" to point at the installed worlds")
endif()
file(WRITE ${_pex_pkg_dir}/sim.toml "${_pex_sim_toml_installed}")
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/sim.toml)

set(_pex_conffiles)
foreach(f ${_pex_configs})
  if(f IN_LIST _pex_robot_configs)
    set(src ${PROJECT_SOURCE_DIR}/config/robot/${f})
  elseif(f STREQUAL "sim.toml")
    set(src ${_pex_pkg_dir}/sim.toml)
  else()
    set(src ${PROJECT_SOURCE_DIR}/config/${f})
  endif()
  install(FILES ${src} DESTINATION ${PEX_ETC_DIR})
  # the simulator's set, untouched by the robot files, for polyexplore-sim.target
  if(f STREQUAL "sim.toml")
    install(FILES ${_pex_pkg_dir}/sim.toml DESTINATION ${PEX_SHARE_DIR}/config/sim)
  else()
    install(FILES ${PROJECT_SOURCE_DIR}/config/${f} DESTINATION ${PEX_SHARE_DIR}/config/sim)
  endif()
  list(APPEND _pex_conffiles ${PEX_ETC_DIR}/${f})
endforeach()
file(GLOB _pex_env_files CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/systemd/*.env)
install(FILES ${_pex_env_files} DESTINATION ${PEX_ETC_DIR})
foreach(f ${_pex_env_files})
  get_filename_component(n ${f} NAME)
  list(APPEND _pex_conffiles ${PEX_ETC_DIR}/${n})
endforeach()
list(JOIN _pex_conffiles "\n" _pex_conffiles_text)
file(WRITE ${_pex_pkg_dir}/conffiles "${_pex_conffiles_text}\n")

# --- units, helper scripts, worlds, types jar ---
file(GLOB _pex_units CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/systemd/*.service
     ${PROJECT_SOURCE_DIR}/systemd/*.target ${PROJECT_SOURCE_DIR}/systemd/*.timer)
install(FILES ${_pex_units} DESTINATION ${PEX_UNIT_DIR})
file(GLOB _pex_helpers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/systemd/bin/*)
install(PROGRAMS ${_pex_helpers} DESTINATION lib/polyexplore)
file(GLOB _pex_worlds CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/worlds/*.wkt)
install(FILES ${_pex_worlds} DESTINATION ${PEX_SHARE_DIR}/worlds)
if(TARGET pex_lcmtypes_jar)
  install(FILES ${CMAKE_BINARY_DIR}/pex_types.jar DESTINATION share/java)
endif()

# --- what the package needs built: every installed program and the jar ---
get_property(_pex_programs GLOBAL PROPERTY PEX_INSTALLED_PROGRAMS)
add_custom_target(pex-package-inputs)
add_dependencies(pex-package-inputs ${_pex_programs})
if(TARGET pex_lcmtypes_jar)
  add_dependencies(pex-package-inputs pex_lcmtypes_jar)
endif()

# --- CPack: one monolithic .deb ---
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME polyexplore)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX ${PEX_PACKAGE_PREFIX})
set(CPACK_PACKAGE_CONTACT "polyexplore maintainers <polyexplore@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "autonomous 2D exploration daemons on LCM (SLAM, polygonal maps, frontiers)")
set(CPACK_PACKAGE_DESCRIPTION "The polyexplore daemons (laser reader, CANopen base driver, SLAM, polygon mapper,
explorer, simulator), their tools, systemd units (polyexplore.target), the robot's
configuration in /etc/polyexplore and the LCM types jar for lcm-spy.")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)   # polyexplore_<version>_<arch>.deb
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Shared libraries found by dpkg-shlibdeps (liblcm1, libspdlog, libsystemd0, ...), plus
# what the units and maintainer scripts run.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "liblcm-bin, adduser, iproute2, systemd")
# pex-spy, pex-logplayer-gui (lcm-spy, lcm-logplayer-gui): lcm.jar, jchart2d for the message
# view, and a JRE with Swing (not -headless). Recommends, not Depends: the daemons run
# without Java, apt installs Recommends unless told not to, and the launchers name what
# is missing (exit 69).
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "liblcm-java, libjchart2d-java, default-jre | java-runtime")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${_pex_pkg_dir}/conffiles
    ${PROJECT_SOURCE_DIR}/cmake/debian/postinst
    ${PROJECT_SOURCE_DIR}/cmake/debian/prerm
    ${PROJECT_SOURCE_DIR}/cmake/debian/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
# cpack must not build everything first (tests, benchmarks): scripts/package.sh builds
# pex-package-inputs, then runs cpack on what is there.
set(CMAKE_SKIP_INSTALL_ALL_DEPENDENCY ON)
set(CPACK_OUTPUT_FILE_PREFIX ${CMAKE_BINARY_DIR})
include(CPack)
