# cmake -P helper for cli.draw_humanoid: `afb draw` of the bundled humanoid to PNG and SVG, both checked by
# afb_picture_check, and the pose of a drop at t = 0 (its spawn pose, through Bullet) drawn like the load pose.
# Arguments: AFB, AFB_DOUBLE (optional: afb-double), CHECK (afb_picture_check), SRC (repository root), TMP
# (scratch folder).
file(REMOVE_RECURSE ${TMP})
file(MAKE_DIRECTORY ${TMP})

include(${CMAKE_CURRENT_LIST_DIR}/run.cmake)

run(0 ${AFB} draw --base ${SRC} humanoid --out ${TMP}/load.png)
run(0 ${CHECK} png ${TMP}/load.png)
run(0 ${AFB} draw --base ${SRC} humanoid --out ${TMP}/load.svg)
run(0 ${CHECK} svg ${TMP}/load.svg)

# The title band (the top 80 rows) names the pose and differs; the figure below it must not. Bullet's float build
# rounds the spawn transforms to float, which may shade an antialiased edge pixel differently by a few levels (a
# pose that differs moves whole edges: differences of 100 and more); its double build must give the same pixels.
run(0 ${AFB} draw --base ${SRC} humanoid --at 0 --out ${TMP}/at0.png)
run(0 ${CHECK} same ${TMP}/load.png ${TMP}/at0.png 80 8)
if(AFB_DOUBLE)
  run(0 ${AFB_DOUBLE} draw --base ${SRC} humanoid --at 0 --out ${TMP}/at0_double.png)
  run(0 ${CHECK} same ${TMP}/load.png ${TMP}/at0_double.png 80 0)
endif()
# A second into the drop the figure has moved: the same check must see it.
run(0 ${AFB} draw --base ${SRC} humanoid --at 1 --out ${TMP}/at1.png)
run(0 ${CHECK} png ${TMP}/at1.png)
run(1 ${CHECK} same ${TMP}/load.png ${TMP}/at1.png 80 0)
# --show names: body and constraint names are drawn (the picture differs from the same layers without them).
run(0 ${AFB} draw --base ${SRC} humanoid --show bodies,joints --out ${TMP}/unnamed.png)
run(0 ${AFB} draw --base ${SRC} humanoid --show bodies,joints,names --out ${TMP}/names.png)
run(0 ${CHECK} png ${TMP}/names.png)
run(1 ${CHECK} same ${TMP}/unnamed.png ${TMP}/names.png 80 0)
