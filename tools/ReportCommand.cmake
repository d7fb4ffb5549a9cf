# `regolith report` (ReportCommand.cpp, docs/accuracy-vs-time.md): the paths it needs, fixed
# at build time. The benchmark programs are the targets of bench/ (REGOLITH_BUILD_BENCH=ON);
# the plots come from scripts/report.py run by a Python with numpy and matplotlib:
# REGOLITH_REPORT_PYTHON if set, else Debian's /usr/bin/python3, else the python3 on PATH.
# Without one the command still builds and says what to install when it is run.
set(REGOLITH_REPORT_PYTHON "" CACHE FILEPATH
    "Python with numpy and matplotlib for `regolith report` (default: /usr/bin/python3)")
set(_report_python "")
find_program(REGOLITH_PATH_PYTHON3 NAMES python3)
foreach(candidate IN ITEMS ${REGOLITH_REPORT_PYTHON} /usr/bin/python3 ${REGOLITH_PATH_PYTHON3})
  if(NOT _report_python AND EXISTS ${candidate})
    execute_process(COMMAND ${candidate} -c "import numpy, matplotlib"
                    RESULT_VARIABLE _rc OUTPUT_QUIET ERROR_QUIET)
    if(_rc EQUAL 0)
      set(_report_python ${candidate})
    endif()
  endif()
endforeach()
if(NOT _report_python)
  message(STATUS "regolith report: no Python with numpy and matplotlib (apt-get install "
                 "python3-matplotlib); the command will say so when run")
endif()
set(_report_bench_dir "")
if(REGOLITH_BUILD_BENCH)
  set(_report_bench_dir "$<TARGET_FILE_DIR:precision_bench>")
endif()
# On this file only: the command's other sources (and their precompiled header) keep their flags.
set_property(SOURCE ReportCommand.cpp APPEND PROPERTY COMPILE_DEFINITIONS
  "REGOLITH_BENCH_DIR=\"${_report_bench_dir}\""
  "REGOLITH_REPORT_SCRIPT=\"${PROJECT_SOURCE_DIR}/scripts/report.py\""
  "REGOLITH_REPORT_PYTHON=\"${_report_python}\"")

if(REGOLITH_BUILD_TESTS AND REGOLITH_BUILD_BENCH AND _report_python)
  # The quick report end to end (scripts/check-report.py): runs `regolith report` into a
  # fresh folder, then checks that every plot index.html shows is a valid PNG and that every
  # number on the page is the number at its JSON pointer in this run's run.json; then the
  # same for `regolith report --from` of that run.json (re-plotting runs nothing). Needs the
  # bench programs built (ninja accuracy_table topo_bench store_bench cache_policies
  # precision_bench clod_bench farfield_bench effects_bench).
  add_test(NAME regolith_report_quick
           COMMAND ${_report_python} ${PROJECT_SOURCE_DIR}/scripts/check-report.py
                   --regolith $<TARGET_FILE:regolith>
                   --out ${CMAKE_CURRENT_BINARY_DIR}/report-quick-test
                   --replot ${CMAKE_CURRENT_BINARY_DIR}/report-quick-test-replot)
  set_tests_properties(regolith_report_quick PROPERTIES COST 60 TIMEOUT 400
    ENVIRONMENT "ASAN_OPTIONS=halt_on_error=1:detect_leaks=0")
endif()
