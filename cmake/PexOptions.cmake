# One place for the language standard and the warnings every target gets.
function(pex_target_options target)
  get_target_property(_type ${target} TYPE)
  if(_type STREQUAL "INTERFACE_LIBRARY")
    target_compile_features(${target} INTERFACE cxx_std_20)
  else()
    target_compile_features(${target} PUBLIC cxx_std_20)
  endif()
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  if(NOT _type STREQUAL "INTERFACE_LIBRARY")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror=return-type)
  endif()
endfunction()

# pex_add_library(name [SOURCES ...] [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# A static library whose headers are included as "<dir>/<header>": from
# platform/ for a library there (I/O), else from common/ (algorithms; the
# daemons' own libraries include common/'s headers too). Without SOURCES a
# header-only (INTERFACE) library.
function(pex_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  set(include_root ${PROJECT_SOURCE_DIR}/common)
  string(FIND "${CMAKE_CURRENT_SOURCE_DIR}/" "${PROJECT_SOURCE_DIR}/platform/" at)
  if(at EQUAL 0)
    set(include_root ${PROJECT_SOURCE_DIR}/platform)
  endif()
  if(NOT ARG_SOURCES)
    add_library(${name} INTERFACE)
    target_include_directories(${name} INTERFACE ${include_root})
    target_link_libraries(${name} INTERFACE ${ARG_PUBLIC_LIBS})
  else()
    add_library(${name} STATIC ${ARG_SOURCES})
    target_include_directories(${name} PUBLIC ${include_root})
    target_link_libraries(${name} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
  endif()
  pex_target_options(${name})
endfunction()

# pex_add_gtest(name SOURCES ... LIBS ... [LABELS ...] [TIMEOUT s] [NETNS])
# A GoogleTest executable registered test by test with ctest. NETNS: each test
# runs in its own private network namespace (scripts/netns-run), for tests that
# start daemons or touch LCM.
function(pex_add_gtest name)
  cmake_parse_arguments(ARG "NETNS" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_definitions(${name} PRIVATE
    PEX_SOURCE_DIR="${PROJECT_SOURCE_DIR}" PEX_SHARED_DIR="${PEX_SHARED_DIR}"
    PEX_BINARY_DIR="${PROJECT_BINARY_DIR}")
  pex_target_options(${name})
  if(ARG_NETNS)
    # ctest (and test discovery) prefix the command with the "emulator".
    set_target_properties(${name} PROPERTIES CROSSCOMPILING_EMULATOR ${PROJECT_SOURCE_DIR}/scripts/netns-run)
  endif()
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 300)
  endif()
  set(props TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}")
  if(ARG_NETNS)
    # Tests that run daemons in real time get the machine to themselves under
    # `ctest -j`, so a CPU-heavy unit test beside them cannot starve them.
    list(APPEND props PROCESSORS 2)
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES ${props})
endfunction()

# pex_add_executable(name SOURCES ... LIBS ...): a program in build/bin (daemons, tools, benchmarks).
function(pex_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  pex_target_options(${name})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bin)
  if(name MATCHES "^pex-bench-")
    # Benchmarks are for the build tree only: not installed, not packaged.
    install(TARGETS ${name} RUNTIME DESTINATION bin COMPONENT bench EXCLUDE_FROM_ALL)
  else()
    install(TARGETS ${name} RUNTIME DESTINATION bin)
    set_property(GLOBAL APPEND PROPERTY PEX_INSTALLED_PROGRAMS ${name})  # cmake/Packaging.cmake
  endif()
endfunction()
