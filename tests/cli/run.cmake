# Included by the cmake -P helpers of the CLI tests.
# run(EXPECTED COMMAND...) runs the command, logs its output, fails unless it exits with EXPECTED, and leaves the
# combined output in `run_output`.
# run_to(EXPECTED OUT_VAR COMMAND...) does the same without logging and returns the combined output in OUT_VAR.
function(run expected)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${ARGN}\n${out}${err}")
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "exit code ${rc}, expected ${expected}")
  endif()
  set(run_output "${out}${err}" PARENT_SCOPE)
endfunction()

function(run_to expected out_var)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "${ARGN}\nexit ${rc}, expected ${expected}\n${out}\n${err}")
  endif()
  set(${out_var} "${out}${err}" PARENT_SCOPE)
endfunction()
