#!/usr/bin/env bash
# The rigs table of docs/cli.md (`afb gen` on real rigs): every rigged model of the corpus (../shared/data, or
# $AFB_CORPUS_DIR) through `afb gen`, and each generated figure through `afb drop` from 1 m. Prints a Markdown
# table: the bodies, the total mass, the warnings of generation (vertices left out of the bodies among them), and
# whether the drop settled or exploded. The content folders and reports stay in build/gen-rigs/ ($OUT).
# Usage: cmake/gen-rigs.sh [AFB]   (default build/dev/bin/afb)
set -euo pipefail
cd "$(dirname "$0")/.."
afb=${1:-build/dev/bin/afb}
corpus=${AFB_CORPUS_DIR:-../shared/data}
out=${OUT:-build/gen-rigs}
[[ -d "$corpus" ]] || { echo "gen-rigs.sh: no corpus at $corpus" >&2; exit 1; }
mkdir -p "$out"
# model (under the corpus) and the afb gen options it needs
models=(
  "assimp-rigs/test/models-nonbsd/X/dwarf.x|"
  "assimp-rigs/test/models-nonbsd/B3D/dwarf2.b3d|"
  "assimp-rigs/test/models/FBX/animation_with_skeleton.fbx|"
  "assimp-rigs/test/models/FBX/huesitos.fbx|"
  "assimp-rigs/test/models/glTF2/simple_skin/simple_skin.gltf|"
  "assimp-rigs/test/models/glTF2/simple_skin/quad_skin.glb|"
  "assimp-rigs/test/models/glTF2/simple_skin/quad_skin.glb|--height 1"
  "assimp-md5/test/models-nonbsd/MD5/Bob.md5mesh|"
  "assimp-md5/test/models-nonbsd/MD5/BoarMan.md5mesh|"
  "assimp-md5/test/models/MD5/SimpleCube.md5mesh|"
  "doom3-kroom3/base/models/md5/monsters/zombies/zsec_pistol/zsecpistol.md5mesh|"
  "doom3-kroom3/base/models/md5/monsters/zombies/zsec_shotgun/zsecshotgun.md5mesh|"
  "doom3-kroom3/base/models/md5/monsters/zombies/zsec_machinegun/zsecmachinegun.md5mesh|"
  "doom3-kroom3/base/models/md5/weapons/pistol_world/worldpistol.md5mesh|"
  "doom3-kroom3/base/models/md5/weapons/shotgun_world/worldshotgun.md5mesh|"
)
json_number() { { grep -o "\"$1\": [-0-9.e]*" "$2" || true; } | head -n 1 | sed 's/.*: //'; }
echo "| model | options | bodies | mass kg | warnings (stray vertices) | 1 m drop |"
echo "|---|---|---|---|---|---|"
for entry in "${models[@]}"; do
  model=${entry%%|*}
  options=${entry#*|}
  name=$(basename "${model%.*}" | tr -c 'A-Za-z0-9_\n' '_')
  [[ -n "$options" ]] && name="${name}_$(echo "$options" | tr -c 'A-Za-z0-9_\n' '_' | tr -s '_')"
  dir="$out/$name"
  rm -rf "$dir"
  # shellcheck disable=SC2086 # the options are words
  if ! "$afb" gen "$corpus/$model" --out "$dir" --name "$name" $options --json >"$out/$name.gen.json" \
      2>"$out/$name.gen.err"; then
    echo "| $(basename "$model") | $options | - | - | $({ grep -m1 -o 'error: .*' "$out/$name.gen.err" || true; } | cut -c8-) | - |"
    continue
  fi
  bodies=$(grep -c '"joints": [0-9]' "$out/$name.gen.json" || true)
  mass=$(json_number totalMassKg "$out/$name.gen.json")
  warnings=$(grep -c 'warning:' "$out/$name.gen.err" || true)
  stray=$({ grep -o 'warning: [0-9]* of the' "$out/$name.gen.err" || true; } | awk '{s += $2} END {print s + 0}')
  if "$afb" drop --base "$dir" "$name" --height 1 --seconds 15 --stop-at-rest --json "$out/$name.drop.json" \
      >/dev/null 2>"$out/$name.drop.err"; then
    settle=$(json_number settle_time_s "$out/$name.drop.json")
    if [[ -n "$settle" ]]; then drop="settles at $(printf '%.2f' "$settle") s"; else drop="still moving at 15 s"; fi
  else
    drop="**exploded** or failed (see $out/$name.drop.err)"
  fi
  printf '| %s | %s | %s | %.1f | %s (%s) | %s |\n' "$(basename "$model")" "$options" "$bodies" "$mass" "$warnings" \
    "$stray" "$drop"
done
