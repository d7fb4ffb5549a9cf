# Shared build settings for every Regolith target.
#
# Warnings live in the INTERFACE target regolith_warnings, linked PRIVATE, so consumers of
# the installed package never inherit them. Sanitizer flags come from REGOLITH_SANITIZE.

add_library(regolith_warnings INTERFACE)
target_compile_options(regolith_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow
  -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual
  $<$<BOOL:${REGOLITH_WERROR}>:-Werror>)

add_library(regolith_sanitizers INTERFACE)
# Fuzzing (tests/fuzz, docs/reliability.md): every library is built with libFuzzer's coverage
# instrumentation (fuzzer-no-link) beside ASan and UBSan; the fuzz targets link libFuzzer.
if(REGOLITH_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang" OR NOT CMAKE_C_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "REGOLITH_FUZZ needs clang (CC=clang CXX=clang++), not "
                        "${CMAKE_CXX_COMPILER_ID}: libFuzzer is clang's")
  endif()
  if(NOT REGOLITH_SANITIZE)
    set(REGOLITH_SANITIZE address,undefined)
  endif()
  target_compile_options(regolith_sanitizers INTERFACE -fsanitize=fuzzer-no-link)
endif()
if(REGOLITH_SANITIZE)
  target_compile_options(regolith_sanitizers INTERFACE
    -fsanitize=${REGOLITH_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(regolith_sanitizers INTERFACE -fsanitize=${REGOLITH_SANITIZE})
endif()

# Build-only helpers; exported so the install's link interface stays complete, but they
# carry no usage requirements once installed (BUILD_INTERFACE below).
function(regolith_apply_settings target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:regolith_warnings>
                                          $<BUILD_INTERFACE:regolith_sanitizers>)
endfunction()

# regolith_add_library(<module> SOURCES ... [DEPS ...] [PRIVATE_DEPS ...])
# Creates target regolith_<module> with alias regolith::<module>, headers under
# <module>/include/regolith/<module>/, and the install/export rules.
function(regolith_add_library module)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  set(target regolith_${module})
  add_library(${target} ${ARG_SOURCES})
  add_library(regolith::${module} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${module}
                                             POSITION_INDEPENDENT_CODE ON)
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  regolith_apply_settings(${target})
  # No implicit GLM conversions inside the libraries (a vec3 from a scalar, a dvec3 from a
  # vec3): every one is spelled out. Private, so consumers keep GLM's defaults.
  target_compile_definitions(${target} PRIVATE GLM_FORCE_EXPLICIT_CTOR)
  # A file whose file-local names clash with another's in one batch (a unity build shares
  # one anonymous namespace) says so in its module's CMakeLists.txt with
  # SKIP_UNITY_BUILD_INCLUSION.
  if(REGOLITH_UNITY_LIBRARIES)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 16)
  endif()
  if(REGOLITH_FORCE_ASSERTS)
    target_compile_definitions(${target} PUBLIC REGOLITH_FORCE_ASSERTS)
  endif()
  install(TARGETS ${target} EXPORT RegolithTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# regolith_add_executable(<name> SOURCES ... DEPS ...)
function(regolith_add_executable name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  regolith_apply_settings(${name})
endfunction()

# regolith_find_python(<var> IMPORTS <python code> OVERRIDE <cache variable> WHAT <who needs it>
#                      INSTALL <Debian packages>)
# The one way the build picks a Python interpreter: the interpreter named by the cache
# variable OVERRIDE if it is set, else Debian's /usr/bin/python3, else the python3 on PATH
# (which may be a separate interpreter without numpy, such as a pyenv shim: it is tried last).
# The first candidate that runs IMPORTS wins; configuring fails loudly, naming the candidates,
# the packages and the override, if none does.
function(regolith_find_python var)
  cmake_parse_arguments(ARG "" "IMPORTS;OVERRIDE;WHAT;INSTALL" "" ${ARGN})
  if(${ARG_OVERRIDE})
    set(candidates ${${ARG_OVERRIDE}})
  else()
    set(candidates /usr/bin/python3)
    find_program(REGOLITH_PATH_PYTHON3 NAMES python3)
    if(REGOLITH_PATH_PYTHON3)
      list(APPEND candidates ${REGOLITH_PATH_PYTHON3})
    endif()
    list(REMOVE_DUPLICATES candidates)
  endif()
  foreach(candidate IN LISTS candidates)
    if(EXISTS ${candidate})
      execute_process(COMMAND ${candidate} -c "${ARG_IMPORTS}"
                      RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
      if(rc EQUAL 0)
        set(${var} ${candidate} PARENT_SCOPE)
        return()
      endif()
    endif()
  endforeach()
  message(FATAL_ERROR
    "No Python interpreter runs '${ARG_IMPORTS}' (tried: ${candidates}), which ${ARG_WHAT} "
    "needs. On Debian: apt-get install ${ARG_INSTALL}; or set -D${ARG_OVERRIDE}=/path/to/python3.")
endfunction()
