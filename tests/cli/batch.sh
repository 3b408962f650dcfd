#!/usr/bin/env bash
# cli.batch: afb plan, run and merge against the one-process commands. A stress matrix run line by line and a
# chart run in two shards merge into the command's own outputs (timings aside); a missing result is named and
# --resume runs it alone; a run killed midway (SIGKILL) leaves no result file; results of another build, another
# plan or changed inputs are refused; golden compare in two shards, one golden failing, merged into compare's
# JUnit file, report and exit code; the GNU parallel recipe of docs/cluster.md (when parallel is installed).
# Arguments: AFB (the afb binary), SRC (repository root), TMP (scratch folder).
set -euo pipefail
afb="$1" src="$2" tmp="$3"
. "$(dirname "${BASH_SOURCE[0]}")/batch-lib.sh"
rm -rf "$tmp"
mkdir -p "$tmp"
cd "$src"

# --- stress: 1 scenario x 2 methods x 2 yaws, four processes, merged equal to afb stress -----------------------
opts=(--methods fast,default --scenarios tiny-bodies --yaws 2)
"$afb" stress "${opts[@]}" --out "$tmp/stress-one" > "$tmp/stress-one.txt"
"$afb" plan stress "${opts[@]}" --manifest "$tmp/stress.jsonl" 2> "$tmp/plan.txt"
[ "$(grep -c . "$tmp/stress.jsonl")" -eq 4 ] || fail "afb plan stress: expected 4 lines"
grep -q "4 runs of afb stress" "$tmp/plan.txt" || fail "afb plan did not say how many runs: $(cat "$tmp/plan.txt")"
grep -q '"scenario":"tiny-bodies"' "$tmp/stress.jsonl" || fail "a stress line does not name its scenario"
for i in 3 1 0 2; do "$afb" run --manifest "$tmp/stress.jsonl" --index $i --out "$tmp/stress-res" > /dev/null; done
"$afb" merge "$tmp/stress-res" --out "$tmp/stress-merged" > "$tmp/merge.txt"
same_stress "$tmp/stress-one" "$tmp/stress-merged"
# The merge prints the command's table.
grep -q "tiny-bodies" "$tmp/merge.txt" || fail "afb merge printed no table"

# A missing result is named on stderr (exit 1); --resume runs only it; the merge is then complete again.
rm "$tmp/stress-res/run-000002.json"
set +e
"$afb" merge "$tmp/stress-res" --out "$tmp/stress-merged2" --manifest "$tmp/stress.jsonl" 2> "$tmp/missing.txt"
rc=$?
set -e
[ $rc -eq 1 ] || fail "afb merge with a missing result: exit $rc, expected 1"
grep -q "1 of 4 results missing in .*: 2$" "$tmp/missing.txt" || fail "missing index not named: $(cat "$tmp/missing.txt")"
grep -q "afb run --manifest $tmp/stress.jsonl --resume" "$tmp/missing.txt" || fail "no --resume hint"
"$afb" run --manifest "$tmp/stress.jsonl" --resume --out "$tmp/stress-res" > "$tmp/resume.txt"
[ "$(grep -c "^afb run: " "$tmp/resume.txt")" -eq 1 ] || fail "--resume ran more than the missing run"
grep -q "^afb run: 2/4 " "$tmp/resume.txt" || fail "--resume did not run index 2: $(cat "$tmp/resume.txt")"
"$afb" merge "$tmp/stress-res" --out "$tmp/stress-merged2" > /dev/null
same_stress "$tmp/stress-one" "$tmp/stress-merged2"

# A result of another build is refused, naming the file.
cp -r "$tmp/stress-res" "$tmp/stress-other"
sed -i 's/"build":"afb /"build":"afb 0.0.0-other /' "$tmp/stress-other/run-000001.json"
set +e
"$afb" merge "$tmp/stress-other" --out "$tmp/x" 2> "$tmp/other.txt"
rc=$?
set -e
[ $rc -eq 1 ] || fail "a result of another build: exit $rc, expected 1"
grep -q "run-000001.json: error: made by another build" "$tmp/other.txt" || fail "$(cat "$tmp/other.txt")"
# A result that found other input files than the plan's is refused; so are results of another manifest's plan.
cp -r "$tmp/stress-res" "$tmp/stress-seen"
sed -i -E 's/"inputs_seen":"[0-9a-f]{16}"/"inputs_seen":"0123456789abcdef"/' "$tmp/stress-seen/run-000003.json"
set +e
"$afb" merge "$tmp/stress-seen" --out "$tmp/x" 2> "$tmp/seen.txt"
rc1=$?
"$afb" merge "$tmp/stress-res" --out "$tmp/x" --manifest "$tmp/plan.txt" 2> /dev/null
rc2=$?
"$afb" plan stress --methods fast,default --scenarios tiny-bodies --yaws 3 --manifest "$tmp/stress3.jsonl" 2> /dev/null
"$afb" merge "$tmp/stress-res" --out "$tmp/x" --manifest "$tmp/stress3.jsonl" 2> "$tmp/manifest3.txt"
rc3=$?
set -e
[ $rc1 -eq 1 ] && grep -q "run-000003.json: error: ran on input files other than the plan's" "$tmp/seen.txt" ||
  fail "a result of other inputs: exit $rc1: $(cat "$tmp/seen.txt")"
[ $rc2 -eq 1 ] && [ $rc3 -eq 1 ] && grep -q "stress3.jsonl: error: the results in .* are not of this manifest's plan" \
  "$tmp/manifest3.txt" || fail "results of another manifest: exits $rc2 $rc3: $(cat "$tmp/manifest3.txt")"

# Command lines that make no sense: exit 2.
set +e
env -u SLURM_ARRAY_TASK_ID "$afb" run --manifest "$tmp/stress.jsonl" --out "$tmp/x" 2> /dev/null
rc1=$?
"$afb" run --manifest "$tmp/stress.jsonl" --index 4 --out "$tmp/x" 2> "$tmp/past.txt"
rc2=$?
"$afb" run --manifest "$tmp/stress.jsonl" --shard 2/2 --out "$tmp/x" 2> /dev/null
rc3=$?
set -e
[ $rc1 -eq 2 ] && [ $rc2 -eq 2 ] && [ $rc3 -eq 2 ] || fail "bad selections: exits $rc1 $rc2 $rc3, expected 2"
grep -q "has 4 runs (0..3)" "$tmp/past.txt" || fail "--index past the end: $(cat "$tmp/past.txt")"
# SLURM_ARRAY_TASK_ID selects the line when no option does.
SLURM_ARRAY_TASK_ID=1 "$afb" run --manifest "$tmp/stress.jsonl" --out "$tmp/slurm-env" > /dev/null
[ "$(cd "$tmp/slurm-env" && ls run-*)" = "run-000001.json" ] || fail "SLURM_ARRAY_TASK_ID=1 wrote $(ls "$tmp/slurm-env")"
# Beside the results, the plan they name: the merge needs no manifest.
[ "$(cd "$tmp/slurm-env" && ls plan-*.json | wc -l)" -eq 1 ] || fail "afb run left no plan file beside its result"

# --- chart: 1 figure x 2 methods x 2 repeats in two shards, on a copy of the content ---------------------------
mkdir -p "$tmp/content"
cp -r af def models "$tmp/content/"
copts=(--base "$tmp/content" chain --methods fast,default --heights 1 --repeats 2 --seconds 1)
"$afb" chart "${copts[@]}" --threads 1 --out "$tmp/chart-one" > /dev/null
"$afb" plan chart "${copts[@]}" --manifest "$tmp/chart.jsonl" 2> /dev/null
"$afb" run --manifest "$tmp/chart.jsonl" --shard 0/2 --out "$tmp/chart-res" > /dev/null
"$afb" run --manifest "$tmp/chart.jsonl" --shard 1/2 --threads 2 --out "$tmp/chart-res" > /dev/null
"$afb" merge "$tmp/chart-res" --out "$tmp/chart-merged" > /dev/null
diff <(csv_untimed "$tmp/chart-one/runs.csv") <(csv_untimed "$tmp/chart-merged/runs.csv") ||
  fail "chart runs.csv differs (timing aside)"
# A stress result among the chart's is from another plan.
cp "$tmp/stress-res/run-000000.json" "$tmp/chart-res/run-000000.json"
set +e
"$afb" merge "$tmp/chart-res" --out "$tmp/x" 2> "$tmp/plan-mix.txt"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "run-000000.json: error: from another plan" "$tmp/plan-mix.txt" ||
  fail "a result of another plan: exit $rc: $(cat "$tmp/plan-mix.txt")"
# An input changed since planning: the run refuses, naming the file.
echo "// changed" >> "$tmp/content/af/chain.af"
set +e
"$afb" run --manifest "$tmp/chart.jsonl" --index 0 --out "$tmp/x" 2> "$tmp/changed.txt"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "af/chain.af: error: input changed since planning" "$tmp/changed.txt" ||
  fail "changed input: exit $rc: $(cat "$tmp/changed.txt")"

# --- drop: a run killed midway leaves no result; --resume completes it; the merge equals afb drop --------------
dopts=(--base . humanoid chain --seconds 4 --count 2)
"$afb" drop "${dopts[@]}" --json "$tmp/drop-one.json" --csv "$tmp/drop-one.csv" > /dev/null
"$afb" plan drop "${dopts[@]}" --manifest "$tmp/drop.jsonl" 2> /dev/null
"$afb" run --manifest "$tmp/drop.jsonl" --index 1 --out "$tmp/drop-res" > /dev/null
"$afb" run --manifest "$tmp/drop.jsonl" --index 0 --out "$tmp/drop-res" > /dev/null &
victim=$!
sleep 0.3
kill -0 $victim 2> /dev/null || fail "the run ended before it could be killed (make it longer)"
kill -KILL $victim
wait $victim 2> /dev/null || true
[ ! -e "$tmp/drop-res/run-000000.json" ] || fail "a killed run left a result file"
set +e
"$afb" merge "$tmp/drop-res" --out "$tmp/drop-merged" 2> "$tmp/killed.txt"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "1 of 2 results missing in .*: 0$" "$tmp/killed.txt" ||
  fail "the killed run is not named missing: $(cat "$tmp/killed.txt")"
"$afb" run --manifest "$tmp/drop.jsonl" --resume --out "$tmp/drop-res" > /dev/null
"$afb" merge "$tmp/drop-res" --out "$tmp/drop-merged" > "$tmp/drop-table.txt"
diff <(csv_untimed "$tmp/drop-one.csv") <(csv_untimed "$tmp/drop-merged/drop.csv") || fail "drop.csv differs"
diff <(json_untimed "$tmp/drop-one.json") <(json_untimed "$tmp/drop-merged/drop.json") || fail "drop.json differs"
grep -q "^humanoid " "$tmp/drop-table.txt" || fail "afb merge printed no drop table"

# A plan of the other precision is run and merged by afb-double, started by afb itself.
"$afb" plan drop --base . chain --steps 5 --precision double --manifest "$tmp/double.jsonl" 2> /dev/null
grep -q '"precision":"double"' "$tmp/double.jsonl" || fail "afb plan --precision double did not plan for double"
"$afb" run --manifest "$tmp/double.jsonl" --index 0 --out "$tmp/double-res" > /dev/null
"$afb" merge "$tmp/double-res" --out "$tmp/double-merged" > "$tmp/double.txt"
grep -q "Bullet 3.[0-9]* (double)" "$tmp/double.txt" || fail "the double plan was not merged by afb-double"

# --- golden compare: four goldens in two shards, one perturbed so that it fails, one not a golden file ----------
mkdir -p "$tmp/gcontent" "$tmp/golden"
cp -r af def models "$tmp/gcontent/"
"$afb" golden record --base "$tmp/gcontent" chain --out "$tmp/golden/chain.json" --seconds 1 > /dev/null
"$afb" golden record --base "$tmp/gcontent" chain --out "$tmp/golden/high.json" --seconds 1 --height 2 > /dev/null
# The fifth joint's recorded x put at 0.5 m: the chain does not hang there.
awk '/"pose": \[/ { pose = 1 }
  { line = $0 }
  pose && prev ~ /"position": \[/ && ++n == 5 { sub(/-?[0-9][0-9.e+-]*/, "0.5", line) }
  { print line; prev = $0 }' "$tmp/golden/chain.json" > "$tmp/golden/moved.json"
cmp -s "$tmp/golden/chain.json" "$tmp/golden/moved.json" && fail "the perturbed golden equals its original"
echo '{}' > "$tmp/golden/broken.json"
goldens=("$tmp/golden/chain.json" "$tmp/golden/moved.json" "$tmp/golden/broken.json" "$tmp/golden/high.json")
set +e
"$afb" golden compare --exact --junit "$tmp/golden-one.xml" --report "$tmp/golden-one" "${goldens[@]}" \
  > "$tmp/golden-one.txt" 2> "$tmp/golden-one.err"
rc_one=$?
set -e
"$afb" plan golden compare --exact --junit "$tmp/golden-merged.xml" --report "$tmp/golden-merged" "${goldens[@]}" \
  --manifest "$tmp/golden.jsonl" 2> /dev/null
[ "$(grep -c . "$tmp/golden.jsonl")" -eq 4 ] || fail "afb plan golden compare: expected 4 lines"
"$afb" run --manifest "$tmp/golden.jsonl" --shard 1/2 --out "$tmp/golden-res" > /dev/null
# A missing golden is named like any missing run.
set +e
"$afb" merge "$tmp/golden-res" 2> "$tmp/golden-missing.txt" > /dev/null
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "2 of 4 results missing in .*: 0, 2$" "$tmp/golden-missing.txt" ||
  fail "missing goldens not named: exit $rc: $(cat "$tmp/golden-missing.txt")"
"$afb" run --manifest "$tmp/golden.jsonl" --shard 0/2 --threads 2 --out "$tmp/golden-res" > /dev/null
set +e
"$afb" merge "$tmp/golden-res" > "$tmp/golden-merged.txt" 2> "$tmp/golden-merged.err"
rc_merged=$?
set -e
[ $rc_one -eq 1 ] && [ $rc_merged -eq 1 ] || fail "a failing golden: compare exit $rc_one, merge exit $rc_merged"
grep -q "^FAIL .*moved.json" "$tmp/golden-merged.txt" || fail "the merge did not report moved.json failing"
grep -q "^ok   .*high.json" "$tmp/golden-merged.txt" || fail "the merge did not report high.json passing"
# The JUnit file equal but for its time attributes; the summary and the failing pose's picture byte for byte; the
# lines on stdout and stderr equal but for where the reports went.
diff <(sed -E 's/ time="[0-9.]+"//' "$tmp/golden-one.xml") <(sed -E 's/ time="[0-9.]+"//' "$tmp/golden-merged.xml") ||
  fail "the merged JUnit file differs (timing aside)"
cmp "$tmp/golden-one/summary.md" "$tmp/golden-merged/summary.md" || fail "the merged summary.md differs"
[ "$(cd "$tmp/golden-merged" && ls)" = "$(printf 'moved.png\nsummary.md')" ] ||
  fail "the merged report holds $(ls "$tmp/golden-merged")"
cmp "$tmp/golden-one/moved.png" "$tmp/golden-merged/moved.png" || fail "the merged picture differs"
diff <(grep -v "^afb golden compare: " "$tmp/golden-one.txt") <(grep -v "^afb golden compare: " "$tmp/golden-merged.txt") ||
  fail "the merge's lines differ from compare's"
diff "$tmp/golden-one.err" "$tmp/golden-merged.err" || fail "the merge's errors differ from compare's"
# With --out, the reports go there: OUT/junit.xml and OUT/summary.md.
set +e
"$afb" merge "$tmp/golden-res" --out "$tmp/golden-out" > /dev/null 2>&1
set -e
cmp "$tmp/golden-merged.xml" "$tmp/golden-out/junit.xml" && cmp "$tmp/golden-one/moved.png" "$tmp/golden-out/moved.png" ||
  fail "afb merge --out did not put the golden reports in its folder"
# The golden file is among a line's inputs: one changed since planning is refused before it runs.
echo " " >> "$tmp/golden/high.json"
set +e
"$afb" run --manifest "$tmp/golden.jsonl" --index 3 --out "$tmp/x" 2> "$tmp/golden-changed.txt"
rc=$?
set -e
[ $rc -eq 1 ] && grep -q "high.json: error: input changed since planning" "$tmp/golden-changed.txt" ||
  fail "a golden changed since planning: exit $rc: $(cat "$tmp/golden-changed.txt")"

# --- GNU parallel: the recipe of docs/cluster.md, with a joblog -------------------------------------------------
if command -v parallel > /dev/null; then
  n=$(grep -c . "$tmp/stress.jsonl")
  seq 0 $((n - 1)) | parallel --will-cite -j 2 --joblog "$tmp/joblog" \
    "$afb" run --manifest "$tmp/stress.jsonl" --index {} --out "$tmp/parallel-res" > /dev/null
  "$afb" merge "$tmp/parallel-res" --out "$tmp/parallel-merged" > /dev/null
  same_stress "$tmp/stress-one" "$tmp/parallel-merged"
else
  echo "GNU parallel not found: its recipe not checked (cmake/install-deps.sh installs it)"
fi
echo "cli.batch: ok"
