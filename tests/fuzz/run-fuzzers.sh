#!/usr/bin/env bash
# Runs every libFuzzer target for a short, fixed time and fails if any of them finds a crash.
#
#   tests/fuzz/run-fuzzers.sh [seconds-per-target]        (default 30)
#
# Build the targets first:  cmake --preset fuzz && cmake --build --preset fuzz
#
# Environment:
#   AFB_FUZZ_BUILD_DIR  fuzz build directory            (default: <repo>/build/fuzz)
#   AFB_FUZZ_BIN_DIR    where the fuzz executables are   (default: <build>/bin, else <build>/tests/fuzz)
#   AFB_CORPUS_DIR      real-world inputs used as seeds  (default: <repo>/../shared/data; skipped when absent)
#   AFB_FUZZ_TARGETS    space-separated subset to run    (default: all seven)
#   AFB_FUZZ_SEED       libFuzzer -seed (default: random; the log prints the one used)
#
# Seeds are assembled at run time inside the build directory (<build>/fuzz-run/seeds/<target>): copies of the
# corpus files, of the repository's own af/ def/ models/ files, and a few tiny hand-written inputs. Nothing is
# ever written into the source tree. New inputs libFuzzer finds go to <build>/fuzz-run/corpus/<target> (kept
# between runs), crash reproducers to <build>/fuzz-run/artifacts/, full logs to <build>/fuzz-run/logs/.
# Reproduce a crash with:  <build>/bin/<target> <artifact file>
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
seconds="${1:-30}"
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "usage: $0 [seconds-per-target]" >&2
  exit 2
fi

build="${AFB_FUZZ_BUILD_DIR:-$repo/build/fuzz}"
corpus_src="${AFB_CORPUS_DIR:-$repo/../shared/data}"
# The executables land in <build>/bin (CMAKE_RUNTIME_OUTPUT_DIRECTORY) or next to their CMakeLists.
bindir="${AFB_FUZZ_BIN_DIR:-}"
if [ -z "$bindir" ]; then
  bindir="$build/bin"
  for d in "$build/bin" "$build/tests/fuzz"; do
    if [ -x "$d/fuzz_lexer" ]; then bindir="$d"; break; fi
  done
fi
work="$build/fuzz-run"
targets=(${AFB_FUZZ_TARGETS:-fuzz_lexer fuzz_af fuzz_def fuzz_md5mesh fuzz_md5anim fuzz_e2e fuzz_gen})

# Per target: the seed file extensions, the largest input libFuzzer may build, and the dictionary.
declare -A exts=(
  [fuzz_lexer]="af def md5mesh md5anim"
  [fuzz_af]="af"
  [fuzz_def]="def"
  [fuzz_md5mesh]="md5mesh"
  [fuzz_md5anim]="md5anim"
  [fuzz_e2e]="af"
  [fuzz_gen]="gltf glb fbx x b3d dae obj md5mesh"
)
declare -A max_len=(
  [fuzz_lexer]=32768
  [fuzz_af]=16384
  [fuzz_def]=32768
  [fuzz_md5mesh]=65536
  [fuzz_md5anim]=65536
  [fuzz_e2e]=16384
  [fuzz_gen]=262144
)
declare -A dict=(
  [fuzz_lexer]=lexer.dict
  [fuzz_af]=af.dict
  [fuzz_def]=def.dict
  [fuzz_md5mesh]=md5mesh.dict
  [fuzz_md5anim]=md5anim.dict
  [fuzz_e2e]=af.dict
  [fuzz_gen]=gen.dict
)

for t in "${targets[@]}"; do
  if [ -z "${exts[$t]+x}" ]; then
    echo "run-fuzzers: unknown target '$t'" >&2
    exit 2
  fi
  if [ ! -x "$bindir/$t" ]; then
    echo "run-fuzzers: $bindir/$t not found; build it first: cmake --preset fuzz && cmake --build --preset fuzz" >&2
    exit 2
  fi
done

# --- seeds ------------------------------------------------------------------------------------------------------
seed_roots=()
if [ -d "$corpus_src" ]; then
  seed_roots+=("$(cd "$corpus_src" && pwd)")
else
  echo "run-fuzzers: no corpus at $corpus_src (set AFB_CORPUS_DIR); using built-in and repository seeds only"
fi
for d in af def models; do
  [ -d "$repo/$d" ] && seed_roots+=("$repo/$d")
done

write_builtin_seeds() { # $1 = target, $2 = seed dir
  local t="$1" dir="$2"
  case "$t" in
    fuzz_af|fuzz_lexer)
      cat > "$dir/builtin-min.af" <<'EOF'
articulatedFigure seed {
settings {
	model "seed_model"
	skin ""
	friction 0.01, 0.01, 0.8, 0.5
	suspendSpeed 20, 30, 40, 60
	totalMass 100
	contents corpse
	clipMask solid, corpse
	selfCollision 1
}
body "waist" {
	joint "origin"
	mod orientation
	model box( ( -8, -8, -8 ), ( 8, 8, 8 ) )
	origin ( 0, 0, 40 )
	angles ( 10, 0, 0 )
	density 0.02
	friction 0.01, 0.01, 0.8
	contents corpse
	clipMask solid, corpse
	selfCollision 0
	containedJoints "*origin -*Chest"
}
body "chest" {
	joint "chest"
	mod orientation
	model cylinder( ( -10, -10, -12 ), ( 10, 10, 12 ), 6 )
	origin bonecenter( "chest", "neck" )
	density 0.02
}
body "arm" {
	joint "arm"
	mod both
	model bone( joint( "arm" ), joint( "hand" ), 4 )
	origin joint( "arm" )
	density 0.03
}
universalJoint "waist_chest" {
	body1 "chest"
	body2 "waist"
	anchor joint( "chest" )
	shafts ( 0, 0, 1 ), ( 0, 0, -1 )
	friction 0.4
	coneLimit ( 0, 0, 1 ), 30
}
hinge "elbow" {
	body1 "arm"
	body2 "chest"
	anchor joint( "arm" )
	axis -bonedir( "arm", "hand" )
	limit 0, 120, 0
}
ballAndSocketJoint "shoulder" {
	body1 "arm"
	anchor ( 0, 0, 70 )
	pyramidLimit ( 1, 0, 0 ), 40, 30, 10, ( 0, 1, 0 )
}
spring "s" {
	body1 "arm"
	body2 "waist"
	anchor1 ( 0, 0, 1 )
	anchor2 ( 0, 0, 2 )
	stretch 10
	compress 10
	damping 0.5
	restLength 1
	minLength 0
	maxLength 4
}
}
EOF
      ;;&
    fuzz_def|fuzz_lexer)
      cat > "$dir/builtin-min.def" <<'EOF'
model seed_model {
	mesh models/md5/seed.md5mesh
	channel torso ( *Waist )
	anim af_pose models/md5/af_pose.md5anim
	anim walk models/md5/walk.md5anim {
		frame 4 sound_body footstep
	}
}
entityDef seed_entity {
	"inherit" "seed_base"
	"model" "seed_model"
	"ragdoll" "seed"
}
entityDef seed_base {
	"spawnclass" "idAFEntity_Generic"
}
EOF
      ;;&
    fuzz_md5mesh|fuzz_lexer)
      cat > "$dir/builtin-min.md5mesh" <<'EOF'
MD5Version 10
commandline "seed"

numJoints 2
numMeshes 1

joints {
	"origin"	-1 ( 0 0 0 ) ( 0 0 0 )		//
	"Chest"	0 ( 0 0 40 ) ( -0.5 -0.5 -0.5 )		// origin
}

mesh {
	shader "seed"
	numverts 3
	vert 0 ( 0 0 ) 0 1
	vert 1 ( 1 0 ) 1 1
	vert 2 ( 0 1 ) 2 2
	numtris 1
	tri 0 0 1 2
	numweights 4
	weight 0 0 1 ( 0 0 0 )
	weight 1 1 1 ( 1 0 0 )
	weight 2 0 0.5 ( 0 1 0 )
	weight 3 1 0.5 ( 0 1 0 )
}
EOF
      ;;&
    fuzz_md5anim|fuzz_lexer)
      cat > "$dir/builtin-min.md5anim" <<'EOF'
MD5Version 10
commandline "seed"

numFrames 2
numJoints 2
frameRate 24
numAnimatedComponents 3

hierarchy {
	"origin"	-1 0 0
	"Chest"	0 7 0
}

bounds {
	( -1 -1 -1 ) ( 1 1 1 )
	( -1 -1 -1 ) ( 1 1 2 )
}

baseframe {
	( 0 0 0 ) ( 0 0 0 )
	( 0 0 40 ) ( -0.5 -0.5 -0.5 )
}

frame 0 {
	0 0 40
}

frame 1 {
	0 0 41
}
EOF
      ;;
  esac
}

build_seeds() { # $1 = target; prints the number of seed files
  local t="$1" dir="$work/seeds/$1" root ext f rel
  rm -rf "$dir"
  mkdir -p "$dir"
  write_builtin_seeds "$t" "$dir"
  local roots=("${seed_roots[@]}")
  # fuzz_e2e builds on the bundled skeletons: only the repository's own figures are seeds that build.
  [ "$t" = fuzz_e2e ] && roots=("$repo/af")
  if [ "$t" = fuzz_gen ]; then # the first byte of a fuzz_gen input names the format (tests/fuzz/fuzz_gen.cpp)
    local i=0
    for ext in ${exts[$t]}; do
      while IFS= read -r -d '' f; do
        rel="${f#/}"
        { printf "\\$(printf '%03o' "$i")"; cat -- "$f"; } > "$dir/${rel//\//__}"
      done < <(find "${roots[@]}" -type f -name "*.$ext" -size -256k -print0)
      i=$((i + 1))
    done
    find "$dir" -type f | wc -l
    return
  fi
  for root in "${roots[@]}"; do
    for ext in ${exts[$t]}; do
      while IFS= read -r -d '' f; do
        rel="${f#"$root"/}"
        cp -- "$f" "$dir/$(basename "$root")__${rel//\//__}"
      done < <(find "$root" -type f -name "*.$ext" -print0)
    done
  done
  find "$dir" -type f | wc -l
}

# --- run ----------------------------------------------------------------------------------------------------------
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1}"
# assimp's FBX reader leaks a zlib stream on some inputs (not afbullet's to free): see tests/lsan-suppressions.txt.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$repo/tests/lsan-suppressions.txt}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
mkdir -p "$work/artifacts" "$work/logs"

echo "run-fuzzers: ${#targets[@]} targets x ${seconds}s, build $build"
summary=()
failed=0
for t in "${targets[@]}"; do
  nseeds="$(build_seeds "$t")"
  mkdir -p "$work/corpus/$t"
  log="$work/logs/$t.log"
  args=(
    -max_total_time="$seconds"
    -max_len="${max_len[$t]}"
    -timeout=10
    -rss_limit_mb=2048
    -malloc_limit_mb=1024
    -print_final_stats=1
    -dict="$repo/tests/fuzz/${dict[$t]}"
    -artifact_prefix="$work/artifacts/$t-"
  )
  [ -n "${AFB_FUZZ_SEED:-}" ] && args+=(-seed="$AFB_FUZZ_SEED")
  echo "--- $t: $nseeds seeds, max_len ${max_len[$t]}, ${seconds}s (log: $log)"
  rc=0
  "$bindir/$t" "${args[@]}" "$work/corpus/$t" "$work/seeds/$t" > "$log" 2>&1 || rc=$?

  execs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)"
  cov="$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' "$log" | tail -n 1 || true)"
  if [ "$rc" -eq 0 ]; then
    result="ok"
  else
    failed=1
    artifact="$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)"
    result="FAILED (exit $rc${artifact:+, reproducer $artifact})"
    echo "----- $t: last 60 lines of $log -----"
    tail -n 60 "$log"
    echo "----- end of $t log -----"
  fi
  line="$(printf '%-14s execs %10s  %-34s %s' "$t" "${execs:-?}" "${cov:-}" "$result")"
  echo "$line"
  summary+=("$line")
done

echo
echo "=== fuzz summary (${seconds}s per target) ==="
printf '%s\n' "${summary[@]}"
if [ "$failed" -ne 0 ]; then
  echo "run-fuzzers: FAILED — see the reproducers in $work/artifacts" >&2
  exit 1
fi
echo "run-fuzzers: all targets ran clean"
