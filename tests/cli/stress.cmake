# cmake -P helper for cli.stress_matrix: a small `afb stress` (2 methods × 2 scenarios, one of them the humanoid's)
# and its files: the terminal table, stress.md with both scenarios, stress.json with one cell and one run per cell,
# stress.png valid (checked by afb_picture_check; skipped when gnuplot is absent). Then the same at 2 yaws: "k/2"
# cells, every run in stress.json with its yaw, and each cell's count agreeing with its runs.
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

# FILE (a stress.json) has the given counts of yaws, cells and runs; its text is left in `json` for the caller.
function(expect_json_counts file yaws_expected cells_expected runs_expected)
  file(READ ${file} text)
  string(JSON yaws GET "${text}" yaws)
  string(JSON cells LENGTH "${text}" cells)
  string(JSON runs LENGTH "${text}" runs)
  if(NOT yaws EQUAL yaws_expected OR NOT cells EQUAL cells_expected OR NOT runs EQUAL runs_expected)
    message(FATAL_ERROR "${file}: ${yaws} yaws, ${cells} cells, ${runs} runs; "
                        "expected ${yaws_expected}, ${cells_expected}, ${runs_expected}")
  endif()
  set(json "${text}" PARENT_SCOPE)
endfunction()

expect_json_counts(${TMP}/stress.json 1 4 4)
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

# Two yaws: every cell is "k/2", stress.md has a yaw column, stress.json every run with its yaw.
run(0 ${AFB} stress --methods raw,default --scenarios tiny-bodies,chain-mass-10 --yaws 2 --out ${TMP}/yaws)
if(NOT run_output MATCHES "x 2 yaws")
  message(FATAL_ERROR "afb stress --yaws 2 did not say its yaw count:\n${run_output}")
endif()
string(REGEX MATCHALL "\n(tiny-bodies|chain-mass-10) +[0-2]/2[^\n]* +[0-2]/2" rows "${run_output}")
list(LENGTH rows nrows)
if(NOT nrows EQUAL 2)
  message(FATAL_ERROR "afb stress --yaws 2: expected 2 rows of k/2 cells:\n${run_output}")
endif()
file(READ ${TMP}/yaws/stress.md md)
if(NOT md MATCHES "\\| scenario \\| method \\| yaw ° \\| cause \\|")
  message(FATAL_ERROR "stress.md at 2 yaws has no yaw column:\n${md}")
endif()
expect_json_counts(${TMP}/yaws/stress.json 2 4 8)
# Runs are cell-major, yaw 0 then 180; each cell's passed count is its runs' passes.
foreach(c RANGE 3)
  string(JSON total GET "${json}" cells ${c} total)
  string(JSON cell_passed GET "${json}" cells ${c} passed)
  set(count 0)
  foreach(k 0 1)
    math(EXPR i "${c} * 2 + ${k}")
    math(EXPR yaw "${k} * 180")
    string(JSON run_yaw GET "${json}" runs ${i} yaw_deg)
    string(JSON run_passed GET "${json}" runs ${i} passed)
    if(NOT run_yaw EQUAL yaw)
      message(FATAL_ERROR "stress.json: run ${i} at yaw ${run_yaw}, expected ${yaw}")
    endif()
    if(run_passed)
      math(EXPR count "${count} + 1")
    endif()
  endforeach()
  if(NOT total EQUAL 2 OR NOT cell_passed EQUAL count)
    message(FATAL_ERROR "stress.json: cell ${c}: ${cell_passed}/${total}, its runs passed ${count} of 2")
  endif()
endforeach()

# Out of 1..64: refused by the option's check as a usage error (exit 2), nothing run.
foreach(bad 0 65)
  execute_process(COMMAND ${AFB} stress --yaws ${bad} --out ${TMP}/bad RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT "${out}${err}" MATCHES "--yaws: Value ${bad} not in range 1 to 64" OR EXISTS ${TMP}/bad)
    message(FATAL_ERROR "afb stress --yaws ${bad}: exit ${rc}, expected a refusal:\n${out}${err}")
  endif()
endforeach()

if(NOT GNUPLOT)
  message(STATUS "gnuplot not found: stress.png not checked (cmake/install-deps.sh installs it)")
  return()
endif()
run(0 ${CHECK} png ${TMP}/stress.png)
run(0 ${CHECK} png ${TMP}/yaws/stress.png)
# One cell (one method, one scenario) is drawn too: gnuplot's `with image` drew nothing for a grid under 2 x 2.
# default passes tiny-bodies at both yaws, so the cell is green.
run(0 ${AFB} stress --methods default --scenarios tiny-bodies --yaws 2 --out ${TMP}/one)
run(0 ${CHECK} colour ${TMP}/one/stress.png 4daf4a 10)
