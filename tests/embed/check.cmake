# The test embed.find_package: installs this build into WORK/prefix, builds tests/embed (a
# separate CMake project that finds hemo with find_package) against it, runs the example on
# SCENE with the validation layer on, and checks what it prints.
#   cmake -DBUILD_DIR=... -DWORK=... -DSOURCE_DIR=... -DSCENE=... -DGENERATOR=... -DCXX=...
#         -DCXX_FLAGS=... -DLINKER_FLAGS=... -DBUILD_TYPE=... -P check.cmake
function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}${err}")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK}")
run("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK}/prefix")
run("configure" ${CMAKE_COMMAND} -S "${SOURCE_DIR}" -B "${WORK}/build" -G "${GENERATOR}"
    "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}" "-DCMAKE_PREFIX_PATH=${WORK}/prefix" "-DCMAKE_CXX_COMPILER=${CXX}"
    "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}" "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
run("build" ${CMAKE_COMMAND} --build "${WORK}/build")
# The example's run is checked as the programs' CLI tests are (exit code, output, no
# validation messages).
set(ENV{HEMO_VALIDATION} 1)
set(CMD "${WORK}/build/embed_example" "${SCENE}" 20)
set(CODE 0)
set(REGEX "scene tiny_tank: 120 fluid, [0-9]+ boundary, 0 wall particles.*after 10 steps, t = [0-9.]+ s: lowest fluid z [-0-9.]+ m.*after 20 steps.*surface: [1-9][0-9]* triangles")
include("${CMAKE_CURRENT_LIST_DIR}/../cli/expect_exit.cmake")
