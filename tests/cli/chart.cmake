# cmake -P helper for cli.chart_matrix: a small `afb chart` (2 methods × 1 figure × 1 height, a short drop) and
# its files: runs.csv with every documented column and one row per run, front.png and front.svg valid (checked
# by afb_picture_check; skipped when gnuplot is absent), summary.md naming a front. Then the tracking panel
# (--track): raw left out, one track.md row per method and strength, track.png and track.svg valid.
# Arguments: AFB, CHECK (afb_picture_check), SRC (repository root), TMP (scratch folder), GNUPLOT (its path, or
# empty/NOTFOUND).
cmake_policy(SET CMP0007 NEW) # empty CSV cells are list elements
file(REMOVE_RECURSE ${TMP})

include(${CMAKE_CURRENT_LIST_DIR}/run.cmake)

run(0 ${AFB} chart --base ${SRC} chain --methods raw,fast:position-iterations=1 --heights 1 --hz 60 --repeats 1
    --seconds 0.5 --threads 2 --out ${TMP} --max-anchor-error 0.5)

# runs.csv: the README's columns, in order, then one row per run.
file(STRINGS ${TMP}/runs.csv lines)
list(LENGTH lines count)
if(NOT count EQUAL 3)
  message(FATAL_ERROR "runs.csv: ${count} lines, expected a header and 2 runs")
endif()
list(GET lines 0 header)
set(expected_columns
    method_label height_m hz repeat figure precision method bodies constraints lod_bodies motor_hz motor_damping_ratio
    steps wall_ms us_per_step
    us_per_body_step awake_body_steps step_cpu_ms awake_step_cpu_ms cpu_us_per_awake_body_step max_anchor_error_m worst_anchor_joint
    max_limit_violation_deg worst_limit_joint max_penetration_m worst_contact rest_penetration_m max_energy_gain_j
    max_speed_mps exploded exploded_at_s non_finite settle_time_s frozen_before_contact method.backend method.substeps method.impact-substeps method.iterations
    method.joint-iterations method.solver-tolerance method.split-impulse method.contact-erp method.joint-erp method.limit-erp
    method.warm-starting method.warm-starting-factor method.friction-directions method.position-iterations method.position-tree method.position-velocity method.multipoint-contacts
    method.speculative-contacts method.self-contact-cap method.speculative-limits method.ccd method.joint-warm-starting
    method.limit-warm-starting method.direct-joints method.figure-iterations method.figure-sweeps method.merge-fixed method.exempt-overlapping
    method.constant-velocity-universal method.friction-through-figure method.joint-space method.separated-pairs)
string(REPLACE "," ";" columns "${header}")
if(NOT columns STREQUAL expected_columns)
  message(FATAL_ERROR "runs.csv header:\n  ${header}\nexpected:\n  ${expected_columns}")
endif()
list(LENGTH expected_columns column_count)
foreach(i 1 2)
  list(GET lines ${i} row)
  string(REPLACE "," ";" cells "${row}")
  list(LENGTH cells cell_count)
  if(NOT cell_count EQUAL column_count)
    message(FATAL_ERROR "runs.csv row ${i} has ${cell_count} cells, expected ${column_count}: ${row}")
  endif()
endforeach()
list(GET lines 1 first)
list(GET lines 2 second)
if(NOT first MATCHES "^raw,1,60,0,chain," OR NOT second MATCHES "^fast:position-iterations=1,1,60,0,chain,")
  message(FATAL_ERROR "runs.csv rows are not the two methods in order:\n${first}\n${second}")
endif()

# summary.md names the front and answers the bound.
file(READ ${TMP}/summary.md summary)
foreach(needle "## chain" "Pareto front" "`raw`" "`fast:position-iterations=1`" "Cheapest within anchor ≤ 500 mm")
  string(FIND "${summary}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "summary.md lacks '${needle}':\n${summary}")
  endif()
endforeach()

# The tracking panel: the humanoid's walk at two strengths with the one rigid method listed.
run(0 ${AFB} chart --base ${SRC} humanoid --track models/md5/humanoid/walk.md5anim --methods raw,fast --strengths 0.5,2
    --hz 60 --repeats 1 --seconds 1 --out ${TMP}/track)
if(NOT run_output MATCHES "raw left out")
  message(FATAL_ERROR "afb chart --track did not say it left raw out:\n${run_output}")
endif()
file(READ ${TMP}/track/track.md track)
foreach(needle "## humanoid" "| fast | 0.50 |" "| fast | 2.00 |")
  string(FIND "${track}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "track.md lacks '${needle}':\n${track}")
  endif()
endforeach()

# The pictures, when gnuplot is there to draw them.
if(NOT GNUPLOT)
  message(STATUS "gnuplot not found: front.png/front.svg not checked (cmake/install-deps.sh installs it)")
  if(NOT run_output MATCHES "gnuplot not found")
    message(FATAL_ERROR "without gnuplot, afb chart must say so")
  endif()
  return()
endif()
run(0 ${CHECK} png ${TMP}/front.png)
run(0 ${CHECK} svg ${TMP}/front.svg)
run(0 ${CHECK} png ${TMP}/track/track.png)
run(0 ${CHECK} svg ${TMP}/track/track.svg)
