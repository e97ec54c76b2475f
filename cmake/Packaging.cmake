# The Debian package (issue 14): `scripts/package.sh` -> build/polyexplore_<version>_<arch>.deb.
# What goes where (docs/deployment.md):
#   /usr/bin                        daemons and tools (pex_add_executable; no benchmarks)
#   /lib/systemd/system             systemd/*.service, *.target (ExecStart=/usr/bin/...)
#   /usr/share/polyexplore/config   config/*.toml: the defaults layer of every daemon
#   /etc/polyexplore                conffiles: each daemon's robot overlay (config/robot/X.toml,
#                                   else one setting nothing), lcm.env, capture.env
#   /usr/share/polyexplore/worlds   worlds/*.wkt
#   /usr/share/polyexplore/config/sim  overlays setting nothing (for polyexplore-sim.target)
#   /usr/share/java/pex_types.jar   LCM types for lcm-spy
#   /usr/bin/pex-spy, pex-logplayer-gui  lcm-spy / lcm-logplayer-gui launchers (tools/spy)
# Included last from the top CMakeLists.txt, after every program is defined.
# Install rules only: no compile flags or targets of others change.

set(PEX_ETC_DIR /etc/polyexplore)
set(PEX_UNIT_DIR /lib/systemd/system)     # Debian 12's place for packaged units
set(PEX_PACKAGE_PREFIX /usr)
set(PEX_SHARE_DIR share/polyexplore)      # under the prefix (/usr)

# --- configs, two layers (docs/deployment.md, "Configuration") ---
# Each unit runs its daemon with `--config /usr/share/polyexplore/config/X.toml --config
# /etc/polyexplore/X.toml`: each key from the last file that sets it.
#   /usr/share/polyexplore/config/X.toml  config/X.toml as it is: the defaults (the
#       simulator's set; sim.toml's "../worlds/" is relative to its own folder, so it
#       names /usr/share/polyexplore/worlds). Not conffiles: an upgrade replaces them.
#   /etc/polyexplore/X.toml  the robot's overlay, a conffile: config/robot/X.toml, only
#       the keys the robot changes; for a daemon with none, an overlay setting nothing
#       (the place for local changes).
#   /usr/share/polyexplore/config/sim/X.toml  overlays setting nothing: copied over
#       /etc/polyexplore, the daemons run the simulator's set (polyexplore-sim.target).
set(_pex_pkg_dir ${CMAKE_BINARY_DIR}/packaging)
file(GLOB _pex_configs RELATIVE ${PROJECT_SOURCE_DIR}/config CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/*.toml)
file(GLOB _pex_robot_configs RELATIVE ${PROJECT_SOURCE_DIR}/config/robot CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/robot/*.toml)
# A robot overlay with no base file would be a typo: say so at configure time.
foreach(f ${_pex_robot_configs})
  if(NOT f IN_LIST _pex_configs)
    message(FATAL_ERROR "config/robot/${f} has no config/${f}")
  endif()
endforeach()

set(_pex_conffiles)
foreach(f ${_pex_configs})
  install(FILES ${PROJECT_SOURCE_DIR}/config/${f} DESTINATION ${PEX_SHARE_DIR}/config)
  set(base ${PEX_PACKAGE_PREFIX}/${PEX_SHARE_DIR}/config/${f})
  if(f IN_LIST _pex_robot_configs)
    install(FILES ${PROJECT_SOURCE_DIR}/config/robot/${f} DESTINATION ${PEX_ETC_DIR})
  else()
    file(WRITE ${_pex_pkg_dir}/robot/${f}
      "# ${PEX_ETC_DIR}/${f}: the robot's changes over ${base}\n"
      "# (read after it: each key set here wins; docs/deployment.md). The robot changes nothing\n"
      "# here; a key copied from that file and changed here overrides it.\n")
    install(FILES ${_pex_pkg_dir}/robot/${f} DESTINATION ${PEX_ETC_DIR})
  endif()
  list(APPEND _pex_conffiles ${PEX_ETC_DIR}/${f})
  file(WRITE ${_pex_pkg_dir}/sim/${f}
    "# ${PEX_ETC_DIR}/${f} for the simulator (polyexplore-sim.target): nothing over\n"
    "# ${base}, which is the simulator's set. Copied from\n"
    "# ${PEX_PACKAGE_PREFIX}/${PEX_SHARE_DIR}/config/sim/ (docs/deployment.md).\n")
  install(FILES ${_pex_pkg_dir}/sim/${f} DESTINATION ${PEX_SHARE_DIR}/config/sim)
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
