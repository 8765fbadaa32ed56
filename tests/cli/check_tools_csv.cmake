# hemo-run with a scene's tools: DIR/tools.csv has its header and one row per step and tool
# (the step count after the step, time, dt, the tool's name, force, torque, tip position), the
# probe's force pushes it back up (+z) once it is in the fluid, and the summary names the file
# and gives the force signal's rate, updates and latency.
# A run stopped at a checkpoint and resumed keeps the rows up to it and ends with the same file.
#   cmake -DRUN=hemo-run -DSCENE=scene.json -DDIR=out -P check_tools_csv.cmake
file(REMOVE_RECURSE "${DIR}")
execute_process(COMMAND "${RUN}" "${SCENE}" --until 0.04 --out "${DIR}/full"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0" OR NOT "${out}" MATCHES "\"tools\": \\[[ \n]*\"probe\"[ \n]*\\],[ \n]*\"tools_file\": \"tools.csv\"")
  message(FATAL_ERROR "exit code ${rc}\n${out}${err}")
endif()
if(NOT "${out}" MATCHES "\"tool_feedback_latency_max_ms\": [0-9.e+-]+,[ \n]*\"tool_feedback_latency_ms\": [0-9.e+-]+,[ \n]*\"tool_feedback_rate_hz\": [1-9][0-9.e+-]*,[ \n]*\"tool_feedback_updates_hz\": [1-9]")
  message(FATAL_ERROR "the summary lacks the force signal's rate and latency\n${out}")
endif()
string(REGEX MATCH "\"steps\": ([0-9]+)," m "${out}")
set(steps ${CMAKE_MATCH_1})
file(STRINGS "${DIR}/full/tools.csv" rows)
list(LENGTH rows n)
math(EXPR expected "${steps} + 1")
if(NOT n EQUAL expected)
  message(FATAL_ERROR "tools.csv has ${n} lines, expected ${expected} (a header and ${steps} steps)")
endif()
list(GET rows 0 header)
if(NOT header STREQUAL "step,time_s,dt_s,tool,force_x_N,force_y_N,force_z_N,torque_x_N_m,torque_y_N_m,torque_z_N_m,position_x_m,position_y_m,position_z_m")
  message(FATAL_ERROR "header: ${header}")
endif()
list(GET rows 1 first)
if(NOT first MATCHES "^1,0,[0-9.e-]+,probe,0,0,0,0,0,0,0.02[45][0-9]*,0.0[12][0-9]*,0.(1|09)[0-9]*$")
  message(FATAL_ERROR "first row (no contact yet): ${first}")
endif()
list(GET rows ${steps} last)
string(REPLACE "," ";" fields "${last}")
list(GET fields 6 fz)
list(GET fields 12 z)
if(NOT fz GREATER 0 OR NOT z LESS 0.07)
  message(FATAL_ERROR "last row: the probe at z = ${z} m should be in the fluid and pushed up (force_z ${fz} N): ${last}")
endif()

# stopped at step 30 with a checkpoint, resumed to the same end
execute_process(COMMAND "${RUN}" "${SCENE}" --steps 30 --checkpoint-every 30 --out "${DIR}/resume"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0")
  message(FATAL_ERROR "first part: exit code ${rc}\n${out}${err}")
endif()
execute_process(COMMAND "${RUN}" "${SCENE}" --until 0.04 --resume "${DIR}/resume/checkpoint.hemo" --out "${DIR}/resume"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0")
  message(FATAL_ERROR "resumed part: exit code ${rc}\n${out}${err}")
endif()
file(READ "${DIR}/full/tools.csv" a)
file(READ "${DIR}/resume/tools.csv" b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "the resumed run's tools.csv differs from the uninterrupted run's")
endif()
message(STATUS "tools.csv: ${steps} steps, last row ${last}")
