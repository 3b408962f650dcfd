# cmake -P test of `afb drop`'s reports on stdout (AFB, SRC, TMP given): with `--json -` or `--csv -` stdout holds
# that document alone (it parses, and its values are the drop's) and the human text goes to stderr; both on stdout
# is refused; an entity that is not there prints its error and nothing else.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")

# streams(EXPECTED ARGS...): runs afb in TMP, fails unless it exits with EXPECTED; stdout in `out`, stderr in `err`.
function(streams expected)
  execute_process(COMMAND "${AFB}" ${ARGN} WORKING_DIRECTORY "${TMP}" RESULT_VARIABLE rc OUTPUT_VARIABLE o
                  ERROR_VARIABLE e)
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "afb ${ARGN}: exit ${rc}, expected ${expected}\nstdout:\n${o}\nstderr:\n${e}")
  endif()
  set(out "${o}" PARENT_SCOPE)
  set(err "${e}" PARENT_SCOPE)
endfunction()

# expect_json(WHAT JSON EXPECTED GET|LENGTH PATH...): the value (or the array's length) at PATH is EXPECTED.
function(expect_json what json expected mode)
  string(JSON value ERROR_VARIABLE error ${mode} "${json}" ${ARGN})
  if(error)
    message(FATAL_ERROR "stdout is not the JSON report (${error}):\n${json}")
  endif()
  if(NOT value STREQUAL expected)
    message(FATAL_ERROR "${what}: ${value}, expected ${expected}")
  endif()
endfunction()

# --json -: the report of both figures on stdout; the banner and the table on stderr.
streams(0 drop --base "${SRC}" humanoid chain --steps 10 --json -)
expect_json("runs" "${out}" 2 LENGTH runs)
expect_json("first run's figure" "${out}" humanoid GET runs 0 figure)
expect_json("first run's bodies" "${out}" 15 GET runs 0 bodies)
expect_json("first run's steps" "${out}" 10 GET runs 0 steps)
expect_json("second run's figure" "${out}" chain GET runs 1 figure)
expect_json("second run's bodies" "${out}" 10 GET runs 1 bodies)
if(NOT err MATCHES "afb drop: Bullet [0-9]" OR NOT err MATCHES "\nentity +bodies +steps" OR NOT err MATCHES "\nhumanoid +15 +10 ")
  message(FATAL_ERROR "the banner and the table are not on stderr:\n${err}")
endif()

# --csv -: the header and one row per figure on stdout, no file named '-'.
streams(0 drop --base "${SRC}" humanoid --steps 10 --csv -)
string(REGEX REPLACE "\n$" "" csv "${out}")
string(REPLACE "\n" ";" lines "${csv}")
list(LENGTH lines count)
if(NOT count EQUAL 2)
  message(FATAL_ERROR "stdout holds ${count} lines, expected the CSV header and one row:\n${out}")
endif()
list(GET lines 0 header)
list(GET lines 1 row)
if(NOT header MATCHES "^figure,precision,method,bodies,constraints,lod_bodies,motor_hz,motor_damping_ratio,steps,wall_ms,")
  message(FATAL_ERROR "CSV header: ${header}")
endif()
if(NOT row MATCHES "^humanoid,(float|double),default,15,[0-9]+,,,,10,")
  message(FATAL_ERROR "CSV row: ${row}")
endif()
if(EXISTS "${TMP}/-")
  message(FATAL_ERROR "--csv - wrote a file named '-'")
endif()
if(NOT err MATCHES "afb drop: Bullet [0-9]")
  message(FATAL_ERROR "the banner is not on stderr:\n${err}")
endif()

# A file and stdout together: the JSON file as without '-', the CSV on stdout.
streams(0 drop --base "${SRC}" chain --steps 3 --json "${TMP}/chain.json" --csv -)
file(READ "${TMP}/chain.json" json)
expect_json("--json FILE beside --csv -" "${json}" 3 GET runs 0 steps)
if(NOT out MATCHES "^figure,[^\n]*\nchain,")
  message(FATAL_ERROR "stdout is not the CSV report:\n${out}")
endif()

# Both on stdout: a usage error, nothing run.
streams(2 drop --base "${SRC}" chain --steps 3 --json - --csv -)
if(NOT out STREQUAL "" OR NOT err MATCHES "--json - and --csv -")
  message(FATAL_ERROR "--json - --csv - was not refused alone:\nstdout:\n${out}\nstderr:\n${err}")
endif()

# A misspelt entity: its error with the nearest entityDef, no banner, no table, no report.
streams(1 drop --base "${SRC}" humanoidd chain --steps 3 --json -)
if(NOT out STREQUAL "")
  message(FATAL_ERROR "stdout is not empty for an entity that is not there:\n${out}")
endif()
if(NOT err MATCHES "entityDef 'humanoidd' not found; did you mean 'humanoid'\\?" OR err MATCHES "afb drop: Bullet"
   OR err MATCHES "entity +bodies")
  message(FATAL_ERROR "an entity that is not there printed more than its error:\n${err}")
endif()
