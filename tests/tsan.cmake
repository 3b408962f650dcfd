# Included from tests/CMakeLists.txt under AFB_TSAN: the afb tool's threaded runs, each of which must finish without
# a ThreadSanitizer report (the tsan test preset makes any report fail the run with TSAN_OPTIONS' exit code).
if(NOT TARGET afb)
  return()
endif()

function(afb_tsan_run name)
  add_test(NAME tsan.${name} COMMAND $<TARGET_FILE:afb> ${ARGN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(tsan.${name} PROPERTIES FAIL_REGULAR_EXPRESSION "WARNING: ThreadSanitizer")
endfunction()

set(_out ${CMAKE_CURRENT_BINARY_DIR}/tsan)
afb_tsan_run(drop_threads drop --base . humanoid buggy chain --count 8 --worlds 4 --threads 2 --seconds 1)
afb_tsan_run(drop_multibody_threads drop --base . humanoid --method multibody --count 4 --worlds 4 --threads 2
             --seconds 1)
afb_tsan_run(chart_threads chart --base . humanoid chain --methods raw,default,multibody --heights 1 --seconds 1
             --threads 2 --out ${_out}/chart)
afb_tsan_run(stress_threads stress --base . --methods default,multibody --scenarios tiny-bodies,rope-30 --yaws 2
             --threads 2 --out ${_out}/stress)
