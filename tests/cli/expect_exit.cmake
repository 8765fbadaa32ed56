# Runs a command and checks its exit code and output.
#   cmake -DCMD=<;-list> -DCODE=<int> -DREGEX=<regex> [-DWORKDIR=dir] -P expect_exit.cmake
# (or include()d with CMD, CODE and REGEX set, as tests/embed/check.cmake does)
execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
set(all "${out}${err}")
if(NOT rc STREQUAL "${CODE}")
  message(FATAL_ERROR "exit code ${rc}, expected ${CODE}\n--- output ---\n${all}")
endif()
if(NOT all MATCHES "${REGEX}")
  message(FATAL_ERROR "output does not match '${REGEX}'\n--- output ---\n${all}")
endif()
if(all MATCHES "validation (error|warning)")
  message(FATAL_ERROR "validation messages in the output\n${all}")
endif()
