# cmake -P test (AFB, SRC, TMP given): a drop whose figure is put to rest by its maxMoveTime before it touched
# anything says so. The bundled humanoid with maxMoveTime 2 s: dropped from 1000 m it is frozen in the air at 2 s
# (the table marks the settle time and explains it, the JSON counts the instances); dropped from 5 cm it lands first.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")
file(COPY "${SRC}/af" "${SRC}/def" "${SRC}/models" DESTINATION "${TMP}")
include("${CMAKE_CURRENT_LIST_DIR}/run.cmake")

file(READ "${TMP}/af/humanoid.af" af)
string(REPLACE "maxMoveTime -1" "maxMoveTime 2" changed "${af}")
if(changed STREQUAL af)
  message(FATAL_ERROR "the test's edit of af/humanoid.af did not apply")
endif()
file(WRITE "${TMP}/af/humanoid.af" "${changed}")

run_to(0 out "${AFB}" drop --base "${TMP}" humanoid --height 1000 --seconds 3)
if(NOT out MATCHES "\nhumanoid +15 [^\n]* 2\\.0[0-9]*\\*\n" OR
   NOT out MATCHES "humanoid: \\* 1 of 1 instances came to rest before touching anything")
  message(FATAL_ERROR "a figure frozen in the air is not said to be:\n${out}")
endif()
execute_process(COMMAND "${AFB}" drop --base "${TMP}" humanoid --height 1000 --seconds 3 --count 2 --json -
                RESULT_VARIABLE rc OUTPUT_VARIABLE json ERROR_VARIABLE err)
string(JSON frozen GET "${json}" runs 0 frozen_before_contact)
if(NOT rc EQUAL 0 OR NOT frozen EQUAL 2)
  message(FATAL_ERROR "frozen_before_contact ${frozen}, expected 2 (exit ${rc})\n${err}")
endif()

execute_process(COMMAND "${AFB}" drop --base "${TMP}" humanoid --height 0.05 --seconds 3 --json -
                RESULT_VARIABLE rc OUTPUT_VARIABLE json ERROR_VARIABLE err)
string(JSON frozen GET "${json}" runs 0 frozen_before_contact)
string(JSON settled GET "${json}" runs 0 settle_time_s)
if(NOT rc EQUAL 0 OR NOT frozen EQUAL 0 OR settled STREQUAL "null" OR err MATCHES "came to rest before touching")
  message(FATAL_ERROR "a figure that landed: frozen_before_contact ${frozen}, settle_time_s ${settled}\n${err}")
endif()
