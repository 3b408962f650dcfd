# cmake -P test of `afb gen` (AFB, SRC, TMP given): a figure generated from the bundled humanoid's mesh is a content
# folder that `afb inspect` reads with no error, whose .af is canonical (`afb fmt --check`) and that `afb drop`
# drops; bad rules and bad models are errors with a message.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")

include("${CMAKE_CURRENT_LIST_DIR}/run.cmake")

run_to(0 out "${AFB}" gen "${SRC}/models/md5/humanoid/humanoid.md5mesh" --out "${TMP}/content" --name hum --mass 80 --json)
if(NOT out MATCHES "\"name\": \"hum\"" OR NOT out MATCHES "\"totalMassKg\": 80" OR NOT out MATCHES "\"role\": \"knee\"")
  message(FATAL_ERROR "unexpected afb gen --json output:\n${out}")
endif()
foreach(f af/hum.af def/hum.def models/md5/hum/hum.md5mesh models/md5/hum/af_pose.md5anim)
  if(NOT EXISTS "${TMP}/content/${f}")
    message(FATAL_ERROR "afb gen did not write ${f}")
  endif()
endforeach()
run_to(0 out "${AFB}" inspect --base "${TMP}/content" hum)
if(out MATCHES "error:")
  message(FATAL_ERROR "afb inspect reports errors on the generated figure:\n${out}")
endif()
run_to(0 out "${AFB}" fmt --check "${TMP}/content/af/hum.af")
run_to(0 out "${AFB}" parse "${TMP}/content/def/hum.def" "${TMP}/content/models/md5/hum/hum.md5mesh"
    "${TMP}/content/models/md5/hum/af_pose.md5anim")
run_to(0 out "${AFB}" drop --base "${TMP}/content" hum --steps 60)

file(WRITE "${TMP}/rules.json" "{\"merge\": [\"(unclosed\"]}")
run_to(1 out "${AFB}" gen "${SRC}/models/md5/humanoid/humanoid.md5mesh" --out "${TMP}/bad" --rules "${TMP}/rules.json")
if(NOT out MATCHES "rules.json: error: bad regular expression")
  message(FATAL_ERROR "a bad rules file was not reported:\n${out}")
endif()
file(WRITE "${TMP}/broken.glb" "glTF not really")
run_to(1 out "${AFB}" gen "${TMP}/broken.glb" --out "${TMP}/bad")
if(NOT out MATCHES "broken.glb: error:")
  message(FATAL_ERROR "a broken model was not reported:\n${out}")
endif()

# Units: a one unit tall md5mesh is read as metres with a note on stderr; --unit-m overrides it without one.
set(tiny "${SRC}/tests/gen/data/tiny_metres.md5mesh")
execute_process(COMMAND "${AFB}" gen "${tiny}" --out "${TMP}/tiny" --json RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT err MATCHES "tiny_metres.md5mesh: note: the model is 0.0254 m tall at Doom.s 0.0254 m per unit .1 in its own units.: read as 1 m per unit, 1 m tall"
   OR NOT out MATCHES "\"source\": \"detected\"")
  message(FATAL_ERROR "the one unit tall md5mesh was not read as metres with a note (exit ${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND "${AFB}" gen "${tiny}" --out "${TMP}/tiny" --unit-m 0.5 --json RESULT_VARIABLE rc
                OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR err MATCHES "note:" OR NOT out MATCHES "\"source\": \"unit-m\"" OR NOT out MATCHES "\"heightM\": 0.5")
  message(FATAL_ERROR "--unit-m did not set the md5mesh's scale (exit ${rc}):\n${out}\n${err}")
endif()
