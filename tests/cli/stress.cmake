# cmake -P helper for cli.stress_matrix: a small `afb stress` (2 methods × 2 scenarios, one of them the humanoid's)
# and its files: the terminal table, stress.md with both scenarios, stress.json with one cell and one run per cell,
# stress.png valid (checked by afb_picture_check; skipped when gnuplot is absent).
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
string(JSON yaws GET "${json}" yaws)
string(JSON cells LENGTH "${json}" cells)
string(JSON runs LENGTH "${json}" runs)
if(NOT yaws EQUAL 1 OR NOT cells EQUAL 4 OR NOT runs EQUAL 4)
  message(FATAL_ERROR "stress.json: ${yaws} yaws, ${cells} cells, ${runs} runs; expected 1, 4, 4")
endif()
string(JSON cause GET "${json}" runs 1 cause)
string(JSON passed GET "${json}" runs 1 passed)
string(JSON cell_passed GET "${json}" cells 1 passed)
if(NOT cause STREQUAL "pass" OR NOT passed OR NOT cell_passed EQUAL 1)
  message(FATAL_ERROR "stress.json: tiny-bodies with default: ${cause}, expected pass")
endif()
# At one yaw a cell reads as before: "ok" or a cause and its time, no "k/1".
if(run_output MATCHES "[0-9]/1" OR NOT run_output MATCHES "scenario +raw +default\ntiny-bodies +[a-z-]+[ 0-9.s]* +ok")
  message(FATAL_ERROR "afb stress at one yaw: the cells are not 'ok' / 'cause time':\n${run_output}")
endif()

if(NOT GNUPLOT)
  message(STATUS "gnuplot not found: stress.png not checked (cmake/install-deps.sh installs it)")
  return()
endif()
run(0 ${CHECK} png ${TMP}/stress.png)
