#!/usr/bin/env bash
# Runs the whole ctest suite and ends with the line "N passed, N failed".
set -uo pipefail
build=${1:-build/release}
log=$(mktemp)
ctest --test-dir "$build" --output-on-failure -j 2 --timeout 900 2>&1 | tee "$log"
rc=${PIPESTATUS[0]}
total=$(grep -oE 'tests passed, [0-9]+ tests failed out of [0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
failed=$(grep -oE '[0-9]+ tests failed out of' "$log" | grep -oE '^[0-9]+' | tail -1)
total=${total:-0}
failed=${failed:-0}
skipped=$(grep -cE '^[[:space:]]*[0-9]+ - .*\(Skipped\)$' "$log")
rm -f "$log"
[ "$skipped" -gt 0 ] && echo "${skipped} skipped (named above; the reason is in each test's output)"
echo "$((total - failed - skipped)) passed, ${failed} failed"
if [ "$total" -eq 0 ]; then echo "no tests ran"; exit 1; fi
exit "$rc"
