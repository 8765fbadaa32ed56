# hemo-mesh writes scenes/meshes/curved_aneurysm.stl (or, with -DSTRAIGHT=S,
# curved_aneurysm_open.stl: straight runs of S m at its ends) again, byte for byte, from the
# command docs/meshes.md gives (-DMESH, -DOUT, -DREF).
file(REMOVE "${OUT}")
set(extra "")
if(DEFINED STRAIGHT)
  set(extra --straight-m ${STRAIGHT})
endif()
execute_process(COMMAND "${MESH}" --out "${OUT}" --length-m 0.0112 --radius-m 0.00175 --bend-height-m 0.0015
                        --sac-radius-m 0.0022 --sac-offset-m 0.0031 --around 48 ${extra}
                RESULT_VARIABLE rc OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "hemo-mesh failed (${rc}):\n${output}")
endif()
execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${OUT}" "${REF}" RESULT_VARIABLE differ)
if(NOT differ EQUAL 0)
  message(FATAL_ERROR "hemo-mesh no longer writes ${REF} (compare ${OUT}); regenerate it with the command in docs/meshes.md if the change is meant")
endif()
message(STATUS "hemo-mesh reproduces ${REF}")
