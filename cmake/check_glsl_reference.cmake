# What glsl_export --reference writes, and what it leaves when it cannot write.
#
#   cmake -DEXPORT=<glsl_export> -DCHECK=<check_glsl_reference> -DWORK_DIR=<dir> -P check_glsl_reference.cmake
#
# 1. A small reference frame: check_glsl_reference reads the PNG back and holds it, byte for byte
#    and top row first, against the C++ reference it renders again.
# 2. --output and --reference together when one of them cannot be written: status 1, and neither
#    file remains (the command writes both or neither).

foreach(variable EXPORT CHECK WORK_DIR)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "check_glsl_reference: -D${variable}=... is required")
    endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(failures)

function(run expected_status)
    execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
    string(JOIN " " shown ${ARGN})
    if(NOT result STREQUAL expected_status)
        set(failures "${failures}\n  ${shown}\n    exit status '${result}', expected ${expected_status}\n    stdout: ${out}\n    stderr: ${err}" PARENT_SCOPE)
    else()
        message(STATUS "ok (${result}): ${shown}")
    endif()
endfunction()

# 1. Written as rendered.
run(0 "${EXPORT}" --scene sponge --reference "${WORK_DIR}/sponge.png" --width 40 --height 30)
run(0 "${CHECK}" sponge "${WORK_DIR}/sponge.png" 40 30)

# 2. A path under a regular file cannot be created.
file(WRITE "${WORK_DIR}/not_a_folder" "a file, not a folder\n")
run(1 "${EXPORT}" --scene sponge --target shadertoy --output "${WORK_DIR}/not_a_folder/sponge.glsl"
    --reference "${WORK_DIR}/unwritten.png" --width 8 --height 8)
if(EXISTS "${WORK_DIR}/unwritten.png")
    set(failures "${failures}\n  the PNG was written although --output failed")
endif()
run(1 "${EXPORT}" --scene sponge --target shadertoy --output "${WORK_DIR}/unwritten.glsl"
    --reference "${WORK_DIR}/not_a_folder/sponge.png" --width 8 --height 8)
if(EXISTS "${WORK_DIR}/unwritten.glsl")
    set(failures "${failures}\n  the text file remains although --reference failed")
endif()

if(failures)
    message(FATAL_ERROR "check_glsl_reference failed:${failures}")
endif()
message(STATUS "check_glsl_reference: the PNG holds the reference; a failed write leaves neither file")
