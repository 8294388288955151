# Runs one example over its rows of a table of command lines and checks how each ends.
#
#   cmake -DPROGRAM=krs_tree -DEXECUTABLE=<path> -DCASES=<table.cmake> -DWORK_DIR=<dir>
#         -P check_command_lines.cmake
#
# The table calls krs_case(program status say arguments...) once per row: `status` is the exit
# status the row must end with and `say` a ;-list of texts the program must print, matched
# literally. A refusal (status 2) must print them on stderr and nothing on stdout: a command line
# is refused before any work starts, so nothing is built or rendered first (the old parser took
# "3x" for 3 and rendered for minutes). A failure found while working (status 1) prints them on
# stderr. Other rows (--help, tiny renders) print them on stdout. Two marks on a text of `say`
# change where it is looked for: "stderr:text" on stderr whatever the status (a success's
# progress and estimates), "!text" nowhere (stdout or stderr: work a refusal must come before).
# "<out>" in an argument stands for WORK_DIR, where rows may write files, "<data>" for DATA_DIR
# (input files the table's rows read). A table needs MIN_ROWS rows of the program (default 5).
# Every row runs; the failures are listed together.

include("${CMAKE_CURRENT_LIST_DIR}/run_report.cmake")

foreach(variable PROGRAM EXECUTABLE CASES WORK_DIR)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "check_command_lines: -D${variable}=... is required")
    endif()
endforeach()
file(MAKE_DIRECTORY "${WORK_DIR}")

set_property(GLOBAL PROPERTY krs_rows 0)
set_property(GLOBAL PROPERTY krs_failures "")

function(krs_case program status say)
    if(NOT program STREQUAL PROGRAM)
        return()
    endif()
    set(arguments)
    foreach(argument IN LISTS ARGN)
        string(REPLACE "<out>" "${WORK_DIR}" argument "${argument}")
        string(REPLACE "<data>" "${DATA_DIR}" argument "${argument}")
        list(APPEND arguments "${argument}")
    endforeach()
    string(JOIN " " shown ${PROGRAM} ${arguments})
    execute_process(COMMAND "${EXECUTABLE}" ${arguments}
                    RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 60)
    get_property(rows GLOBAL PROPERTY krs_rows)
    math(EXPR rows "${rows} + 1")
    set_property(GLOBAL PROPERTY krs_rows ${rows})

    set(problems)
    if(NOT result STREQUAL status)
        list(APPEND problems "exit status '${result}', expected ${status}")
    endif()
    if(status EQUAL 2)
        set(where "${err}")
        set(stream stderr)
        if(NOT out STREQUAL "")
            list(APPEND problems "printed on stdout (work started before the refusal?)")
        endif()
    elseif(status EQUAL 1)
        # A failure found while working (a setting the tree cannot take): its message on stderr.
        set(where "${err}")
        set(stream stderr)
    else()
        set(where "${out}")
        set(stream stdout)
    endif()
    foreach(text IN LISTS say)
        if(text MATCHES "^!(.*)$")
            string(FIND "${out}${err}" "${CMAKE_MATCH_1}" at)
            if(NOT at EQUAL -1)
                list(APPEND problems "says \"${CMAKE_MATCH_1}\", which must not come")
            endif()
            continue()
        endif()
        set(in "${where}")
        set(in_stream ${stream})
        if(text MATCHES "^stderr:(.*)$")
            set(text "${CMAKE_MATCH_1}")
            set(in "${err}")
            set(in_stream stderr)
        endif()
        string(FIND "${in}" "${text}" at)
        if(at EQUAL -1)
            list(APPEND problems "${in_stream} does not say \"${text}\"")
        endif()
    endforeach()
    krs_report_run("${shown}" "${result}" "${problems}" "${out}" "${err}")
endfunction()

include("${CASES}")

get_property(rows GLOBAL PROPERTY krs_rows)
get_property(failures GLOBAL PROPERTY krs_failures)
# A table with no rows for this example would pass without checking anything.
if(NOT DEFINED MIN_ROWS)
    set(MIN_ROWS 5)
endif()
if(rows LESS MIN_ROWS)
    message(FATAL_ERROR "check_command_lines: only ${rows} row(s) for ${PROGRAM} in ${CASES}")
endif()
if(failures)
    message(FATAL_ERROR "check_command_lines: ${PROGRAM} failed rows:${failures}")
endif()
message(STATUS "check_command_lines: ${rows} command lines of ${PROGRAM} end as expected")
