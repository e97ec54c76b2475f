# pex_lcm_types(target LCM_FILES ...)
# Generates C++ headers with lcm-gen at build time (never committed) into an
# INTERFACE target, and — when a JDK and lcm.jar are present — a jar of Java
# classes so lcm-spy can decode our channels.
#
# The C++ decoders are patched right after lcm-gen writes them
# (PexLcmBoundedDecode.cmake): every array count is checked against the bytes
# left before anything is allocated, so no message can make a daemon allocate
# more than a small multiple of its size (issue 12; docs/channels.md).
set(PEX_LCM_BOUNDED_DECODE ${CMAKE_CURRENT_LIST_DIR}/PexLcmBoundedDecode.cmake)
find_program(LCM_GEN lcm-gen REQUIRED)
find_package(Java COMPONENTS Development QUIET)
find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java)

function(pex_lcm_types target)
  cmake_parse_arguments(ARG "" "PACKAGE" "LCM_FILES" ${ARGN})
  set(cpp_dir ${CMAKE_CURRENT_BINARY_DIR}/cpp)
  set(java_dir ${CMAKE_CURRENT_BINARY_DIR}/java)
  set(headers)
  set(java_sources)
  foreach(f ${ARG_LCM_FILES})
    get_filename_component(base ${f} NAME_WE)
    # file name pex_laser_scan_t.lcm -> type laser_scan_t in package pex
    string(REGEX REPLACE "^${ARG_PACKAGE}_" "" type ${base})
    list(APPEND headers ${cpp_dir}/${ARG_PACKAGE}/${type}.hpp)
    list(APPEND java_sources ${java_dir}/${ARG_PACKAGE}/${type}.java)
  endforeach()
  set(abs_files)
  foreach(f ${ARG_LCM_FILES})
    list(APPEND abs_files ${CMAKE_CURRENT_SOURCE_DIR}/${f})
  endforeach()
  # lcm-gen leaves a header alone when it is newer than its .lcm file: removed
  # first, every header is fresh lcm-gen output when the patch runs on it.
  add_custom_command(OUTPUT ${headers}
    COMMAND ${CMAKE_COMMAND} -E rm -rf ${cpp_dir}/${ARG_PACKAGE}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${cpp_dir}
    COMMAND ${LCM_GEN} --cpp --cpp-hpath ${cpp_dir} ${abs_files}
    COMMAND ${CMAKE_COMMAND} -DDIR=${cpp_dir}/${ARG_PACKAGE} -P ${PEX_LCM_BOUNDED_DECODE}
    DEPENDS ${abs_files} ${PEX_LCM_BOUNDED_DECODE}
    COMMENT "lcm-gen C++ for ${ARG_PACKAGE}, array counts bounded by the bytes left" VERBATIM)
  add_custom_target(${target}_gen DEPENDS ${headers})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_gen)
  # SYSTEM: lcm-gen's code is not ours to warn about (it trips -Wpedantic).
  target_include_directories(${target} SYSTEM INTERFACE ${cpp_dir})
  target_link_libraries(${target} INTERFACE PkgConfig::LCM)

  if(Java_JAVAC_EXECUTABLE AND LCM_JAR)
    set(jar ${CMAKE_BINARY_DIR}/${ARG_PACKAGE}_types.jar)
    add_custom_command(OUTPUT ${jar}
      COMMAND ${CMAKE_COMMAND} -E rm -rf ${java_dir} ${java_dir}_classes
      COMMAND ${CMAKE_COMMAND} -E make_directory ${java_dir} ${java_dir}_classes
      COMMAND ${LCM_GEN} --java --jpath ${java_dir} ${abs_files}
      COMMAND ${Java_JAVAC_EXECUTABLE} -nowarn -source 8 -target 8 -cp ${LCM_JAR} -d ${java_dir}_classes ${java_sources}
      COMMAND ${Java_JAR_EXECUTABLE} cf ${jar} -C ${java_dir}_classes .
      DEPENDS ${abs_files}
      COMMENT "lcm-gen Java + javac -> ${ARG_PACKAGE}_types.jar (for lcm-spy)" VERBATIM)
    add_custom_target(${target}_jar ALL DEPENDS ${jar})
  else()
    message(STATUS "No JDK or lcm.jar: ${ARG_PACKAGE}_types.jar for lcm-spy is not built")
  endif()
endfunction()
