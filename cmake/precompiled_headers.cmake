# Precompiled headers: Eigen and the standard library, which every file of ours includes, and
# GoogleTest for the tests. Half of a typical file's compile time is parsing them (g++ 12,
# -fsyntax-only: 2.2 s for Eigen/Dense, 1.4 s for gtest.h). Each header set is compiled once, by
# a host target, and every other target reuses it (REUSE_FROM) rather than compiling its own.
# The targets share the host's code-generation flags (-march, -fopenmp, the sanitizers); where
# one does not (CGAL's -frounding-math in pipeline/init), g++ finds the precompiled header
# unusable and parses the headers as text, so a mismatch costs time, never correctness.
# Off for the fuzz build: clang refuses a precompiled header built with other flags.

set(_mudcrack_pch_headers
  <algorithm> <array> <cmath> <cstdint> <filesystem> <functional> <map> <memory> <optional>
  <string> <unordered_map> <utility> <vector> <Eigen/Dense>)

add_library(mudcrack_pch OBJECT ${PROJECT_SOURCE_DIR}/cmake/pch_host.cpp)
target_link_libraries(mudcrack_pch PRIVATE Eigen3::Eigen OpenMP::OpenMP_CXX mudcrack_warnings)
target_precompile_headers(mudcrack_pch PRIVATE ${_mudcrack_pch_headers})

if(TARGET GTest::gtest)
  add_library(mudcrack_pch_tests OBJECT ${PROJECT_SOURCE_DIR}/cmake/pch_host.cpp)
  target_link_libraries(mudcrack_pch_tests PRIVATE Eigen3::Eigen OpenMP::OpenMP_CXX GTest::gtest mudcrack_warnings
                        mudcrack_test_codegen)
  target_precompile_headers(mudcrack_pch_tests PRIVATE ${_mudcrack_pch_headers} <gtest/gtest.h>)
endif()

# every library and program below `dir`, recursively
function(_mudcrack_targets_below dir out)
  get_property(_targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(_subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(_sub ${_subdirs})
    _mudcrack_targets_below(${_sub} _below)
    list(APPEND _targets ${_below})
  endforeach()
  set(${out} ${_targets} PARENT_SCOPE)
endfunction()

_mudcrack_targets_below(${PROJECT_SOURCE_DIR} _mudcrack_all_targets)
foreach(_t ${_mudcrack_all_targets})
  if(_t MATCHES "^mudcrack_pch")
    continue()
  endif()
  get_target_property(_type ${_t} TYPE)
  if(NOT _type MATCHES "^(STATIC_LIBRARY|EXECUTABLE|OBJECT_LIBRARY)$")
    continue()
  endif()
  # only targets built on Eigen and OpenMP (ours link them through mudcrack::core): a test that
  # only runs our programs has neither, and would parse the set as text without Eigen's path
  get_target_property(_libs ${_t} LINK_LIBRARIES)
  set(_on_core FALSE)
  foreach(_lib ${_libs})
    if(_lib MATCHES "^(mudcrack::|mudcrack_)" AND NOT _lib MATCHES "^mudcrack_(warnings|test_codegen)$"
       OR _lib STREQUAL "Eigen3::Eigen")
      set(_on_core TRUE)
    endif()
  endforeach()
  if(NOT _on_core)
    continue()
  endif()
  if(TARGET mudcrack_pch_tests AND "GTest::gtest" IN_LIST _libs)
    target_precompile_headers(${_t} REUSE_FROM mudcrack_pch_tests)
  else()
    target_precompile_headers(${_t} REUSE_FROM mudcrack_pch)
  endif()
endforeach()
