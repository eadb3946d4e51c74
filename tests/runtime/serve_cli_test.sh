#!/usr/bin/env bash
# `cncore serve` as a process: its console on standard input, SIGTERM during a program (a
# controlled stop, exit 0, the state file written), and its servo outputs read by
# cncore-servo-reader (every sequence number once, in order).
#   serve_cli_test.sh CNCORE READER SOURCE_DIR console|udp|shm [SECONDS]
set -uo pipefail
cncore=$1 reader=$2 src=$3 mode=$4 seconds=${5:-5}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

case "$mode" in
console)
  out=$(printf 'load %s\nstart\nwait Idle 30\nstatus\njog inc X5 F3000\nwait Idle 30\nstatus\nfrobnicate\nfeed 500\nquit\n' \
          "$src/examples/seed-line-arc-line.ngc" |
        "$cncore" serve --no-state --no-realtime 2>&1)
  rc=$?
  echo "$out"
  [ "$rc" -eq 0 ] || fail "exit code $rc"
  [ "$(grep -c '^ok$' <<<"$out")" -ge 5 ] || fail "expected ok replies"
  grep -q '"state":"Idle"' <<<"$out" || fail "no Idle status"
  # The seed example ends at X55 Y60 (machine coordinates); the jog adds 5 to X.
  grep -qE '"x":(60\.0|59\.99999)' <<<"$out" || fail "the jog did not end at X60"
  grep -q "error: unknown command 'frobnicate'" <<<"$out" || fail "unknown command not reported"
  grep -q 'error: feed override must be between 0 and 200' <<<"$out" || fail "bad override accepted"
  # SIGTERM while a program runs: a controlled stop, exit 0, the position saved.
  "$cncore" serve --state-dir "$tmp/state" --no-realtime --trajectory "$tmp/served.csv" \
      --program "$src/examples/pocket-with-arcs.ngc" --start </dev/null >"$tmp/serve.log" 2>&1 &
  pid=$!
  sleep 1.5
  kill -TERM "$pid"
  wait "$pid"; rc=$?
  cat "$tmp/serve.log"
  [ "$rc" -eq 0 ] || fail "SIGTERM: exit code $rc"
  grep -q '"position"' "$tmp/state/machine-state.json" || fail "no state saved"
  grep -q 'cncore-machine-state-1' "$tmp/state/machine-state.json" || fail "state file format"
  # The recorded cycles: a header and one row per served cycle (≥ 1 s of them).
  head -1 "$tmp/served.csv" | grep -q '^t,line,x,y,z,feed' || fail "trajectory header"
  [ "$(wc -l <"$tmp/served.csv")" -gt 1000 ] || fail "trajectory too short"
  # The web page on an address other than loopback needs a token (usage error, exit 2).
  "$cncore" serve --no-state --no-realtime --http 0.0.0.0:0 </dev/null >/dev/null 2>&1
  [ $? -eq 2 ] || fail "--http on 0.0.0.0 without a token should be a usage error"
  echo "console: ok"
  ;;
udp|shm)
  if [ "$mode" = udp ]; then
    port=$((20000 + RANDOM % 20000))
    where="udp:$port" servo="udp:127.0.0.1:$port"
  else
    where="shm:cncore-test-$$" servo="shm:cncore-test-$$"
  fi
  "$reader" "$where" --seconds $((seconds + 4)) >"$tmp/reader.log" 2>&1 &
  rpid=$!
  sleep 1
  "$cncore" serve --no-state --no-realtime --servo "$servo" \
      --program "$src/examples/pocket-with-arcs.ngc" --start </dev/null >"$tmp/serve.log" 2>&1 &
  spid=$!
  sleep "$seconds"
  kill -TERM "$spid"
  wait "$spid"; src_rc=$?
  wait "$rpid"; rrc=$?
  cat "$tmp/serve.log" "$tmp/reader.log"
  [ "$src_rc" -eq 0 ] || fail "serve exit code $src_rc"
  [ "$rrc" -eq 0 ] || fail "reader exit code $rrc"
  line=$(grep '^records' "$tmp/reader.log") || fail "no reader summary"
  read -r _ records _ first _ last _ gaps _ missing _ dups _ ooo <<<"$line"
  [ "$gaps" -eq 0 ] && [ "$dups" -eq 0 ] && [ "$ooo" -eq 0 ] || fail "lost or repeated records: $line"
  [ $((last - first + 1)) -eq "$records" ] || fail "records do not cover first…last: $line"
  [ "$records" -ge $((seconds * 900)) ] || fail "too few records for $seconds s: $line"
  if [ "$mode" = udp ]; then [ "$first" -eq 0 ] || fail "the first datagram is missing: $line"; fi
  echo "$mode: ok"
  ;;
*) fail "unknown mode $mode" ;;
esac
