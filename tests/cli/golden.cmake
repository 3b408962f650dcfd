# cmake -P test of `afb golden` (AFB, SRC, TMP given): recording twice gives the same state hash; a changed input
# is reported as a changed input; and, compared anyway, the pose difference names the joints that moved.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")
file(COPY "${SRC}/af" "${SRC}/def" "${SRC}/models" DESTINATION "${TMP}")

include("${CMAKE_CURRENT_LIST_DIR}/run.cmake")

run_to(0 out "${AFB}" golden record --base "${TMP}" chain --out "${TMP}/first.json")
run_to(0 out "${AFB}" golden record --base "${TMP}" chain --out "${TMP}/second.json")
file(READ "${TMP}/first.json" first)
file(READ "${TMP}/second.json" second)
string(JSON h1 GET "${first}" state_hash)
string(JSON h2 GET "${second}" state_hash)
if(NOT h1 STREQUAL h2)
  message(FATAL_ERROR "recording twice gave different state hashes: ${h1} vs ${h2}")
endif()
run_to(0 out "${AFB}" golden compare --exact "${TMP}/first.json")

# A record whose method lacks a knob (made before the knob existed) is refused, not run with today's preset value.
string(JSON older REMOVE "${first}" options method friction-directions)
file(WRITE "${TMP}/older.json" "${older}")
run_to(1 out "${AFB}" golden compare "${TMP}/older.json")
if(NOT out MATCHES "does not name friction-directions")
  message(FATAL_ERROR "a record without a knob was not refused:\n${out}")
endif()

# A deliberate change: the hook moves 8 units (0.2 m) sideways, so the chain swings to hang below it.
file(READ "${TMP}/af/chain.af" af)
string(REPLACE "body2 \"world\"\n\t\tanchor joint( \"link1\" )" "body2 \"world\"\n\t\tanchor ( 8, 0, 100 )" changed "${af}")
if(changed STREQUAL af)
  message(FATAL_ERROR "the test's edit of af/chain.af did not apply")
endif()
file(WRITE "${TMP}/af/chain.af" "${changed}")
run_to(1 out "${AFB}" golden compare "${TMP}/first.json")
if(NOT out MATCHES "input changed since recording: af/chain.af")
  message(FATAL_ERROR "a changed input was not reported as such:\n${out}")
endif()
run_to(1 out "${AFB}" golden compare --ignore-inputs "${TMP}/first.json")
if(NOT out MATCHES "FAIL" OR NOT out MATCHES "\\(entity\\) +moved")
  message(FATAL_ERROR "the pose difference does not name the joints that moved:\n${out}")
endif()
