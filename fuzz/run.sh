#!/usr/bin/env bash
# Runs every libFuzzer target for FUZZ_SECONDS (default 60) each, one process at a time, and
# prints executions and findings per target. Usage: fuzz/run.sh [SECONDS] [TARGET...]
# Build: the `fuzz` preset (clang, -fsanitize=fuzzer,address,undefined) in build/fuzz.
# The working corpus (seeds from the repo's test programs + what the fuzzer adds) lives in
# build/fuzz/corpus/<target>; crashing inputs go to build/fuzz/findings/<target>/. Keep the
# ones worth keeping under fuzz/regressions/<target>/ (fixed) or fuzz/regressions/pending/.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-${FUZZ_SECONDS:-60}}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(interpreter run tables config)
build=$root/build/fuzz

cmake --preset fuzz -S "$root" >/dev/null || exit 3
cmake --build "$build" -j2 --target $(printf 'fuzz_%s ' "${targets[@]}") || exit 3

seed() {  # seed TARGET: fill the corpus from the repo's own inputs (idempotent)
  local t=$1 dir=$build/corpus/$1 f
  mkdir -p "$dir"
  case $t in
    interpreter|run)
      for f in "$root"/tests/interpreter/golden/*/program.ngc "$root"/tests/interpreter/reject/*/program.ngc \
               "$root"/examples/*.ngc "$root"/fuzz/seeds/run/* "$root"/fuzz/regressions/$t/* \
               "$root"/fuzz/regressions/pending/$t/*; do
        [ -f "$f" ] && cp "$f" "$dir/seed-$(sha1sum "$f" | cut -c1-16)"
      done ;;
    tables)
      for f in "$root"/examples/tables/*.tbl "$root"/fuzz/seeds/tables/* "$root"/fuzz/regressions/tables/* \
               "$root"/fuzz/regressions/pending/tables/*; do
        [ -f "$f" ] && cp "$f" "$dir/seed-$(sha1sum "$f" | cut -c1-16)"
      done ;;
    config)
      for f in "$root"/examples/tables/*.toml "$root"/fuzz/seeds/config/* "$root"/fuzz/regressions/config/* \
               "$root"/fuzz/regressions/pending/config/*; do
        [ -f "$f" ] && cp "$f" "$dir/seed-$(sha1sum "$f" | cut -c1-16)"
      done ;;
  esac
}

summary=()
for t in "${targets[@]}"; do
  seed "$t"
  findings=$build/findings/$t
  mkdir -p "$findings"
  before=$(ls "$findings" | wc -l)
  dict=()
  [ "$t" = interpreter ] || [ "$t" = run ] && dict=(-dict="$root/fuzz/gcode.dict")
  log=$build/fuzz_$t.log
  echo "== fuzz_$t for ${seconds}s (corpus $(ls "$build/corpus/$t" | wc -l) files)"
  # -fork=1 with -ignore_*: keep fuzzing after a finding (each one is saved to findings/).
  (cd "$build" && ASAN_OPTIONS=detect_leaks=1 "$build/fuzz/fuzz_$t" -fork=1 -ignore_crashes=1 \
     -ignore_timeouts=1 -ignore_ooms=1 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
     -max_len=4096 -artifact_prefix="$findings/" "${dict[@]}" "$build/corpus/$t") >"$log" 2>&1
  # Fork mode prints "#<execs>: cov: .. corp: .. exec/s: .. oom/timeout/crash: a/b/c time: .."
  last=$(grep -E '^#[0-9]+: cov:' "$log" | tail -1)
  execs=$(echo "$last" | sed -E 's/^#([0-9]+):.*/\1/')
  cov=$(echo "$last" | sed -E 's/.* cov: ([0-9]+).*/\1/')
  oomtc=$(echo "$last" | sed -E 's/.*oom\/timeout\/crash: ([0-9\/]+).*/\1/')
  new=$(( $(ls "$findings" | wc -l) - before ))
  line="fuzz_$t: ${execs:-0} executions in ${seconds}s, coverage ${cov:-?}, oom/timeout/crash ${oomtc:-?}, $new new finding file(s) in $findings"
  echo "$line"
  summary+=("$line")
done
echo "== summary"
printf '%s\n' "${summary[@]}"
