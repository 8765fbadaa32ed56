# hemo-run --vtk-format legacy: ASCII legacy VTK frames (particles_<step>.vtk), no XML files
# and no .pvd.
#   cmake -DRUN=hemo-run -DSCENE=scene.json -DDIR=out -P check_vtk_legacy.cmake
file(REMOVE_RECURSE "${DIR}")
execute_process(COMMAND "${RUN}" "${SCENE}" --steps 10 --vtk-every 5 --vtk-format legacy --out "${DIR}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0" OR NOT "${out}" MATCHES "\"vtk_files\": 3")
  message(FATAL_ERROR "exit code ${rc}\n${out}${err}")
endif()
file(GLOB written RELATIVE "${DIR}" "${DIR}/*.vt*" "${DIR}/*.pvd")
list(SORT written)
if(NOT written STREQUAL "particles_00000000.vtk;particles_00000005.vtk;particles_00000010.vtk")
  message(FATAL_ERROR "wrote ${written}")
endif()
file(STRINGS "${DIR}/particles_00000010.vtk" head LIMIT_COUNT 4)
if(NOT head MATCHES "# vtk DataFile Version 3.0;hemo particles, t = [0-9.e-]+ s;ASCII;DATASET POLYDATA")
  message(FATAL_ERROR "not a legacy ASCII VTK file: ${head}")
endif()
message(STATUS "legacy VTK frames: ${written}")
