# cmake -P script behind the package_consumer and subdirectory_consumer tests.
#   KRS_MODE=package       install KRS_BUILD_DIR into KRS_BUILD_DIR/consumer-prefix, then configure
#                          the consumer with find_package(krs) against that prefix only
#   KRS_MODE=subdirectory  configure the consumer with -DKRS_SOURCE_DIR (add_subdirectory)
# Then build and run the consumer; any failing step fails the test.
cmake_minimum_required(VERSION 3.20)

foreach(var KRS_MODE KRS_BUILD_DIR KRS_CONSUMER_SOURCE_DIR KRS_GENERATOR KRS_CXX_COMPILER)
    if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
        message(FATAL_ERROR "run_consumer.cmake: ${var} is not set")
    endif()
endforeach()
if(NOT KRS_CONFIG)
    set(KRS_CONFIG Release)
endif()

function(run_step what)
    message(STATUS "[${KRS_MODE}] ${what}: ${ARGN}")
    execute_process(COMMAND ${ARGN} RESULT_VARIABLE result)
    if(NOT result EQUAL 0)
        message(FATAL_ERROR "[${KRS_MODE}] ${what} failed (${result})")
    endif()
endfunction()

set(work "${KRS_BUILD_DIR}/consumer-${KRS_MODE}")
file(REMOVE_RECURSE "${work}")
set(configure_args
    -S "${KRS_CONSUMER_SOURCE_DIR}" -B "${work}" -G "${KRS_GENERATOR}"
    -DCMAKE_CXX_COMPILER=${KRS_CXX_COMPILER} -DCMAKE_BUILD_TYPE=${KRS_CONFIG})
if(KRS_CONSUMER_OPENVDB)
    list(APPEND configure_args -DKRS_CONSUMER_OPENVDB=ON)
endif()

if(KRS_MODE STREQUAL "package")
    set(prefix "${KRS_BUILD_DIR}/consumer-prefix")
    file(REMOVE_RECURSE "${prefix}")
    run_step("install" "${CMAKE_COMMAND}" --install "${KRS_BUILD_DIR}" --prefix "${prefix}"
             --config "${KRS_CONFIG}")
    # The package registry and the source tree must not satisfy find_package by accident.
    list(APPEND configure_args "-DCMAKE_PREFIX_PATH=${prefix}"
         -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON)
elseif(KRS_MODE STREQUAL "subdirectory")
    if(NOT KRS_SOURCE_DIR)
        message(FATAL_ERROR "run_consumer.cmake: subdirectory mode needs KRS_SOURCE_DIR")
    endif()
    list(APPEND configure_args "-DKRS_SOURCE_DIR=${KRS_SOURCE_DIR}")
else()
    message(FATAL_ERROR "run_consumer.cmake: unknown KRS_MODE '${KRS_MODE}'")
endif()

run_step("configure" "${CMAKE_COMMAND}" ${configure_args})
run_step("build" "${CMAKE_COMMAND}" --build "${work}" --config "${KRS_CONFIG}")
if(EXISTS "${work}/${KRS_CONFIG}/krs_consumer")
    set(exe "${work}/${KRS_CONFIG}/krs_consumer")
else()
    set(exe "${work}/krs_consumer")
endif()
run_step("run" "${exe}")
