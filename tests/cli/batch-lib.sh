# Sourced by the batch tests (batch.sh, slurm.sh): failing, and outputs compared with their timings masked.

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# A CSV without its timing columns (afb drop's and afb chart's: wall time, µs per step, CPU times).
csv_untimed() {
  awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) if ($i !~ /^(wall_ms|us_per_step|us_per_body_step|step_cpu_ms|awake_step_cpu_ms|cpu_us_per_awake_body_step)$/) keep[i] = 1 }
    { line = ""; for (i = 1; i <= NF; i++) if (i in keep) line = line "," $i; print line }' "$1"
}

# A JSON report (one key per line) without its timing keys.
json_untimed() {
  grep -Ev '"(cpu_ms|wall_ms|us_per_step|us_per_body_step|step_cpu_ms|awake_step_cpu_ms|cpu_us_per_awake_body_step)"' "$1"
}

# stress.md without its CPU column (the last cell of each failing run's row, milliseconds).
md_untimed() {
  sed -E 's/\| [0-9]+ \|$/| (cpu) |/' "$1"
}

# Fails unless the stress outputs of folders $1 and $2 are equal but for timings: the heat map byte for byte.
same_stress() {
  local f
  for f in stress.dat stress.gp; do cmp "$1/$f" "$2/$f" || fail "$1/$f and $2/$f differ"; done
  if [ -f "$1/stress.png" ] || [ -f "$2/stress.png" ]; then
    cmp "$1/stress.png" "$2/stress.png" || fail "$1/stress.png and $2/stress.png differ"
  fi
  diff <(json_untimed "$1/stress.json") <(json_untimed "$2/stress.json") || fail "stress.json differs (timing aside)"
  diff <(md_untimed "$1/stress.md") <(md_untimed "$2/stress.md") || fail "stress.md differs (timing aside)"
}
