# Runs an example with its output captured (a pipe, as in a log) and checks the progress it
# reports there: lines that end, with no '\r' redraws (a terminal's bar left ~100 KB of frames in
# scripts/examples.sh's log), and at most one line per tenth of each bar.
#
#   cmake -DEXECUTABLE=<path> "-DARGUMENTS=--width;64;..." -DLABEL=render -P check_progress_log.cmake
#
# LABEL is the progress label that must reach 100% (a run that reports nothing checks nothing).

foreach(variable EXECUTABLE ARGUMENTS LABEL)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "check_progress_log: -D${variable}=... is required")
    endif()
endforeach()
execute_process(COMMAND "${EXECUTABLE}" ${ARGUMENTS}
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 240)
set(both "${out}${err}")
if(NOT result EQUAL 0)
    message(FATAL_ERROR "check_progress_log: exit status ${result}\nstdout: ${out}\nstderr: ${err}")
endif()
string(FIND "${both}" "\r" carriage_return)
if(NOT carriage_return EQUAL -1)
    string(REPLACE "\r" "<CR>" shown "${both}")
    message(FATAL_ERROR "check_progress_log: a carriage return in captured output:\n${shown}")
endif()
string(FIND "${both}" "${LABEL}: 100%\n" finished)
if(finished EQUAL -1)
    message(FATAL_ERROR "check_progress_log: no line '${LABEL}: 100%' in:\n${both}")
endif()
# One line per tenth: a percent that is not a multiple of ten means per-percent frames.
string(REGEX MATCHALL "${LABEL}: [0-9]+%" lines "${both}")
foreach(line IN LISTS lines)
    if(NOT line MATCHES ": (0|[1-9]0|100)%$")
        message(FATAL_ERROR "check_progress_log: '${line}' is not a tenth:\n${both}")
    endif()
endforeach()
list(LENGTH lines count)
# Within one bar (up to its 100%) each tenth at most once, rising: a bar redrawn as lines.
set(last -1)
foreach(line IN LISTS lines)
    string(REGEX REPLACE "^.*: ([0-9]+)%$" "\\1" percent "${line}")
    if(NOT percent GREATER last)
        message(FATAL_ERROR "check_progress_log: '${line}' after ${last}% in one bar:\n${both}")
    endif()
    set(last ${percent})
    if(percent EQUAL 100)
        set(last -1)
    endif()
endforeach()
message(STATUS "check_progress_log: ${count} progress line(s), no carriage return")
