# Shared by the example checks run with -P (check_command_lines.cmake, check_output_failures.cmake):
# one run's verdict. `problems` is the list of what the run got wrong; an empty list prints
# "ok (<result>): <label>", a non-empty one adds the label, the problems and both streams to the
# global krs_failures, which the script reports at its end.
function(krs_report_run label result problems out err)
    if(problems)
        string(JOIN "; " joined ${problems})
        set_property(GLOBAL APPEND_STRING PROPERTY krs_failures
                     "\n  ${label}\n    ${joined}\n    stdout: ${out}\n    stderr: ${err}")
    else()
        message(STATUS "ok (${result}): ${label}")
    endif()
endfunction()
