#!/usr/bin/env bash
# Byte-for-byte comparison of the trajectories two cncore builds produce on the corpus, for each
# acc/dec type: a change that should not change behaviour (a refactoring) must leave every
# trajectory CSV identical.
#
#   tools/compare-trajectories.sh REF NEW [PROGRAM...]
#   tools/compare-trajectories.sh --digest CNCORE [PROGRAM...] > DIGEST.tsv
#
# REF and NEW are cncore binaries or digest files written by --digest (one line per program and
# type: type, program, exit code, md5 of the trajectory CSV, its rows), so that one build's side
# can be run once and kept. Without programs: every file in $CNCORE_SHARED_DIR/testdata/gcode
# (default ../shared) and every .ngc under examples/. A program that both builds fail to
# interpret is skipped and counted; one that only one of them fails on is a difference.
# ACCDEC (default "acceleration moving_average search") and JOBS (default 2) may be set.
# Exit code: 0 when every compared trajectory is identical, 1 otherwise.
set -uo pipefail

usage() { sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; }
root=$(cd "$(dirname "$0")/.." && pwd)
shared=${CNCORE_SHARED_DIR:-$root/../shared}
accdecs=${ACCDEC:-acceleration moving_average search}
jobs=${JOBS:-2}

# One program × type: "TYPE<TAB>PROGRAM<TAB>EXIT<TAB>MD5<TAB>ROWS".
digest_one() {
  local cncore=$1 work=$2 accdec=$3 prog=$4
  local csv
  csv="$work/$(printf '%s' "$prog-$accdec" | md5sum | cut -c1-12).csv"
  "$cncore" run "$prog" --accdec "$accdec" --trajectory "$csv" >/dev/null 2>&1
  local rc=$?
  if [[ $rc -eq 0 && -f $csv ]]; then
    printf '%s\t%s\t0\t%s\t%s\n' "$accdec" "$prog" "$(md5sum <"$csv" | cut -c1-32)" "$(wc -l <"$csv")"
  else
    printf '%s\t%s\t%s\t-\t0\n' "$accdec" "$prog" "$rc"
  fi
  rm -f "$csv"
}
export -f digest_one

digest() {
  local cncore work
  cncore=$(realpath "$1")
  shift
  local programs=("$@")
  if [[ ${#programs[@]} -eq 0 ]]; then
    if [[ -d $shared/testdata/gcode ]]; then
      mapfile -t programs < <(find "$shared/testdata/gcode" -type f ! -name '*.md' | sort)
    else
      echo "note: $shared/testdata/gcode is absent: examples/ only" >&2
    fi
    mapfile -t -O "${#programs[@]}" programs < <(find "$root/examples" -name '*.ngc' | sort)
  fi
  work=$(mktemp -d)
  for accdec in $accdecs; do
    for prog in "${programs[@]}"; do printf '%s\0%s\0' "$accdec" "$prog"; done
  done | xargs -0 -n 2 -P "$jobs" bash -c 'digest_one "$0" "$1" "$2" "$3"' "$cncore" "$work" |
    sort -t $'\t' -k1,1 -k2,2
  rm -rf "$work"
}

if [[ ${1:-} == --digest ]]; then
  [[ $# -ge 2 ]] || { usage; exit 2; }
  shift
  digest "$@"
  exit 0
fi
[[ $# -ge 2 ]] || { usage; exit 2; }
ref=$1
new=$2
shift 2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for side in ref new; do
  src=${!side}
  if [[ $(head -c 4 "$src" 2>/dev/null) == $'\x7fELF' ]]; then
    digest "$src" "$@" >"$tmp/$side.tsv"  # a cncore binary
  else
    cp "$src" "$tmp/$side.tsv"  # a digest file
  fi
done
join -t $'\t' -j1 -a1 -a2 -e missing -o auto <(awk -F'\t' '{print $1" "$2"\t"$3"\t"$4"\t"$5}' "$tmp/ref.tsv" | sort) \
  <(awk -F'\t' '{print $1" "$2"\t"$3"\t"$4"\t"$5}' "$tmp/new.tsv" | sort) |
  awk -F'\t' '{
    if ($2 == "missing" || $5 == "missing") { print "missing   " $1 " (in one side only)"; bad++ }
    else if ($2 != 0 && $5 != 0) { print "skipped   " $1; skipped++ }
    else if ($2 != 0 || $5 != 0) { print "one-failed " $1 " (exit " $2 " / " $5 ")"; bad++ }
    else if ($3 == $6) { print "same      " $1 " " $4 " rows"; same++ }
    else { print "differs   " $1; bad++ }
  } END {
    printf "identical: %d, skipped (neither build interprets it): %d, different: %d\n", same, skipped, bad
    exit bad > 0
  }'
