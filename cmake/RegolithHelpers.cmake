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
