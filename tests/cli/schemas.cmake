# cmake -P test of the "schema" member every JSON report carries (AFB, SRC, TMP given): each command's JSON parses
# and names its report and version 1 (docs/cli.md, "Report schemas"); a golden file of a newer version than this afb
# reads is refused with an error naming both versions, and one without "schema" (recorded before it existed) is read.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")

# run(EXPECTED ARGS...): runs afb in TMP, fails unless it exits with EXPECTED; stdout in `out`, stderr in `err`.
function(run expected)
  execute_process(COMMAND "${AFB}" ${ARGN} WORKING_DIRECTORY "${TMP}" RESULT_VARIABLE rc OUTPUT_VARIABLE o
                  ERROR_VARIABLE e)
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "afb ${ARGN}: exit ${rc}, expected ${expected}\nstdout:\n${o}\nstderr:\n${e}")
  endif()
  set(out "${o}" PARENT_SCOPE)
  set(err "${e}" PARENT_SCOPE)
endfunction()

# expect_schema(WHAT JSON NAME): the document's schema is {NAME, 1}.
function(expect_schema what json name)
  string(JSON got ERROR_VARIABLE error GET "${json}" schema name)
  string(JSON version ERROR_VARIABLE error2 GET "${json}" schema version)
  if(error OR error2 OR NOT got STREQUAL name OR NOT version EQUAL 1)
    message(FATAL_ERROR "${what}: schema ${got} version ${version}, expected ${name} version 1 (${error}${error2}):\n${json}")
  endif()
endfunction()

run(0 drop --base "${SRC}" chain --steps 3 --json -)
expect_schema("afb drop --json -" "${out}" afbullet-drop)
run(0 methods --json)
expect_schema("afb methods --json" "${out}" afbullet-methods)
run(0 methods fast --json)
expect_schema("afb methods fast --json" "${out}" afbullet-method)
run(0 resolve --base "${SRC}" chain --json)
expect_schema("afb resolve --json" "${out}" afbullet-resolve)
run(0 inspect --base "${SRC}" chain --json)
expect_schema("afb inspect --json" "${out}" afbullet-inspect)
run(0 parse "${SRC}/af/chain.af" --json)
expect_schema("afb parse --json" "${out}" afbullet-parse)
run(0 gen "${SRC}/models/md5/humanoid/humanoid.md5mesh" --out "${TMP}/gen" --name hum --mass 80 --json)
expect_schema("afb gen --json" "${out}" afbullet-gen)
run(0 stress --base "${SRC}" --methods fast --scenarios tiny-bodies --threads 1 --out "${TMP}/stress")
file(READ "${TMP}/stress/stress.json" stress)
expect_schema("afb stress's stress.json" "${stress}" afbullet-stress)

# Goldens: recorded with the schema; a newer version refused; none at all read as version 1.
run(0 golden record --base "${SRC}" chain --seconds 0.5 --out "${TMP}/chain.json")
file(READ "${TMP}/chain.json" golden)
expect_schema("afb golden record" "${golden}" afbullet-golden)
run(0 golden compare "${TMP}/chain.json")
string(JSON newer SET "${golden}" schema version 2)
file(WRITE "${TMP}/newer.json" "${newer}")
run(1 golden compare "${TMP}/newer.json")
if(NOT "${out}${err}" MATCHES "newer.json: error: afbullet-golden version 2: this afb reads up to version 1")
  message(FATAL_ERROR "a golden of a newer schema was not refused by name:\nstdout:\n${out}\nstderr:\n${err}")
endif()
string(JSON unversioned REMOVE "${golden}" schema)
file(WRITE "${TMP}/unversioned.json" "${unversioned}")
run(0 golden compare "${TMP}/unversioned.json")
