# cmake -P helper for cli.stress_matrix: a small `afb stress` (2 methods × 2 scenarios, one of them the humanoid's)
# and its files: the terminal table, stress.md with both scenarios, stress.json with one cell per run, stress.png
# valid (checked by afb_picture_check; skipped when gnuplot is absent).
# Arguments: AFB, CHECK (afb_picture_check), SRC (repository root), TMP (scratch folder), GNUPLOT (its path, or
# empty/NOTFOUND).
file(REMOVE_RECURSE ${TMP})

include(${CMAKE_CURRENT_LIST_DIR}/run.cmake)

run(0 ${AFB} stress --base ${SRC} --methods raw,default --scenarios tiny-bodies,humanoid-projectile --out ${TMP})
foreach(needle "scenario" "tiny-bodies" "humanoid-projectile" "cells failed")
  if(NOT run_output MATCHES "${needle}")
    message(FATAL_ERROR "afb stress printed no '${needle}':\n${run_output}")
  endif()
endforeach()

file(READ ${TMP}/stress.md md)
foreach(needle "| tiny-bodies |" "| humanoid-projectile |" "`raw`" "`default`" "## Failures" "## Worst values")
  string(FIND "${md}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "stress.md lacks '${needle}':\n${md}")
  endif()
endforeach()

file(READ ${TMP}/stress.json json)
string(JSON cells LENGTH "${json}" cells)
if(NOT cells EQUAL 4)
  message(FATAL_ERROR "stress.json: ${cells} cells, expected 4")
endif()
string(JSON cause GET "${json}" cells 1 cause)
string(JSON passed GET "${json}" cells 1 passed)
if(NOT cause STREQUAL "pass" OR NOT passed)
  message(FATAL_ERROR "stress.json: tiny-bodies with default: ${cause}, expected pass")
endif()

if(NOT GNUPLOT)
  message(STATUS "gnuplot not found: stress.png not checked (cmake/install-deps.sh installs it)")
  return()
endif()
run(0 ${CHECK} png ${TMP}/stress.png)
