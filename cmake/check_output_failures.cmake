# Runs one example's writers against the ways an output fails and checks that nothing is lost and
# nothing is claimed (issue 37).
#
#   cmake -DPROGRAM=krs_tree -DEXECUTABLE=<path> -DLIMITER=<run_with_file_limit> -DCASES=<table>
#         -DWORK_DIR=<dir> -DPART=writes|read_only [-DLAUNCHER=xvfb-run;-a] -P check_output_failures.cmake
#
# LAUNCHER, when given, runs every command (krs_view draws under a virtual display, `xvfb-run -a`);
# the file size limit is set inside it, on the program alone, never on the display server.
#
# The table (examples/output_failure_cases.cmake) has one row per writer of a program:
#   krs_output_file(program extension arguments...)    "<file>" in the arguments is the output file
#   krs_output_folder(program written arguments...)    "<dir>" is an --output-dir, `written` a file
#                                                      the program writes in it
# ("<work>" is the row's own directory, for other outputs the row needs). Each row is run once per
# failure; PART=writes runs these:
#   full      a full disk: run_with_file_limit caps every file at 64 bytes (RLIMIT_FSIZE, SIGXFSZ
#             ignored), over an earlier file at the path; the reason must be "File too large"
#   missing   the file's directory does not exist (file rows): refused, the directory not made
#   directory the path is a directory (file rows) or the --output-dir a file (folder rows)
#   extension the name ends in an extension the writer does not write (file rows that have one)
# and PART=read_only this one, in a test of its own because it needs a directory that refuses
# root (tests run as root, where permission bits do not stop a write):
#   read_only the directory, holding an earlier file, is made immutable with `chattr +i` (root:
#             no file can be created or renamed in it, the reason "Operation not permitted"), or,
#             for a user other than root, mode 0555 ("Permission denied"); where neither can be
#             made the test says "cannot make a read-only directory here" and ctest reports it
#             skipped, never passed.
# Every run must: exit non-zero (2 for what can be refused before the work), print on stderr the
# path and the reason, leave the earlier file byte for byte, leave no temporary ("*.partial-*",
# the probe of support/output_path.hpp) and make no directory.

cmake_policy(VERSION 3.20)
include("${CMAKE_CURRENT_LIST_DIR}/run_report.cmake")

foreach(variable PROGRAM EXECUTABLE LIMITER CASES WORK_DIR PART)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "check_output_failures: -D${variable}=... is required")
    endif()
endforeach()

# A directory left immutable by an earlier run that was killed half way would refuse its removal.
if(EXISTS "${WORK_DIR}")
    execute_process(COMMAND chattr -R -i "${WORK_DIR}" OUTPUT_QUIET ERROR_QUIET)
    file(REMOVE_RECURSE "${WORK_DIR}")
endif()
file(MAKE_DIRECTORY "${WORK_DIR}")

set(earlier_text "an earlier file that must survive\n")

# How to make a directory read-only here: sets read_only_reason ("" when it cannot be done).
set(read_only_reason "")
if(PART STREQUAL "read_only")
    set(trial "${WORK_DIR}/trial")
    file(MAKE_DIRECTORY "${trial}")
    execute_process(COMMAND chattr +i "${trial}" RESULT_VARIABLE chattr_result OUTPUT_QUIET ERROR_QUIET)
    execute_process(COMMAND touch "${trial}/x" RESULT_VARIABLE touch_result OUTPUT_QUIET ERROR_QUIET)
    execute_process(COMMAND chattr -i "${trial}" OUTPUT_QUIET ERROR_QUIET)
    if(chattr_result EQUAL 0 AND NOT touch_result EQUAL 0)
        set(read_only_reason "Operation not permitted")
        set(read_only_method chattr)
    else()
        file(CHMOD "${trial}" DIRECTORY_PERMISSIONS OWNER_READ OWNER_EXECUTE)
        execute_process(COMMAND touch "${trial}/y" RESULT_VARIABLE touch_result OUTPUT_QUIET ERROR_QUIET)
        file(CHMOD "${trial}" DIRECTORY_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
        if(NOT touch_result EQUAL 0)
            set(read_only_reason "Permission denied")
            set(read_only_method chmod)
        endif()
    endif()
    file(REMOVE_RECURSE "${trial}")
    if(read_only_reason STREQUAL "")
        message(FATAL_ERROR "check_output_failures: cannot make a read-only directory here (chattr +i failed or did not "
                            "stop root, and mode 0555 does not stop this user)")
    endif()
endif()

function(krs_make_read_only dir on)
    if(read_only_method STREQUAL "chattr")
        if(on)
            execute_process(COMMAND chattr +i "${dir}")
        else()
            execute_process(COMMAND chattr -i "${dir}")
        endif()
    elseif(on)
        file(CHMOD "${dir}" DIRECTORY_PERMISSIONS OWNER_READ OWNER_EXECUTE)
    else()
        file(CHMOD "${dir}" DIRECTORY_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
    endif()
endfunction()

set_property(GLOBAL PROPERTY krs_runs 0)
set_property(GLOBAL PROPERTY krs_failures "")

# Runs `arguments` (placeholders replaced) in the failure `kind` and checks the run.
#   must_say: texts stderr must hold; earlier: the earlier file (or ""); status: "2" or "nonzero"
function(krs_run kind row_dir earlier status must_say limit)
    set(arguments)
    foreach(argument IN LISTS ARGN)
        string(REPLACE "<work>" "${row_dir}" argument "${argument}")
        list(APPEND arguments "${argument}")
    endforeach()
    file(GLOB_RECURSE dirs_before LIST_DIRECTORIES true "${row_dir}/*")
    if(limit)
        set(command ${LAUNCHER} "${LIMITER}" ${limit} "${EXECUTABLE}" ${arguments})
    else()
        set(command ${LAUNCHER} "${EXECUTABLE}" ${arguments})
    endif()
    execute_process(COMMAND ${command} WORKING_DIRECTORY "${row_dir}"
                    RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
    get_property(runs GLOBAL PROPERTY krs_runs)
    math(EXPR runs "${runs} + 1")
    set_property(GLOBAL PROPERTY krs_runs ${runs})
    string(JOIN " " shown ${PROGRAM} ${arguments})

    set(problems)
    if(status STREQUAL "2" AND NOT result STREQUAL "2")
        list(APPEND problems "exit status '${result}', expected 2 (refused before the work)")
    elseif(result STREQUAL "0" OR NOT result MATCHES "^[0-9]+$")
        list(APPEND problems "exit status '${result}', expected a failure")
    endif()
    foreach(text IN LISTS must_say)
        string(FIND "${err}" "${text}" at)
        if(at EQUAL -1)
            list(APPEND problems "stderr does not say \"${text}\"")
        endif()
    endforeach()
    if(earlier)
        file(READ "${earlier}" now)
        if(NOT now STREQUAL earlier_text)
            list(APPEND problems "the earlier file ${earlier} changed")
        endif()
    endif()
    file(GLOB_RECURSE left LIST_DIRECTORIES true "${row_dir}/*")
    foreach(path IN LISTS left)
        if(path MATCHES "\\.partial-|krs-output-probe")
            list(APPEND problems "a temporary was left: ${path}")
        elseif(NOT path IN_LIST dirs_before AND IS_DIRECTORY "${path}")
            list(APPEND problems "a directory was made: ${path}")
        endif()
    endforeach()
    krs_report_run("[${kind}] ${shown}" "${result}" "${problems}" "${out}" "${err}")
endfunction()

set_property(GLOBAL PROPERTY krs_rows 0)
function(krs_next_row out)
    get_property(rows GLOBAL PROPERTY krs_rows)
    math(EXPR rows "${rows} + 1")
    set_property(GLOBAL PROPERTY krs_rows ${rows})
    set(${out} "${WORK_DIR}/row${rows}" PARENT_SCOPE)
endfunction()

# Replaces "<file>" / "<dir>" in ARGN by `value` into the variable `out`.
function(krs_substitute out placeholder value)
    set(result)
    foreach(argument IN LISTS ARGN)
        string(REPLACE "${placeholder}" "${value}" argument "${argument}")
        list(APPEND result "${argument}")
    endforeach()
    set(${out} "${result}" PARENT_SCOPE)
endfunction()

# The two failures that need an earlier file beside the output: its folder made read-only
# (kind read_only) or the disk full (kind full). The folder is the row's "locked" or "full"; the
# earlier file `name` is written in it; `placeholder` in the arguments becomes that file, or the
# folder itself when `is_folder` (an --output-dir). The earlier file must survive either way.
function(krs_run_beside_earlier kind row placeholder name is_folder)
    if(kind STREQUAL "read_only")
        set(folder "${row}/locked")
    else()
        set(folder "${row}/full")
    endif()
    file(MAKE_DIRECTORY "${folder}")
    file(WRITE "${folder}/${name}" "${earlier_text}")
    set(target "${folder}/${name}")
    if(is_folder)
        set(target "${folder}")
    endif()
    krs_substitute(arguments "${placeholder}" "${target}" ${ARGN})
    if(kind STREQUAL "read_only")
        krs_make_read_only("${folder}" ON)
        krs_run(read_only "${row}" "${folder}/${name}" nonzero "${target};${read_only_reason}" "" ${arguments})
        krs_make_read_only("${folder}" OFF)
    else()
        krs_run(full "${row}" "${folder}/${name}" nonzero "${folder}/${name};File too large" 64 ${arguments})
    endif()
endfunction()

function(krs_output_file program extension)
    if(NOT program STREQUAL PROGRAM)
        return()
    endif()
    krs_next_row(row)
    set(name "out${extension}")
    if(extension STREQUAL "")
        set(name "out.data")
    endif()
    if(PART STREQUAL "read_only")
        krs_run_beside_earlier(read_only "${row}" "<file>" "${name}" OFF ${ARGN})
        return()
    endif()
    krs_run_beside_earlier(full "${row}" "<file>" "${name}" OFF ${ARGN})

    krs_substitute(arguments "<file>" "${row}/missing/deeper/${name}" ${ARGN})
    krs_run(missing "${row}" "" 2 "${row}/missing/deeper/${name};does not exist" "" ${arguments})

    file(MAKE_DIRECTORY "${row}/a_directory${extension}")
    krs_substitute(arguments "<file>" "${row}/a_directory${extension}" ${ARGN})
    krs_run(directory "${row}" "" 2 "${row}/a_directory${extension};is a directory" "" ${arguments})

    if(NOT extension STREQUAL "")
        set(wrong ".jpg")
        if(extension STREQUAL ".jpg")
            set(wrong ".png")
        endif()
        krs_substitute(arguments "<file>" "${row}/wrong${wrong}" ${ARGN})
        krs_run(extension "${row}" "" 2 "${row}/wrong${wrong};does not end in;${extension}" "" ${arguments})
        if(EXISTS "${row}/wrong${wrong}")
            set_property(GLOBAL APPEND_STRING PROPERTY krs_failures "\n  [extension] ${program} wrote ${row}/wrong${wrong}")
        endif()
    endif()
endfunction()

function(krs_output_folder program written)
    if(NOT program STREQUAL PROGRAM)
        return()
    endif()
    krs_next_row(row)
    if(PART STREQUAL "read_only")
        krs_run_beside_earlier(read_only "${row}" "<dir>" "${written}" ON ${ARGN})
        return()
    endif()
    krs_run_beside_earlier(full "${row}" "<dir>" "${written}" ON ${ARGN})

    file(WRITE "${row}/a_file" "${earlier_text}")
    krs_substitute(arguments "<dir>" "${row}/a_file" ${ARGN})
    krs_run(directory "${row}" "${row}/a_file" 2 "${row}/a_file;is not a directory" "" ${arguments})
endfunction()

include("${CASES}")

get_property(rows GLOBAL PROPERTY krs_rows)
get_property(runs GLOBAL PROPERTY krs_runs)
get_property(failures GLOBAL PROPERTY krs_failures)
if(rows EQUAL 0)
    message(FATAL_ERROR "check_output_failures: no row for ${PROGRAM} in ${CASES}")
endif()
if(failures)
    message(FATAL_ERROR "check_output_failures: ${PROGRAM} (${PART}) failed runs:${failures}")
endif()
message(STATUS "check_output_failures: ${runs} runs over ${rows} writer(s) of ${PROGRAM} (${PART}) lost nothing and claimed nothing")
