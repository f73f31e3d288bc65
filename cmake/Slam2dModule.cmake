# SPDX-License-Identifier: BSD-3-Clause
# One helper declares every slam2d target, so C++20 and warnings are set in one place.

function(slam2d_set_warnings target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
  # GCC 12 reports false -Wrestrict positives inside std::string's operator+ at -O2/-O3
  # (GCC bug 105651); the warning finds nothing real in this code base.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(SLAM2D_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# slam2d_add_module(NAME DEPS <public deps> PRIVATE_DEPS <private deps>)
# Builds the static library slam2d_<NAME> from src/slam2d/<NAME>/**/*.cpp.
function(slam2d_add_module name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/*.cpp)
  if(NOT sources)
    message(FATAL_ERROR "slam2d module '${name}' has no sources")
  endif()
  add_library(slam2d_${name} STATIC ${sources})
  add_library(slam2d::${name} ALIAS slam2d_${name})
  # Installed and exported as slam2d::<NAME> too (src/slam2d/CMakeLists.txt), headers under
  # <prefix>/include/slam2d/<NAME>/.
  # Position-independent, so that the Python module (python/) can link the static libraries.
  set_target_properties(slam2d_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  target_include_directories(slam2d_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                   $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(slam2d_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  slam2d_set_warnings(slam2d_${name})
  set_property(GLOBAL APPEND PROPERTY SLAM2D_MODULES slam2d_${name})
endfunction()

# slam2d_add_test(NAME DEPS <libs>)
# Builds the GoogleTest executable slam2d_test_<NAME> from tests/<NAME>/**/*.cpp.
function(slam2d_add_test name)
  cmake_parse_arguments(ARG "" "" "DEPS" ${ARGN})
  file(GLOB_RECURSE sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/*.cpp)
  if(NOT sources)
    return()
  endif()
  add_executable(slam2d_test_${name} ${sources})
  target_link_libraries(slam2d_test_${name} PRIVATE ${ARG_DEPS} slam2d_test_support GTest::gtest GTest::gmock GTest::gtest_main)
  slam2d_set_warnings(slam2d_test_${name})
  gtest_discover_tests(slam2d_test_${name}
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    PROPERTIES ENVIRONMENT "SLAM2D_BIN=${PROJECT_BINARY_DIR}/bin/slam2d"
    DISCOVERY_TIMEOUT 60)
endfunction()
