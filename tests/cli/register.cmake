# Included from tests/CMakeLists.txt: end-to-end tests of the afb tool on bundled content.
if(NOT TARGET afb)
  return()
endif()

function(afb_cli_test name exit)
  cmake_parse_arguments(T "" "" "ARGS;MATCH" ${ARGN})
  add_test(NAME cli.${name}
    COMMAND ${CMAKE_COMMAND} "-DCMD=$<TARGET_FILE:afb>;${T_ARGS}" "-DEXIT=${exit}" "-DMATCH=${T_MATCH}"
            -P ${CMAKE_CURRENT_LIST_DIR}/expect.cmake
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
endfunction()

file(GLOB _afb_bundled_af RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/af/*.af)
file(GLOB _afb_bundled_def RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/def/*.def)
file(GLOB_RECURSE _afb_bundled_md5 RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS
     ${PROJECT_SOURCE_DIR}/models/*.md5mesh ${PROJECT_SOURCE_DIR}/models/*.md5anim)

afb_cli_test(parse_bundled 0 ARGS parse ${_afb_bundled_af} ${_afb_bundled_def} ${_afb_bundled_md5})
afb_cli_test(parse_json 0 ARGS parse --json af/chain.af models/md5/props/chain/chain.md5mesh
             MATCH "\"bodies\":10" "\"constraints\":10" "\"joints\":11" "\"tris\":10")
afb_cli_test(parse_error_location 1 ARGS parse tests/cli/data/typo_in_body.af
             MATCH "typo_in_body.af:5:3: error: unknown token 'denisty' in body 'pelvis'")
afb_cli_test(parse_missing_file 1 ARGS parse no/such/file.af MATCH "no/such/file.af: error: no such file")
afb_cli_test(parse_unknown_type 1 ARGS parse README.md MATCH "unknown file type")
# afb --version: the project version, the Bullet it runs on, its precision and build type; afb-double says double.
afb_cli_test(version 0 ARGS --version
             MATCH "^afb [0-9]+\\.[0-9]+\\.[0-9]+ \\(Bullet [0-9.]+, (float|double), " "^afb ${PROJECT_VERSION} \\(.*, float, ")
add_test(NAME cli.version_double
  COMMAND ${CMAKE_COMMAND} "-DCMD=$<TARGET_FILE:afb-double>;--version" "-DEXIT=0"
          "-DMATCH=^afb ${PROJECT_VERSION} \\(Bullet [0-9.]+, double, " -P ${CMAKE_CURRENT_LIST_DIR}/expect.cmake)
foreach(af IN LISTS _afb_bundled_af)
  get_filename_component(_n ${af} NAME_WE)
  afb_cli_test(fmt_canonical_${_n} 0 ARGS fmt --check ${af})
endforeach()
afb_cli_test(resolve_chain 0 ARGS resolve --base . chain
             MATCH "models/md5/props/chain/chain.md5mesh" "af_pose.md5anim" "chain.af")
afb_cli_test(resolve_json 0 ARGS resolve --json --base . chain MATCH "\"figure\": *\"chain\"")
afb_cli_test(resolve_unknown 1 ARGS resolve --base . no_such_entity MATCH "no_such_entity")

# afb golden: determinism, input-change detection, and a pose difference that names the joints.
add_test(NAME cli.golden_behaviour
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/golden_behaviour" -P ${CMAKE_CURRENT_LIST_DIR}/golden.cmake)
# The project's own goldens (tests/golden/*.json) must hold.
# afb golden compare --junit and --report: the JUnit file against tests/cli/junit.xsd (with xmllint), the Markdown
# summary and the pictures of failing goldens; and the CI recipe's steps (examples/ci/goldens.sh).
find_program(AFB_XMLLINT xmllint)
foreach(_t golden_report ci_recipe)
  add_test(NAME cli.${_t}
    COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DCHECK=$<TARGET_FILE:afb_picture_check>"
            "-DXMLLINT=${AFB_XMLLINT}" "-DSCHEMA=${CMAKE_CURRENT_LIST_DIR}/junit.xsd" "-DSRC=${PROJECT_SOURCE_DIR}"
            "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/${_t}" -P ${CMAKE_CURRENT_LIST_DIR}/${_t}.cmake)
endforeach()
file(GLOB _afb_goldens CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/golden/*.json)
if(_afb_goldens)
  afb_cli_test(golden_compare 0 ARGS golden compare ${_afb_goldens})
endif()
# afb gen: a content folder from the bundled humanoid's mesh that inspect, fmt --check and drop accept.
add_test(NAME cli.gen_humanoid
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/gen_humanoid" -P ${CMAKE_CURRENT_LIST_DIR}/gen.cmake)
# afb drop: the spawn pose with --steps 0, a JSON report, and a real drop of the bundled chain.
afb_cli_test(drop_chain 0 ARGS drop --base . chain --seconds 2 MATCH "chain" "Bullet 3")
afb_cli_test(drop_json 0 ARGS drop --base . chain --steps 0 --json - MATCH "\"steps\": 0" "\"final_pose\"" "\"us_per_step\"")
afb_cli_test(drop_double 0 ARGS drop --base . chain --seconds 1 --precision double MATCH "\\(double\\)")
afb_cli_test(drop_unknown 1 ARGS drop --base . no_such_entity MATCH "no_such_entity")
# A figure put to rest by its rules before it touched anything is said to be frozen in the air; a figure hung from
# the world (the chain) rests in the air by design and is not.
add_test(NAME cli.drop_frozen_in_air
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/drop_frozen_in_air" -P ${CMAKE_CURRENT_LIST_DIR}/frozen.cmake)
afb_cli_test(drop_hung_not_frozen 0 ARGS drop --base . chain --height 1000 --seconds 12 --json -
             MATCH "\"frozen_before_contact\": 0" "\"settle_time_s\": [0-9]")
# Entities that share a figure are told apart in the table: each row names its entity, then the figure.
afb_cli_test(drop_entity_rows 0 ARGS drop --base . humanoid humanoid_sleeping --steps 1
             MATCH "humanoid +15 +1 " "humanoid_sleeping \\(humanoid\\) +15 +1 ")
# afb track: its JSON and CSV reports, a hit, and bad input refused.
add_test(NAME cli.track
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/track" -P ${CMAKE_CURRENT_LIST_DIR}/track.cmake)
# afb drop --lod: the humanoid at six rigid bodies, recorded in the report; refused where it cannot apply.
afb_cli_test(drop_lod 0 ARGS drop --base . humanoid --steps 30 --lod 6 --json -
             MATCH "6 rigid bodies for 15 bodies" "\"lod_bodies\": 6" "\"lod\": 6")
afb_cli_test(drop_lod_raw 2 ARGS drop --base . humanoid --steps 1 --lod 6 --method raw MATCH "--lod needs the rigid")
afb_cli_test(drop_lod_help 0 ARGS drop --help MATCH "--lod")
# afb drop --motor-hz: instances holding their load pose with joint motors, recorded in the report; refused where
# motors cannot run, and a damping ratio without a frequency.
afb_cli_test(drop_motors 0 ARGS drop --base . humanoid --steps 30 --motor-hz 6 --json -
             MATCH "joint motors: 6 Hz, damping ratio 1," "\"motor_hz\": 6" "\"motor_damping_ratio\": 1")
afb_cli_test(drop_motors_raw 2 ARGS drop --base . humanoid --steps 1 --motor-hz 6 --method raw
             MATCH "--motor-hz needs the rigid")
afb_cli_test(drop_motor_damping_alone 2 ARGS drop --base . humanoid --steps 1 --motor-damping 0.5
             MATCH "--motor-damping needs --motor-hz")
afb_cli_test(inspect_chain 0 ARGS inspect --base . chain MATCH "figure chain: 10 bodies, 10 constraints, 11 md5 joints")
# An af_pose whose hierarchy differs from the mesh's (link5's parent) is reported at the af_pose's line of the joint,
# naming the mesh's line of it.
afb_cli_test(inspect_hierarchy_location 1 ARGS inspect --af af/chain.af --mesh models/md5/props/chain/chain.md5mesh
             --pose tests/cli/data/chain_reparented.md5anim
             MATCH "tests/cli/data/chain_reparented.md5anim:15:2: error: af_pose does not match the mesh hierarchy"
                   "joint 5 \"link5\" has parent 3 in the anim but 4 in the mesh \\(the mesh's joint 5: models/md5/props/chain/chain.md5mesh:13:2\\)")

# afb draw: the humanoid as PNG and SVG, checked by afb_picture_check (signature, size, not blank; SVG parses), and
# the drop pose at --at 0 drawn like the load pose.
pkg_check_modules(AFB_EXPAT REQUIRED IMPORTED_TARGET expat)
add_executable(afb_picture_check ${CMAKE_CURRENT_LIST_DIR}/picture_check.cpp)
target_link_libraries(afb_picture_check PRIVATE PkgConfig::AFB_CAIRO PkgConfig::AFB_EXPAT)
afb_warnings(afb_picture_check)
add_test(NAME cli.draw_humanoid
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DAFB_DOUBLE=$<TARGET_FILE:afb-double>"
          "-DCHECK=$<TARGET_FILE:afb_picture_check>"
          "-DSRC=${PROJECT_SOURCE_DIR}" "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/draw_humanoid"
          -P ${CMAKE_CURRENT_LIST_DIR}/draw.cmake)
afb_cli_test(draw_views 0 ARGS draw --base . chain --view top,front --show bodies,joints
             --out ${CMAKE_CURRENT_BINARY_DIR}/draw_chain.svg MATCH "chain \\(load pose\\)")
afb_cli_test(draw_bad_extension 2 ARGS draw --base . chain --out ${CMAKE_CURRENT_BINARY_DIR}/chain.jpg
             MATCH "must be a .png or .svg file")
afb_cli_test(draw_unknown 1 ARGS draw --base . no_such_entity --out ${CMAKE_CURRENT_BINARY_DIR}/none.png
             MATCH "no_such_entity")

# afb drop --gltf: replays that the Khronos glTF validator passes with zero errors (skipped without node and the
# validator, except under CI), and the option's own errors.
find_program(AFB_NODE node)
add_test(NAME cli.drop_gltf
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DAFB_DOUBLE=$<TARGET_FILE:afb-double>" "-DNODE=${AFB_NODE}"
          "-DSRC=${PROJECT_SOURCE_DIR}" "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/drop_gltf"
          -P ${CMAKE_CURRENT_LIST_DIR}/gltf.cmake)
set_tests_properties(cli.drop_gltf PROPERTIES SKIP_REGULAR_EXPRESSION "validation skipped")
afb_cli_test(drop_gltf_extension 2 ARGS drop --base . chain --steps 1 --gltf ${CMAKE_CURRENT_BINARY_DIR}/chain.gltf
             MATCH "--gltf must name a .glb file")
afb_cli_test(drop_gltf_one_entity 2 ARGS drop --base . chain humanoid --steps 1
             --gltf ${CMAKE_CURRENT_BINARY_DIR}/two.glb MATCH "--gltf records one entity")
afb_cli_test(drop_gltf_unwritable 1 ARGS drop --base . chain --steps 1
             --gltf ${CMAKE_CURRENT_BINARY_DIR}/no/such/folder/chain.glb MATCH "assimp could not write")

# afb chart: a 2-method matrix on the chain, its CSV, summary and (with gnuplot) its pictures; bad method specs.
find_program(AFB_GNUPLOT gnuplot)
add_test(NAME cli.chart_matrix
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DCHECK=$<TARGET_FILE:afb_picture_check>"
          "-DSRC=${PROJECT_SOURCE_DIR}" "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/chart_matrix" "-DGNUPLOT=${AFB_GNUPLOT}"
          -P ${CMAKE_CURRENT_LIST_DIR}/chart.cmake)
afb_cli_test(chart_unknown_method 2 ARGS chart --base . chain --methods raw,nonsense --out ${CMAKE_CURRENT_BINARY_DIR}/x
             MATCH "unknown method nonsense")
afb_cli_test(chart_raw_technique 2 ARGS chart --base . chain --methods raw:position-iterations=2
             --out ${CMAKE_CURRENT_BINARY_DIR}/x MATCH "raw \\(plain Bullet\\) has no position-iterations")
# afb stress: a 2 × 2 matrix, its table, Markdown, JSON and heat map; bad names.
add_test(NAME cli.stress_matrix
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DCHECK=$<TARGET_FILE:afb_picture_check>"
          "-DSRC=${PROJECT_SOURCE_DIR}" "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/stress_matrix" "-DGNUPLOT=${AFB_GNUPLOT}"
          -P ${CMAKE_CURRENT_LIST_DIR}/stress.cmake)
afb_cli_test(stress_unknown_scenario 2 ARGS stress --scenarios nonsense --out ${CMAKE_CURRENT_BINARY_DIR}/x
             MATCH "unknown scenario 'nonsense'")
afb_cli_test(stress_list 0 ARGS stress --list MATCH "humanoid-pile-160")
afb_cli_test(drop_raw 0 ARGS drop --base . chain --seconds 1 --method raw MATCH "method raw \\(" "chain")
afb_cli_test(drop_raw_technique 2 ARGS drop --base . chain --method raw --speculative-limits on
             MATCH "has no speculative-limits")

# Reports on stdout: `--json -` and `--csv -` leave stdout to the document alone (parsed and checked).
add_test(NAME cli.drop_report_stdout
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/drop_report_stdout" -P ${CMAKE_CURRENT_LIST_DIR}/streams.cmake)
# Every JSON report names its schema and version; golden compare refuses a newer one.
add_test(NAME cli.report_schemas
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" "-DSRC=${PROJECT_SOURCE_DIR}"
          "-DTMP=${CMAKE_CURRENT_BINARY_DIR}/report_schemas" -P ${CMAKE_CURRENT_LIST_DIR}/schemas.cmake)
# Exit codes: 0 success, 1 a failed check or bad input, 2 a command line that makes no sense; misspelt names get
# the nearest valid one.
afb_cli_test(exit_success 0 ARGS drop --base . chain --steps 5 MATCH "chain +10 +5 ")
afb_cli_test(usage_unknown_command 2 ARGS dorp MATCH "^afb: unknown command 'dorp'; did you mean 'drop'\\?")
afb_cli_test(usage_unknown_subcommand 2 ARGS golden recrod x.json
             MATCH "afb golden: unknown command 'recrod'; did you mean 'record'\\?")
afb_cli_test(usage_no_command 2 MATCH "afb: no command given \\(parse, fmt, ")
afb_cli_test(usage_unknown_option 2 ARGS drop --base . chain --bogus-flag
             MATCH "afb drop: unknown option '--bogus-flag'")
afb_cli_test(usage_misspelt_option 2 ARGS drop --base . chain --coutn 2 MATCH "did you mean '--count'\\?")
afb_cli_test(usage_missing_value 2 ARGS drop --base . chain --json MATCH "afb drop: --json")
afb_cli_test(usage_count_zero 2 ARGS drop --base . chain --count 0 MATCH "afb drop: --count: Value 0 not in range")
afb_cli_test(usage_count_negative 2 ARGS drop --base . chain --count -3 MATCH "--count: Value -3 not in range")
afb_cli_test(usage_count_text 2 ARGS drop --base . chain --count many MATCH "--count")
afb_cli_test(usage_height_negative 2 ARGS drop --base . chain --height -1 MATCH "--height: Value -1 is not")
afb_cli_test(usage_hz_zero 2 ARGS drop --base . chain --hz 0 MATCH "--hz: Value 0 is not a positive number")
afb_cli_test(usage_hz_nan 2 ARGS drop --base . chain --hz nan MATCH "--hz: Value nan is not")
afb_cli_test(usage_seconds_negative 2 ARGS drop --base . chain --seconds -2 MATCH "--seconds: Value -2 is not")
afb_cli_test(usage_too_many_steps 2 ARGS drop --base . chain --seconds 1e9 --hz 1000
             MATCH "--seconds 1e\\+?0*9 at --hz 1000: more steps than a run can count")
afb_cli_test(usage_steps_negative 2 ARGS drop --base . chain --steps -1 MATCH "--steps")
afb_cli_test(usage_method_misspelt 2 ARGS drop --base . chain --method defualt
             MATCH "unknown method 'defualt'; did you mean 'default'\\?")
afb_cli_test(usage_knob_value 2 ARGS drop --base . chain --substeps lots MATCH "--substeps: Value lots: not an integer")
afb_cli_test(usage_golden_hz 2 ARGS golden record --base . chain --out ${CMAKE_CURRENT_BINARY_DIR}/x.json --hz -60
             MATCH "afb golden record: --hz: Value -60 is not a positive number")
afb_cli_test(usage_draw_height 2 ARGS draw --base . chain --out ${CMAKE_CURRENT_BINARY_DIR}/x.png --height -1
             MATCH "afb draw: --height")
afb_cli_test(usage_chart_heights 2 ARGS chart --base . chain --heights 1,-1 --out ${CMAKE_CURRENT_BINARY_DIR}/x
             MATCH "--heights: Value -1 is not in \\[0 - 10000\\]")
afb_cli_test(usage_chart_method_misspelt 2 ARGS chart --base . chain --methods raw,defualt
             --out ${CMAKE_CURRENT_BINARY_DIR}/x MATCH "did you mean 'default'\\?")
afb_cli_test(usage_chart_knob_misspelt 2 ARGS chart --base . chain --methods raw:substep=2
             --out ${CMAKE_CURRENT_BINARY_DIR}/x MATCH "did you mean 'substeps'\\?")
afb_cli_test(usage_stress_scenario_misspelt 2 ARGS stress --scenarios tiny-bodie --out ${CMAKE_CURRENT_BINARY_DIR}/x
             MATCH "unknown scenario 'tiny-bodie'; did you mean 'tiny-bodies'\\?")
afb_cli_test(usage_stress_mitigation_misspelt 2 ARGS stress --methods default+stabilise --scenarios tiny-bodies
             --out ${CMAKE_CURRENT_BINARY_DIR}/x MATCH "did you mean 'stabilize'\\?")
afb_cli_test(usage_inspect_af_alone 2 ARGS inspect --af af/chain.af MATCH "--af needs --mesh and --pose")
afb_cli_test(drop_entity_misspelt 1 ARGS drop --base . humanoidd
             MATCH "entityDef 'humanoidd' not found; did you mean 'humanoid'\\?")
afb_cli_test(resolve_entity_misspelt 1 ARGS resolve --base . chian MATCH "did you mean 'chain'\\?")
afb_cli_test(inspect_entity_misspelt 1 ARGS inspect --base . --json lampp MATCH "did you mean 'lamp'\\?")
afb_cli_test(golden_not_a_golden_file 1 ARGS golden compare README.md MATCH "README.md: error: not a golden file")
afb_cli_test(help_exit 0 ARGS drop --help MATCH "--count INT:INT in \\[1 - 1048576\\]" "--hz FLOAT:POSITIVE"
             "afb drop --base \\. humanoid --method fast" "--substeps INT" "--split-impulse on\\|off")
# Every command's help starts with examples of it (the commands read from afb --help).
add_test(NAME cli.help_examples
  COMMAND ${CMAKE_COMMAND} "-DAFB=$<TARGET_FILE:afb>" -P ${CMAKE_CURRENT_LIST_DIR}/help_examples.cmake)
# afb methods: every method with its summary and every knob with its values and default; one method's knobs, those
# that differ from the default marked; JSON; a misspelt method.
afb_cli_test(methods_list 0 ARGS methods MATCH "  fast +the default's direct joint solve in block mode" "  raw +plain Bullet"
             "  substeps +INT +1 +Substeps per frame" "  split-impulse +on\\|off +on ")
afb_cli_test(methods_one 0 ARGS methods fast MATCH "  figure-iterations +2 +\\(default: 0\\)" "  substeps +1\n")
afb_cli_test(methods_json 0 ARGS methods fast --json MATCH "\"name\": \"fast\"" "\"position-tree\": \"1\"")
afb_cli_test(methods_misspelt 2 ARGS methods fsat MATCH "unknown method 'fsat'; did you mean 'fast'\\?")
# The drop table: bodies per instance, a legend, and the method as chart and stress spell it.
afb_cli_test(drop_table_legend 0 ARGS drop --base . humanoid --count 2 --steps 2 --method fast --iterations 8
             MATCH "method fast:iterations=8 \\(every knob: --verbose" "\nhumanoid +15 +2 "
             "bodies: per instance")
afb_cli_test(drop_verbose 0 ARGS drop --base . chain --steps 2 --verbose
             MATCH "method default \\(backend rigid, substeps 1, ")

# The bundled content is generated: re-running the generator must reproduce the committed files byte for byte.
if(TARGET afb_gen_content)
  add_test(NAME cli.content_reproducible
           COMMAND ${CMAKE_COMMAND} -DGEN=$<TARGET_FILE:afb_gen_content> -DSOURCE=${PROJECT_SOURCE_DIR}
                   -DWORK=${CMAKE_CURRENT_BINARY_DIR}/content_check
                   -P ${PROJECT_SOURCE_DIR}/tests/cli/content.cmake)
endif()

# The smoke matrix (cmake/smoke.sh): every afb command x every preset x the options that change code paths, in short
# runs; each must end with exit 0, 1 or 2, never by a signal.
add_test(NAME smoke.matrix
  COMMAND bash ${PROJECT_SOURCE_DIR}/cmake/smoke.sh $<TARGET_FILE:afb> ${CMAKE_CURRENT_BINARY_DIR}/smoke
  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(smoke.matrix PROPERTIES TIMEOUT 900)

# afb plan, run and merge: merged outputs equal the one-process commands' (timings aside), missing results named,
# --resume, a run killed midway, refused results and inputs; GNU parallel when installed (tests/cli/batch.sh).
find_program(AFB_BASH bash)
if(AFB_BASH)
  add_test(NAME cli.batch
    COMMAND ${AFB_BASH} ${CMAKE_CURRENT_LIST_DIR}/batch.sh $<TARGET_FILE:afb> ${PROJECT_SOURCE_DIR}
            ${CMAKE_CURRENT_BINARY_DIR}/batch)
endif()
