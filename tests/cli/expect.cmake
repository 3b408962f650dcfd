# cmake -P helper for CLI tests: runs CMD (a ;-list), checks the exit code is EXIT and that the combined
# output matches every regular expression in MATCH (a ;-list; may be empty).
execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL EXIT)
  message(FATAL_ERROR "exit code ${rc}, expected ${EXIT}\nstdout:\n${out}\nstderr:\n${err}")
endif()
foreach(re IN LISTS MATCH)
  if(NOT "${out}${err}" MATCHES "${re}")
    message(FATAL_ERROR "output does not match '${re}'\nstdout:\n${out}\nstderr:\n${err}")
  endif()
endforeach()
