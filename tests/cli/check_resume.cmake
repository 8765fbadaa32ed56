# hemo-run --checkpoint-every and --resume: a run stopped at a checkpoint and resumed in the
# same output directory ends with the same files as the uninterrupted run, byte for byte (the
# last VTK frame, and steps.csv, whose rows before the checkpoint the resumed run keeps), and
# its particles.pvd lists the frames of both parts, each once, in order; and
# a checkpoint that is not one, or belongs to another scene, is refused with exit code 1 and a
# message naming it.
#   cmake -DRUN=hemo-run -DSCENE=scene.json -DOTHER=other_scene.json -DDIR=out -P check_resume.cmake
file(REMOVE_RECURSE "${DIR}")
function(run_hemo expected_code)
  execute_process(COMMAND "${RUN}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(all "${out}${err}" PARENT_SCOPE)
  if(NOT rc STREQUAL "${expected_code}")
    message(FATAL_ERROR "hemo-run ${ARGN}: exit code ${rc}, expected ${expected_code}\n--- output ---\n${out}${err}")
  endif()
endfunction()
set(common --vtk-every 40 --stats-every 3)
run_hemo(0 "${SCENE}" --steps 40 ${common} --out "${DIR}/whole")
# Stopped at step 21 (an odd step: the clock's other record), then resumed to step 40.
run_hemo(0 "${SCENE}" --steps 21 --checkpoint-every 7 ${common} --out "${DIR}/parts")
if(NOT all MATCHES "\"checkpoint_step\": 21")
  message(FATAL_ERROR "no checkpoint at step 21\n${all}")
endif()
file(COPY "${DIR}/parts/checkpoint.hemo" DESTINATION "${DIR}/kept")
run_hemo(0 "${SCENE}" --steps 40 ${common} --resume "${DIR}/parts/checkpoint.hemo" --out "${DIR}/parts")
if(NOT all MATCHES "resumed from [^\n]*checkpoint.hemo at step 21" OR NOT all MATCHES "\"resumed_from_step\": 21")
  message(FATAL_ERROR "the resumed run does not say where it resumed\n${all}")
endif()
foreach(name particles_00000040.vtu steps.csv)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E compare_files "${DIR}/whole/${name}" "${DIR}/parts/${name}"
                  RESULT_VARIABLE differ)
  if(differ)
    message(FATAL_ERROR "${name} of the resumed run differs from the uninterrupted run's")
  endif()
endforeach()
file(READ "${DIR}/parts/particles.pvd" pvd)
string(REGEX MATCHALL "file=\"[^\"]+\"" frames "${pvd}")
if(NOT frames STREQUAL "file=\"particles_00000000.vtu\";file=\"particles_00000021.vtu\";file=\"particles_00000040.vtu\"")
  message(FATAL_ERROR "the resumed run's particles.pvd lists ${frames}\n${pvd}")
endif()
# Not a checkpoint; a checkpoint of another scene.
run_hemo(1 "${SCENE}" --steps 5 --resume "${SCENE}" --out "${DIR}/bad")
if(NOT all MATCHES "checkpoint '[^']*' is not a hemo checkpoint")
  message(FATAL_ERROR "no clear refusal of a file that is not a checkpoint\n${all}")
endif()
run_hemo(1 "${OTHER}" --steps 5 --resume "${DIR}/kept/checkpoint.hemo" --out "${DIR}/bad")
if(NOT all MATCHES "checkpoint '[^']*' was written for scene '[^']+': the particles, springs or settings of scene")
  message(FATAL_ERROR "no clear refusal of another scene's checkpoint\n${all}")
endif()
message(STATUS "resumed run identical to the uninterrupted one; bad checkpoints refused")
