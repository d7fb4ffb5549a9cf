# ctest consumer_find_package: does the installed package work for a downstream project?
#
#   cmake -DBUILD_DIR=<regolith build> -DSOURCE_DIR=<tests/consumer> -DWORK_DIR=<scratch>
#         [-DCONFIG=<build type>] [-DGENERATOR=<cmake generator>] [-DMAKE_PROGRAM=<ninja>]
#         [-DCXX_COMPILER=<c++>] [-DSANITIZE=<list>] -P run_consumer_test.cmake
#
# 1. cmake --install BUILD_DIR into WORK_DIR/prefix (wiped first),
# 2. configures and builds SOURCE_DIR against it with CMAKE_PREFIX_PATH=WORK_DIR/prefix and
#    checks that find_package(Regolith) found that prefix and nothing else,
# 3. runs the program, which exits non-zero if a query result is wrong.
# SANITIZE repeats the build's -fsanitize list for the consumer: a sanitized static
# library needs the sanitizer runtime at the final link.
cmake_minimum_required(VERSION 3.25)

foreach(var BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "run_consumer_test.cmake: ${var} is not set")
  endif()
endforeach()

set(prefix "${WORK_DIR}/prefix")
set(consumer_build "${WORK_DIR}/build")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# run(<step> <command...>): runs a command, prints its output, stops the test if it fails.
function(run step)
  execute_process(COMMAND ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message("---- ${step}\n${out}")
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "consumer test: ${step} failed (exit ${rc}):\n  ${cmd}")
  endif()
endfunction()

set(config_args "")
if(CONFIG)
  set(config_args --config "${CONFIG}")
endif()

# 1. Install the build under test.
run("install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}" ${config_args})

# The package is relocatable: no installed CMake file names a library by absolute path.
file(GLOB package_files "${prefix}/lib*/cmake/Regolith/*.cmake")
if(NOT package_files)
  message(FATAL_ERROR "consumer test: no CMake package files under ${prefix}/lib*/cmake/Regolith")
endif()
foreach(f ${package_files})
  file(STRINGS "${f}" absolute REGEX "[\"; ]/[^\"; ]*\\.(so|a)([\"; ]|$)")
  if(absolute)
    message(FATAL_ERROR "consumer test: ${f} names a library by absolute path, expected a "
                        "relocatable package:\n${absolute}")
  endif()
endforeach()

# 2. Configure and build the consumer against the prefix only.
set(configure_args
  -S "${SOURCE_DIR}" -B "${consumer_build}"
  "-DCMAKE_PREFIX_PATH=${prefix}"
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
  -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)
if(GENERATOR)
  list(APPEND configure_args -G "${GENERATOR}")
endif()
if(MAKE_PROGRAM)
  list(APPEND configure_args "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
endif()
if(CXX_COMPILER)
  list(APPEND configure_args "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
endif()
if(CONFIG)
  list(APPEND configure_args "-DCMAKE_BUILD_TYPE=${CONFIG}")
endif()
if(SANITIZE)
  list(APPEND configure_args
    "-DCMAKE_CXX_FLAGS=-fsanitize=${SANITIZE} -fno-omit-frame-pointer"
    "-DCMAKE_EXE_LINKER_FLAGS=-fsanitize=${SANITIZE}")
endif()
run("configure consumer" "${CMAKE_COMMAND}" ${configure_args})

# find_package must have used the fresh install, not a system copy or the build tree.
file(STRINGS "${consumer_build}/CMakeCache.txt" regolith_dir REGEX "^Regolith_DIR:")
string(REGEX REPLACE "^Regolith_DIR:[A-Z]+=" "" regolith_dir "${regolith_dir}")
file(REAL_PATH "${prefix}" real_prefix)
if(regolith_dir STREQUAL "" OR NOT EXISTS "${regolith_dir}")
  message(FATAL_ERROR "consumer test: Regolith_DIR is '${regolith_dir}', expected a folder in ${prefix}")
endif()
file(REAL_PATH "${regolith_dir}" real_regolith_dir)
string(FIND "${real_regolith_dir}/" "${real_prefix}/" pos)
if(NOT pos EQUAL 0)
  message(FATAL_ERROR "consumer test: found Regolith in ${regolith_dir}, expected it under ${prefix}")
endif()

run("build consumer" "${CMAKE_COMMAND}" --build "${consumer_build}" ${config_args})

# 3. Run it.
set(exe "${consumer_build}/regolith_consumer")
if(NOT EXISTS "${exe}" AND CONFIG)
  set(exe "${consumer_build}/${CONFIG}/regolith_consumer")
endif()
run("run consumer" "${exe}")
