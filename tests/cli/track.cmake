# cmake -P test of `afb track` (AFB, SRC, TMP given): --json - holds the report alone with every field, --csv - a
# header and one row; a hit gives a finite recovery; bad input is refused with its exit code and a message naming
# what was wrong.
cmake_policy(SET CMP0054 NEW)
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")
set(walk models/md5/humanoid/walk.md5anim)

# track(EXPECTED ARGS...): runs afb track in SRC, fails unless it exits with EXPECTED; stdout in `out`, stderr in `err`.
function(track expected)
  execute_process(COMMAND "${AFB}" track ${ARGN} WORKING_DIRECTORY "${SRC}" RESULT_VARIABLE rc OUTPUT_VARIABLE o
                  ERROR_VARIABLE e)
  if(NOT rc STREQUAL expected)
    message(FATAL_ERROR "afb track ${ARGN}: exit ${rc}, expected ${expected}\nstdout:\n${o}\nstderr:\n${e}")
  endif()
  set(out "${o}" PARENT_SCOPE)
  set(err "${e}" PARENT_SCOPE)
endfunction()

# --json -: the report alone on stdout, one run with every field; the table on stderr.
track(0 --base . humanoid --anim ${walk} --seconds 1 --json -)
string(JSON runs ERROR_VARIABLE error LENGTH "${out}" runs)
if(error OR NOT runs EQUAL 1)
  message(FATAL_ERROR "stdout is not the JSON report with one run (${error}):\n${out}")
endif()
foreach(field figure root strength motor_hz keyframed_bodies tracking_rms_m tracking_max_m tracking_rms_deg
              tracking_max_deg exploded recovery_s steps awake_body_steps cpu_us_per_awake_body_step
              anim_limit_excess_deg method)
  string(JSON value ERROR_VARIABLE error GET "${out}" runs 0 ${field})
  if(error)
    message(FATAL_ERROR "the run has no field ${field}:\n${out}")
  endif()
endforeach()
string(JSON steps GET "${out}" runs 0 steps)
string(JSON root GET "${out}" runs 0 root)
string(JSON kf_bodies GET "${out}" runs 0 keyframed_bodies)
string(JSON recovery TYPE "${out}" runs 0 recovery_s)
string(JSON rms GET "${out}" runs 0 tracking_rms_m)
if(NOT steps EQUAL 60 OR NOT root STREQUAL "keyframed" OR NOT kf_bodies STREQUAL "pelvis" OR NOT recovery STREQUAL "NULL"
   OR NOT rms GREATER 0)
  message(FATAL_ERROR "run: ${steps} steps, root ${root}, keyframed '${kf_bodies}', recovery ${recovery}, rms ${rms}")
endif()
if(NOT err MATCHES "afb track: Bullet [0-9]" OR NOT err MATCHES "\nhumanoid +15 +60 ")
  message(FATAL_ERROR "the banner and the table are not on stderr:\n${err}")
endif()

# --csv -: a header and one row; --root free keyframes the legs.
track(0 --base . humanoid --anim ${walk} --seconds 1 --root free --csv -)
if(NOT out MATCHES "^figure,precision,method,root,strength,[^\n]*tracking_rms_m[^\n]*\nhumanoid,[a-z]+,default,free,1(\\.0)?,"
   OR NOT out MATCHES "l_thigh l_shin l_foot r_thigh r_shin r_foot")
  message(FATAL_ERROR "stdout is not the CSV report of a free root:\n${out}")
endif()

# A hit: when and where, and a finite recovery.
track(0 --base . humanoid --anim ${walk} --seconds 3 --hit TORSO:40@1.5 --json -)
string(JSON body GET "${out}" runs 0 hit_body)
string(JSON at GET "${out}" runs 0 hit_at_s)
string(JSON recovery TYPE "${out}" runs 0 recovery_s)
if(NOT body STREQUAL "torso" OR NOT at EQUAL 1.5 OR NOT recovery STREQUAL "NUMBER")
  message(FATAL_ERROR "hit: body ${body} at ${at}, recovery ${recovery}:\n${out}")
endif()

# Bad input: a file that is not there (1), a body the figure lacks (1, with the nearest), numbers out of range (2).
track(1 --base . humanoid --anim no/such/walk.md5anim)
if(NOT err MATCHES "no/such/walk.md5anim: error: ")
  message(FATAL_ERROR "a missing anim was not named:\n${err}")
endif()
track(1 --base . humanoid --anim ${walk} --hit torsoo:40@1)
if(NOT err MATCHES "unknown body 'torsoo'; did you mean 'torso'\\?")
  message(FATAL_ERROR "an unknown body was not named:\n${err}")
endif()
track(1 --base . humanoid --anim models/md5/props/chain/chain.md5mesh)
track(1 --base . humanoid --anim tests/cli/data/chain_reparented.md5anim)
if(NOT err MATCHES "error: ")
  message(FATAL_ERROR "an anim of another skeleton was not refused with an error:\n${err}")
endif()
track(2 --base . humanoid --anim ${walk} --strength -1)
if(NOT err MATCHES "--strength: Value -1")
  message(FATAL_ERROR "a negative strength was not refused:\n${err}")
endif()
track(2 --base . humanoid --anim ${walk} --hz 0)
if(NOT err MATCHES "--hz: Value 0 is not a positive number")
  message(FATAL_ERROR "--hz 0 was not refused:\n${err}")
endif()
track(2 --base . humanoid --anim ${walk} --hit torso:40)
if(NOT err MATCHES "is not BODY:NS@SECONDS")
  message(FATAL_ERROR "a malformed --hit was not refused:\n${err}")
endif()
track(2 --base . humanoid --anim ${walk} --hit torso:40@0.2)
if(NOT err MATCHES "after the 0.5 s warm-up")
  message(FATAL_ERROR "a hit in the warm-up was not refused:\n${err}")
endif()
track(2 --base . humanoid --anim ${walk} --method raw)
track(2 --base . humanoid)
