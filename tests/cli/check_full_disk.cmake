# hemo-run on a disk that fills up: the process's file-size limit (ulimit -f, in KiB) stands in
# for a full disk, since a write past it fails as one past the disk's end does (EFBIG instead
# of ENOSPC; SIGXFSZ ignored so the write returns the error). The run must exit with code 4,
# naming the file and the reason, and leave no file under a real name that it did not finish,
# nor any temporary.
#   cmake -DRUN=hemo-run -DSCENE=scene.json -DDIR=out -DLIMIT_KIB=n -P check_full_disk.cmake
file(REMOVE_RECURSE "${DIR}")
file(MAKE_DIRECTORY "${DIR}")
execute_process(
  COMMAND bash -c "ulimit -f ${LIMIT_KIB} && trap '' XFSZ && exec \"$0\" \"$@\"" "${RUN}" "${SCENE}" --steps 40
          --vtk-every 10 --stats-every 1 --out "${DIR}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
if(NOT rc STREQUAL "4")
  message(FATAL_ERROR "exit code ${rc}, expected 4\n--- output ---\n${all}")
endif()
if(NOT all MATCHES "failed while writing '[^']*particles_[0-9]+\\.vtu': File too large")
  message(FATAL_ERROR "the message does not name the file and the reason\n--- output ---\n${all}")
endif()
file(GLOB left RELATIVE "${DIR}" "${DIR}/*")
foreach(name IN LISTS left)
  if(name MATCHES "\\.part-")
    message(FATAL_ERROR "a temporary was left behind: ${name}")
  endif()
  if(name MATCHES "^particles_.*\\.vtu$" OR name STREQUAL "particles.pvd")
    file(SIZE "${DIR}/${name}" size)
    message(FATAL_ERROR "${name} (${size} bytes) exists, but the limit stops every VTK file of the scene")
  endif()
endforeach()
message(STATUS "full disk: exit 4, no partial file (left: ${left})")
