# cmake -P helper for cli.drop_gltf: `afb drop --gltf` replays of short drops of the bundled figures (both Bullet
# builds), each checked by the Khronos glTF validator (tests/cli/validate_gltf.js on node, npm package
# gltf-validator) for zero errors. Arguments: AFB, AFB_DOUBLE (optional), NODE (node, or empty), SRC (repository
# root), TMP (scratch folder). Without node or the validator the replays are still written and the check is skipped
# (the output says "validation skipped"); under CI (the CI environment variable set) that is a failure instead.
file(REMOVE_RECURSE ${TMP})
file(MAKE_DIRECTORY ${TMP})

include(${CMAKE_CURRENT_LIST_DIR}/run.cmake)

set(files)
foreach(entity IN ITEMS humanoid chain props)
  run(0 ${AFB} drop --base ${SRC} ${entity} --steps 30 --gltf ${TMP}/${entity}.glb)
  list(APPEND files ${TMP}/${entity}.glb)
endforeach()
if(AFB_DOUBLE)
  run(0 ${AFB_DOUBLE} drop --base ${SRC} humanoid --steps 30 --seed 7 --gltf ${TMP}/humanoid_double.glb)
  list(APPEND files ${TMP}/humanoid_double.glb)
endif()

set(why "")
if(NOT NODE)
  set(why "node is not installed")
else()
  execute_process(COMMAND ${NODE} ${CMAKE_CURRENT_LIST_DIR}/validate_gltf.js ${files}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}${err}")
  if(rc STREQUAL "77")
    set(why "gltf-validator is not installed")
  elseif(NOT rc STREQUAL "0")
    message(FATAL_ERROR "the glTF validator found errors (exit code ${rc})")
  endif()
endif()
if(why)
  if(DEFINED ENV{CI})
    message(FATAL_ERROR "${why}: CI must validate the replays (cmake/install-deps.sh installs the validator)")
  endif()
  message(STATUS "validation skipped: ${why}")
endif()
