# What glsl_export --reference writes, and what it leaves when it cannot write.
#
#   cmake -DEXPORT=<glsl_export> -DCHECK=<check_glsl_reference> -DWORK_DIR=<dir> -P check_glsl_reference.cmake
#
# 1. A small reference frame: check_glsl_reference reads the PNG back and holds it, byte for byte
#    and top row first, against the C++ reference it renders again.
# 2. --output and --reference together when one of them cannot be written: refused before the
#    work (status 2), and neither file is made.
# 3. Both together on a full disk (LIMITER: run_with_file_limit), the text fitting and the PNG
#    not, then neither fitting: status 1, and the earlier files of both names byte-identical (the
#    command writes both or neither).

foreach(variable EXPORT CHECK WORK_DIR LIMITER)
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
run(2 "${EXPORT}" --scene sponge --target shadertoy --output "${WORK_DIR}/not_a_folder/sponge.glsl"
    --reference "${WORK_DIR}/unwritten.png" --width 8 --height 8)
if(EXISTS "${WORK_DIR}/unwritten.png")
    set(failures "${failures}\n  the PNG was written although --output failed")
endif()
run(2 "${EXPORT}" --scene sponge --target shadertoy --output "${WORK_DIR}/unwritten.glsl"
    --reference "${WORK_DIR}/not_a_folder/sponge.png" --width 8 --height 8)
if(EXISTS "${WORK_DIR}/unwritten.glsl")
    set(failures "${failures}\n  the text file remains although --reference failed")
endif()

# 3. The sizes of the two files first (written whole), so that a file size limit can take the
#    text and refuse the PNG; the frame is made large enough that its PNG is the larger file.
set(both --scene sponge --target shadertoy --output "${WORK_DIR}/both.glsl" --reference "${WORK_DIR}/both.png"
    --width 256 --height 192)
run(0 "${EXPORT}" ${both})
file(SIZE "${WORK_DIR}/both.glsl" text_bytes)
file(SIZE "${WORK_DIR}/both.png" png_bytes)
if(NOT png_bytes GREATER text_bytes)
    string(APPEND failures "\n  the PNG (${png_bytes} bytes) is not larger than the text (${text_bytes}): no "
           "limit takes one and refuses the other; make the frame larger")
else()
    math(EXPR text_fits "${text_bytes} + 16")
    foreach(limit ${text_fits} 64)
        file(WRITE "${WORK_DIR}/both.glsl" "the earlier text\n")
        file(WRITE "${WORK_DIR}/both.png" "the earlier picture\n")
        run(1 "${LIMITER}" ${limit} "${EXPORT}" ${both})
        file(READ "${WORK_DIR}/both.glsl" text_now)
        file(READ "${WORK_DIR}/both.png" png_now)
        if(NOT text_now STREQUAL "the earlier text\n" OR NOT png_now STREQUAL "the earlier picture\n")
            string(APPEND failures "\n  a limit of ${limit} bytes changed an earlier file (text: '${text_now}', "
                   "PNG: '${png_now}')")
        endif()
        file(GLOB left "${WORK_DIR}/*.partial-*")
        if(left)
            set(failures "${failures}\n  a limit of ${limit} bytes left temporaries: ${left}")
        endif()
    endforeach()
endif()

if(failures)
    message(FATAL_ERROR "check_glsl_reference failed:${failures}")
endif()
message(STATUS "check_glsl_reference: the PNG holds the reference; a refused or failed write makes or changes neither file")
