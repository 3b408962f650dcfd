# cmake -P test of `afb golden compare --junit` and `--report` (AFB, CHECK: afb_picture_check, XMLLINT: xmllint or
# empty, SCHEMA: tests/cli/junit.xsd, SRC, TMP given). Goldens of the bundled chain: one that holds, one whose
# recorded pose has two joints moved half a metre, one whose tolerance is below zero (it fails with the pose as
# recorded: its picture shows the two poses as one), a file that is not a golden, and one whose entity's name XML
# must escape. The JUnit file validates against the schema and counts them; the failure names the moved joints; the
# report has a summary and a picture per golden whose pose failed, and the moved golden's picture differs from the
# one whose poses coincide.
file(REMOVE_RECURSE "${TMP}")
file(MAKE_DIRECTORY "${TMP}")
file(COPY "${SRC}/af" "${SRC}/def" "${SRC}/models" DESTINATION "${TMP}")
include("${CMAKE_CURRENT_LIST_DIR}/run.cmake")

run_to(0 out "${AFB}" golden record --base "${TMP}" chain --out "${TMP}/pass.json" --seconds 2)
file(READ "${TMP}/pass.json" golden)
# Two joints of the recorded pose put half a metre away from where the chain hangs.
string(JSON name_4 GET "${golden}" pose 4 joint)
string(JSON name_6 GET "${golden}" pose 6 joint)
string(JSON moved SET "${golden}" pose 4 position 0 "0.5")
string(JSON moved SET "${moved}" pose 6 position 0 "-0.5")
file(WRITE "${TMP}/moved.json" "${moved}")
string(JSON same SET "${golden}" tolerance position_m "-1")
file(WRITE "${TMP}/same.json" "${same}")
file(WRITE "${TMP}/broken.json" "{}")
# An entity whose name XML must escape (and a control character XML 1.0 cannot hold): an error, still valid XML.
string(JSON odd SET "${golden}" entity "\"ch<a>i&n'\\u0001\"")
file(WRITE "${TMP}/odd.json" "${odd}")

set(report "${TMP}/report")
run_to(1 out "${AFB}" golden compare --junit "${TMP}/junit.xml" --report "${report}"
       "${TMP}/pass.json" "${TMP}/moved.json" "${TMP}/same.json" "${TMP}/broken.json" "${TMP}/odd.json")
if(NOT out MATCHES "ok   [^\n]*pass.json" OR NOT out MATCHES "FAIL [^\n]*moved.json")
  message(FATAL_ERROR "compare's lines are not as expected:\n${out}")
endif()

# The JUnit file: the schema, the counts, one test case per golden, the failure naming the moved joints.
file(READ "${TMP}/junit.xml" xml)
if(XMLLINT)
  run_to(0 lint "${XMLLINT}" --noout --schema "${SCHEMA}" "${TMP}/junit.xml")
elseif(DEFINED ENV{CI})
  message(FATAL_ERROR "no xmllint: CI must validate the JUnit report (cmake/install-deps.sh installs it)")
else()
  message(STATUS "JUnit schema validation skipped: no xmllint")
endif()
foreach(re "<testsuites [^>]*tests=\"5\" failures=\"2\" errors=\"2\""
           "<testsuite [^>]*tests=\"5\" failures=\"2\" errors=\"2\""
           "<testcase name=\"[^\"]*pass.json\" classname=\"afb.golden.chain\"[^>]*/>"
           "<testcase name=\"[^\"]*moved.json\"[^>]*>\n *<failure message=\"2 joints past tolerance [^\"]*: ${name_4}, ${name_6}\""
           "<testcase name=\"[^\"]*broken.json\"[^>]*>\n *<error message=\"[^\"]*not a golden file"
           "classname=\"afb.golden.ch&lt;a&gt;i&amp;n&apos;\\?\"")
  if(NOT xml MATCHES "${re}")
    message(FATAL_ERROR "the JUnit report does not match '${re}':\n${xml}")
  endif()
endforeach()
string(REGEX MATCHALL "<testcase " cases "${xml}")
list(LENGTH cases n)
if(NOT n EQUAL 5)
  message(FATAL_ERROR "${n} test cases, expected 5:\n${xml}")
endif()

# The Markdown summary and the pictures: one per failing golden that ran, none for the others.
file(READ "${report}/summary.md" md)
foreach(re "5 goldens: 1 passed, 2 failed, 2 could not be compared" "\\| [^|]*pass.json \\| chain \\| ok \\|" "\\*\\*FAIL\\*\\*"
           "\\*\\*ERROR\\*\\*" "!\\[[^]]*\\]\\(moved.png\\)" "${name_4} moved 0\\.[0-9]+ m")
  if(NOT md MATCHES "${re}")
    message(FATAL_ERROR "the summary does not match '${re}':\n${md}")
  endif()
endforeach()
foreach(f moved same)
  if(NOT EXISTS "${report}/${f}.png")
    message(FATAL_ERROR "no picture ${report}/${f}.png")
  endif()
  run_to(0 out "${CHECK}" png "${report}/${f}.png")
endforeach()
if(EXISTS "${report}/pass.png" OR EXISTS "${report}/broken.png")
  message(FATAL_ERROR "a picture of a golden that did not fail on its pose")
endif()
run_to(1 out "${CHECK}" same "${report}/moved.png" "${report}/same.png" 80 0)

# --junit -: stdout holds the XML alone; the lines for people go to stderr.
execute_process(COMMAND "${AFB}" golden compare --junit - "${TMP}/pass.json"
                RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT rc EQUAL 0 OR NOT stdout MATCHES "^<\\?xml " OR stdout MATCHES "ok   " OR NOT stderr MATCHES "ok   ")
  message(FATAL_ERROR "--junit -: exit ${rc}\nstdout:\n${stdout}\nstderr:\n${stderr}")
endif()

# A report folder that cannot be made (a file is in the way) is bad input: exit 1, saying so.
run_to(1 out "${AFB}" golden compare --report "${TMP}/pass.json/report" "${TMP}/pass.json")
if(NOT out MATCHES "--report [^\n]*pass.json/report: ")
  message(FATAL_ERROR "an impossible report folder was not reported:\n${out}")
endif()
