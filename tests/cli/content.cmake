# cmake -P check that the bundled content is reproducible: runs the content generator into a scratch folder and
# compares every file it writes with the committed copy, byte for byte.
#   GEN     path of the afb_gen_content executable
#   SOURCE  the repository root (holds the committed af/, def/, models/)
#   WORK    a scratch folder (emptied first)
# Register (tests/CMakeLists.txt or tests/cli/register.cmake):
#   add_test(NAME cli.content_reproducible
#            COMMAND ${CMAKE_COMMAND} -DGEN=$<TARGET_FILE:afb_gen_content> -DSOURCE=${PROJECT_SOURCE_DIR}
#                    -DWORK=${CMAKE_CURRENT_BINARY_DIR}/content_check -P ${PROJECT_SOURCE_DIR}/tests/cli/content.cmake)
foreach(var GEN SOURCE WORK)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "content.cmake: pass -D${var}=...")
  endif()
endforeach()

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
execute_process(COMMAND "${GEN}" "${WORK}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0")
  message(FATAL_ERROR "afb_gen_content failed (exit code ${rc})\nstdout:\n${out}\nstderr:\n${err}")
endif()

file(GLOB_RECURSE generated RELATIVE "${WORK}" LIST_DIRECTORIES false "${WORK}/*")
list(SORT generated)
list(LENGTH generated count)
if(count EQUAL 0)
  message(FATAL_ERROR "afb_gen_content wrote no files into ${WORK}")
endif()

set(problems "")
foreach(rel IN LISTS generated)
  if(NOT EXISTS "${SOURCE}/${rel}")
    string(APPEND problems "  ${rel}: generated but not committed\n")
    continue()
  endif()
  file(READ "${WORK}/${rel}" fresh HEX)
  file(READ "${SOURCE}/${rel}" committed HEX)
  if(NOT fresh STREQUAL committed)
    string(APPEND problems "  ${rel}: differs from the committed file (re-run `afb_gen_content .` from the repo root)\n")
  endif()
endforeach()
if(NOT problems STREQUAL "")
  message(FATAL_ERROR "bundled content is not reproducible:\n${problems}")
endif()
message(STATUS "content: ${count} generated files match the committed ones")
