# Shared by the cmake -P CLI tests: run(EXPECT_RC OUT_VAR COMMAND...) runs a command, fails the test unless it
# exits with EXPECT_RC, and returns its stdout and stderr in OUT_VAR.
function(run expect_rc out_var)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc STREQUAL expect_rc)
    message(FATAL_ERROR "${ARGN}\nexit ${rc}, expected ${expect_rc}\n${out}\n${err}")
  endif()
  set(${out_var} "${out}${err}" PARENT_SCOPE)
endfunction()
