# Included by the cmake -P helpers of the CLI tests: run(EXPECTED COMMAND...) runs the command, logs its output,
# fails unless it exits with EXPECTED, and leaves the combined output in `run_output`.
function(run expected)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ARGN}\n${out}${err}")
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "exit code ${rc}, expected ${expected}")
  endif()
  set(run_output "${out}${err}" PARENT_SCOPE)
endfunction()
