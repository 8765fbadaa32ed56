# hemo-mesh writes scenes/meshes/curved_aneurysm.stl (or, with -DSTRAIGHT=S,
# curved_aneurysm_open.stl: straight runs of S m at its ends; with -DBRANCH=1,
# bifurcation_aneurysm_open.stl) again, byte for byte, from the command docs/meshes.md gives
# (-DMESH, -DOUT, -DREF).
file(REMOVE "${OUT}")
if(DEFINED BRANCH)
  set(args --length-m 0.015 --radius-m 0.00175 --branch-angle-deg 45 --branch-radius-m 0.0014 --split-m 0.005
           --spread-m 0.005 --sac-radius-m 0.002 --sac-offset-m 0.0035 --cell-m 0.00025)
else()
  set(args --length-m 0.0112 --radius-m 0.00175 --bend-height-m 0.0015 --sac-radius-m 0.0022 --sac-offset-m 0.0031 --around 48)
  if(DEFINED STRAIGHT)
    list(APPEND args --straight-m ${STRAIGHT})
  endif()
endif()
execute_process(COMMAND "${MESH}" --out "${OUT}" ${args}
                RESULT_VARIABLE rc OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hemo-mesh failed (${rc}):\n${output}")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${OUT}" "${REF}" RESULT_VARIABLE differ)
if(NOT differ EQUAL 0)
  message(FATAL_ERROR "hemo-mesh no longer writes ${REF} (compare ${OUT}); regenerate it with the command in docs/meshes.md if the change is meant")
endif()
message(STATUS "hemo-mesh reproduces ${REF}")
