# The layering rule of ../shared/DESIGN.md, checked by the build rather than
# kept by convention: a library under common/ is an algorithm, with no LCM, no
# clock and no I/O. pex_check_layering() looks at every library target defined
# under common/ and stops the configuration (FATAL_ERROR) when one
#   - links anything but another common/ library or one of
#     PEX_ALGORITHM_ALLOWED_LINKS (so not pex_runtime, pex_hwio, the LCM types,
#     LCM, spdlog, libsystemd, a socket or file library), or
#   - has a source or header that includes one of PEX_ALGORITHM_FORBIDDEN_INCLUDES
#     (LCM, our platform libraries, logging, config files, files, streams to
#     the terminal, sockets, the clock): a header-only use links nothing, so the
#     link check alone would not see it.
# Platform libraries (I/O: the daemon runtime, device transports) live in
# platform/. Tests beside the code (*_test.cpp, *test*.hpp helpers) may do
# I/O: they are not part of the library and are not scanned.
#
# tests/layering/ holds a small project on which the check must fail for each
# kind of violation (ctest -L layering).

set(PEX_ALGORITHM_ALLOWED_LINKS Eigen3::Eigen Boost::headers Threads::Threads PkgConfig::POLYCLIPPING)
# Matched against each #include's target (the text between <> or "").
set(PEX_ALGORITHM_FORBIDDEN_INCLUDES
    "^lcm/" "^pex/" "^runtime/" "^hwio/" "^spdlog/" "^fmt/" "^systemd/" "^toml\\+\\+/" "^CLI/" "^httplib"
    "^fstream$" "^filesystem$" "^iostream$" "^chrono$" "^ctime$"
    "^sys/socket\\.h$" "^sys/time\\.h$" "^netinet/" "^arpa/" "^netdb\\.h$" "^unistd\\.h$" "^fcntl\\.h$"
    "^poll\\.h$" "^sys/epoll\\.h$" "^linux/can/")

# All build-system targets defined in `dir` and its subdirectories.
function(_pex_targets_under dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _pex_targets_under(${sub} sub_targets)
    list(APPEND targets ${sub_targets})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

function(_pex_is_algorithm_library target algorithm_dir out)
  set(result FALSE)
  if(TARGET ${target})
    get_target_property(aliased ${target} ALIASED_TARGET)
    if(aliased)
      set(target ${aliased})
    endif()
    get_target_property(type ${target} TYPE)
    get_target_property(imported ${target} IMPORTED)
    get_target_property(source_dir ${target} SOURCE_DIR)
    string(FIND "${source_dir}/" "${algorithm_dir}/" at)
    if(NOT imported AND type MATCHES "^(STATIC|SHARED|MODULE|OBJECT|INTERFACE)_LIBRARY$" AND at EQUAL 0)
      set(result TRUE)
    endif()
  endif()
  set(${out} ${result} PARENT_SCOPE)
endfunction()

# pex_check_layering([ALGORITHM_DIR dir]): the check, over the targets defined
# so far; call it once every directory is added. ALGORITHM_DIR defaults to
# ${PROJECT_SOURCE_DIR}/common.
function(pex_check_layering)
  cmake_parse_arguments(ARG "" "ALGORITHM_DIR" "" ${ARGN})
  if(NOT ARG_ALGORITHM_DIR)
    set(ARG_ALGORITHM_DIR ${PROJECT_SOURCE_DIR}/common)
  endif()
  _pex_targets_under(${PROJECT_SOURCE_DIR} all_targets)
  set(problems "")
  set(checked 0)
  foreach(target IN LISTS all_targets)
    _pex_is_algorithm_library(${target} ${ARG_ALGORITHM_DIR} is_algorithm)
    if(NOT is_algorithm)
      continue()
    endif()
    math(EXPR checked "${checked} + 1")
    get_target_property(type ${target} TYPE)
    get_target_property(source_dir ${target} SOURCE_DIR)
    file(RELATIVE_PATH where ${PROJECT_SOURCE_DIR} ${source_dir})

    # Links: direct ones (each common/ library is checked itself, so the
    # closure follows), PUBLIC, PRIVATE and INTERFACE alike.
    set(links "")
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(direct ${target} LINK_LIBRARIES)
      if(direct)
        list(APPEND links ${direct})
      endif()
    endif()
    get_target_property(interface ${target} INTERFACE_LINK_LIBRARIES)
    if(interface)
      list(APPEND links ${interface})
    endif()
    foreach(item IN LISTS links)
      if(item MATCHES "^::@")  # directory markers of target_link_libraries from another directory
        continue()
      endif()
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" item "${item}")
      _pex_is_algorithm_library("${item}" ${ARG_ALGORITHM_DIR} linked_algorithm)
      if(linked_algorithm OR item IN_LIST PEX_ALGORITHM_ALLOWED_LINKS)
        continue()
      endif()
      list(APPEND problems "${target} (${where}) links ${item}")
    endforeach()

    # Includes of its sources and of the headers beside them.
    get_target_property(sources ${target} SOURCES)
    if(NOT sources)
      set(sources "")
    endif()
    file(GLOB headers LIST_DIRECTORIES false ${source_dir}/*.hpp ${source_dir}/*.h)
    set(files "")
    foreach(file IN LISTS sources headers)
      if(NOT IS_ABSOLUTE ${file})
        set(file ${source_dir}/${file})
      endif()
      get_filename_component(name ${file} NAME)
      if(name MATCHES "test")
        continue()
      endif()
      list(APPEND files ${file})
    endforeach()
    list(REMOVE_DUPLICATES files)
    foreach(file IN LISTS files)
      file(STRINGS ${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*[<\"]")
      foreach(line IN LISTS includes)
        string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*[<\"]([^>\"]*)[>\"].*$" "\\1" header "${line}")
        foreach(pattern IN LISTS PEX_ALGORITHM_FORBIDDEN_INCLUDES)
          if(header MATCHES "${pattern}")
            file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${file})
            list(APPEND problems "${target}: ${rel} includes <${header}>")
          endif()
        endforeach()
      endforeach()
    endforeach()
  endforeach()

  if(checked EQUAL 0)
    message(FATAL_ERROR "layering: no library found under ${ARG_ALGORITHM_DIR}: nothing was checked")
  endif()
  if(problems)
    list(REMOVE_DUPLICATES problems)
    list(JOIN problems "\n  " text)
    list(JOIN PEX_ALGORITHM_ALLOWED_LINKS ", " allowed)
    message(FATAL_ERROR
      "layering: an algorithm library (under ${ARG_ALGORITHM_DIR}) may link only other algorithm "
      "libraries and ${allowed}, and include no LCM, platform, logging, file, "
      "socket or clock header (cmake/PexLayering.cmake; I/O belongs in platform/ or a daemon):\n  ${text}")
  endif()
  message(STATUS "layering: ${checked} algorithm libraries link and include no I/O")
endfunction()
