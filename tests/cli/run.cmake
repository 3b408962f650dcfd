# Included by the cmake -P CLI tests: run(expected COMMAND...) runs a command, echoes it with its output, and stops
# the test unless its exit code is `expected`.
function(run expected)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ARGN}\n${out}${err}")
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "exit code ${rc}, expected ${expected}")
  endif()
endfunction()
