#!/usr/bin/env bash
# Whole-run benchmark: cycle time of every accepted corpus program and of generated programs in
# look-ahead and stop modes against the time-optimal lower bound, with wall time, cycles per second
# and peak memory; then the Google Benchmark executables if they are built.
#
#   bash bench/run.sh BUILD_DIR [--quick] [--no-gbench] [--no-stop] [--accdec TYPE]
#                    [--machine FILE.toml] [--only REGEX]
#
#   --quick      skip the 1 000 000-line CAM program and the 100x refined stress test
#   --no-gbench  skip bench_interpreter / bench_motion
#   --no-stop    skip the stop-mode runs (stop_s and stop/b left empty)
#   --accdec T   also pass `--accdec T` to `cncore run` (acc/dec type), when supported
#   --machine F  run and bound on machine F (with a jerk limit the bound is the jerk-aware one,
#                bench/README.md)
#   --only RE    run only the programs whose path matches the extended regex RE
# Environment: CNCORE_SHARED_DIR (default: <repo>/../shared) for the corpus; BENCH_OUT for the
# output folder (default BUILD_DIR/bench-out); BENCH_TIMEOUT seconds per run (default 300).
# Writes BENCH_OUT/results.tsv as well as the table.
set -uo pipefail

usage() { sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; }
[ $# -ge 1 ] || { usage; exit 2; }
case $1 in -h|--help) usage; exit 0 ;; esac
build=$1
shift
quick=0
gbench=1
accdec=""
machine=""
stop=1
only=""
while [ $# -gt 0 ]; do
  case $1 in
    --quick) quick=1 ;;
    --no-gbench) gbench=0 ;;
    --accdec) accdec=${2:-}; shift ;;
    --machine) machine=${2:-}; shift ;;
    --no-stop) stop=0 ;;
    --only) only=${2:-}; shift ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run.sh: unknown option $1" >&2; usage >&2; exit 2 ;;
  esac
  shift
done

repo=$(cd "$(dirname "$0")/.." && pwd)
build_arg=$build
build=$(cd "$build" 2>/dev/null && pwd) || { echo "run.sh: no build directory $build_arg" >&2; exit 2; }
cncore=$build/src/app/cncore
bound=$build/bench/bound/cncore-bound
gen=$build/bench/gen/cncore-gen
for exe in "$cncore" "$bound" "$gen"; do
  if [ ! -x "$exe" ]; then
    echo "run.sh: $exe is not built (cmake --build $build --target cncore cncore-bound cncore-gen)" >&2
    exit 2
  fi
done
shared=${CNCORE_SHARED_DIR:-$repo/../shared}
corpus=$shared/testdata/gcode
out=${BENCH_OUT:-$build/bench-out}
tmo=${BENCH_TIMEOUT:-300}
mkdir -p "$out/programs" "$out/runs"

# Peak RSS and wall time of a command: GNU time if present, else python3's getrusage.
measure() {  # measure LOGFILE cmd...  → prints "wall_s rss_kb", returns the command's status
  local log=$1
  shift
  if [ -x /usr/bin/time ]; then
    /usr/bin/time -f '%e %M' -o "$log.time" timeout "$tmo" "$@" >"$log" 2>&1
    local rc=$?
    tail -1 "$log.time"
    return $rc
  fi
  python3 - "$log" "$tmo" "$@" <<'PY'
import resource, subprocess, sys, time
log, tmo, cmd = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
t0 = time.monotonic()
with open(log, "w") as f:
    try:
        rc = subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT, timeout=tmo)
    except subprocess.TimeoutExpired:
        rc = 124
wall = time.monotonic() - t0
rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
print(f"{wall:.2f} {rss}")
sys.exit(rc)
PY
}

json_get() {  # json_get FILE KEY → number (empty when absent)
  python3 -c 'import json,sys
try:
    d = json.load(open(sys.argv[1])); v = d.get(sys.argv[2], "")
    print(v if v != "" else "")
except Exception:
    print("")' "$1" "$2"
}

# ---- Programs: generated ones first, then the corpus. ----
programs=()
echo "generating programs in $out/programs"
"$gen" zigzag --strokes 200 --length 5 -o "$out/programs/gen-zigzag-5mm.ngc"
"$gen" circle --chords 360 --radius 50 -o "$out/programs/gen-circle-360.ngc"
"$gen" raster --width 60 --height 30 --stepover 1 --spacing 0.5 -o "$out/programs/gen-raster-3d.ngc"
"$gen" random --seed 1 --segments 2000 -o "$out/programs/gen-random-2000.ngc"
"$gen" random --seed 1 --segments 2000 --refine 100 -o "$out/programs/gen-random-2000-x100.ngc"
programs+=("$out/programs/gen-zigzag-5mm.ngc" "$out/programs/gen-circle-360.ngc"
  "$out/programs/gen-raster-3d.ngc" "$out/programs/gen-random-2000.ngc"
  "$out/programs/gen-random-2000-x100.ngc")
if [ "$quick" -eq 0 ]; then
  "$gen" cam --lines 1000000 -o "$out/programs/gen-cam-1M.ngc"
  programs+=("$out/programs/gen-cam-1M.ngc")
fi
for f in "$repo"/examples/*.ngc; do [ -f "$f" ] && programs+=("$f"); done

if [ -d "$corpus" ]; then
  while IFS= read -r f; do
    if "$cncore" check "$f" >"$out/runs/check.log" 2>&1; then
      programs+=("$f")
    else
      echo "skip (cncore check rejects it): ${f#"$corpus"/}: $(head -1 "$out/runs/check.log")"
    fi
  done < <(find "$corpus" -type f \( -name '*.ngc' -o -name '*.nc' -o -name '*.gcode' -o -name '*.tap' \) | sort)
  stress=$corpus/ugs/stress_test.gcode
  if [ "$quick" -eq 0 ] && [ -f "$stress" ] && "$cncore" check "$stress" >/dev/null 2>&1; then
    # P7: the same path in 100x more segments.
    if "$gen" refine "$stress" --factor 100 -o "$out/programs/stress_test-x100.ngc" 2>"$out/runs/refine.log"; then
      programs+=("$out/programs/stress_test-x100.ngc")
    else
      echo "skip stress_test x100: $(head -1 "$out/runs/refine.log")"
    fi
  fi
else
  echo "corpus not found at $corpus (set CNCORE_SHARED_DIR): skipping the corpus programs"
fi

# ---- Runs. ----
extra=()
[ -n "$accdec" ] && extra=(--accdec "$accdec")
mach=()
if [ -n "$machine" ]; then
  machine=$(cd "$(dirname "$machine")" && pwd)/$(basename "$machine")
  mach=(--machine "$machine")
  extra+=("${mach[@]}")
fi
results=$out/results.tsv
printf 'program\tblocks\tlookahead_s\tstop_s\tbound_s\tlook/bound\tstop/bound\twall_look_s\tMcycles_per_s\trss_MB\n' >"$results"
printf '%-44s %8s %10s %10s %10s %7s %7s %8s %8s %7s\n' program blocks look_s stop_s bound_s \
  look/b stop/b wall_s Mcyc/s RSS_MB
for p in "${programs[@]}"; do
  if [ -n "$only" ] && ! [[ $p =~ $only ]]; then continue; fi
  name=${p#"$corpus"/}
  name=${name#"$out"/programs/}
  name=${name#"$repo"/}
  tag=$(echo "$name" | tr '/ ' '__')
  b=$("$bound" "$p" "${mach[@]}" 2>"$out/runs/$tag.bound.err")
  if [ $? -ne 0 ]; then
    echo "skip $name: cncore-bound: $(head -1 "$out/runs/$tag.bound.err")"
    continue
  fi
  bound_s=$(echo "$b" | sed -n 's/.*bound_s=\([^ ]*\).*/\1/p')
  blocks=$(echo "$b" | sed -n 's/.*blocks=\([^ ]*\).*/\1/p')
  tm_l=$(measure "$out/runs/$tag.look.log" "$cncore" run "$p" --mode lookahead "${extra[@]}" \
    --summary "$out/runs/$tag.look.json")
  rc_l=$?
  if [ $stop -eq 1 ]; then
    tm_s=$(measure "$out/runs/$tag.stop.log" "$cncore" run "$p" --mode stop "${extra[@]}" \
      --summary "$out/runs/$tag.stop.json")
    rc_s=$?
  else
    tm_s=""; rc_s=-1
  fi
  look_s=""; stop_s=""; cycles=""
  [ $rc_l -eq 0 ] && look_s=$(json_get "$out/runs/$tag.look.json" cycle_time_s) &&
    cycles=$(json_get "$out/runs/$tag.look.json" cycles)
  [ $rc_s -eq 0 ] && stop_s=$(json_get "$out/runs/$tag.stop.json" cycle_time_s)
  why() { [ "$1" -eq 124 ] && echo "timed out after ${tmo} s" || echo "exit $1: $(grep -m1 error "$2")"; }
  [ $rc_l -ne 0 ] && echo "  $name: lookahead run failed ($(why $rc_l "$out/runs/$tag.look.log"))"
  [ $rc_s -gt 0 ] && echo "  $name: stop run failed ($(why $rc_s "$out/runs/$tag.stop.log"))"
  read -r wall rss <<<"$tm_l"
  row=$(python3 - "$name" "$blocks" "$look_s" "$stop_s" "$bound_s" "$wall" "$cycles" "$rss" <<'PY'
import sys
name, blocks, look, stop, bound, wall, cycles, rss = sys.argv[1:]
def f(x):
    try: return float(x)
    except ValueError: return None
look, stop, bound, wall, cycles, rss = map(f, (look, stop, bound, wall, cycles, rss))
def r(a, b): return f"{a / b:.3f}" if a is not None and b else "-"
def n(x, fmt): return format(x, fmt) if x is not None else "-"
mcps = cycles / wall / 1e6 if cycles and wall else None
vals = [name, blocks, n(look, ".3f"), n(stop, ".3f"), n(bound, ".3f"), r(look, bound), r(stop, bound),
        n(wall, ".2f"), n(mcps, ".2f"), n(rss / 1024 if rss else None, ".1f")]
print("\t".join(vals))
PY
)
  echo "$row" >>"$results"
  echo "$row" | awk -F'\t' '{printf "%-44s %8s %10s %10s %10s %7s %7s %8s %8s %7s\n", $1,$2,$3,$4,$5,$6,$7,$8,$9,$10}'
done
# The whole table in one line per type: geometric mean and largest look/b, the programs above 1.05.
python3 - "$results" <<'PY'
import csv, math, sys
rows = [r for r in csv.DictReader(open(sys.argv[1]), delimiter="\t")]
for col in ("look/bound", "stop/bound"):
    vals = [(float(r[col]), r["program"]) for r in rows if r[col] not in ("", "-")]
    if not vals:
        continue
    gm = math.exp(sum(math.log(v) for v, _ in vals) / len(vals))
    top = max(vals)
    over = ", ".join(f"{p} {v:.3f}" for v, p in sorted(vals, reverse=True) if v > 1.05)
    print(f"{col}: geometric mean {gm:.3f} over {len(vals)} programs, largest {top[0]:.3f} "
          f"({top[1]}); above 1.05: {over or 'none'}")
PY
echo "(look/b, stop/b: cycle time / time-optimal bound; wall, Mcyc/s, RSS: the look-ahead run,"
echo " including interpretation and the summary; table also in $results)"

# ---- Google Benchmark executables. ----
if [ "$gbench" -eq 1 ]; then
  for exe in bench_interpreter bench_motion; do
    path=$(find "$build/bench" -type f -name "$exe" -perm -u+x 2>/dev/null | head -1)
    if [ -n "$path" ]; then
      echo
      echo "== $exe =="
      "$path" --benchmark_min_time=0.2 2>&1 | tail -n +1
    else
      echo "($exe not built: skipped)"
    fi
  done
fi
