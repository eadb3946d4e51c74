#!/usr/bin/env bash
# `make install` and `make package` outcomes: installs the build into a temporary prefix, and
# builds the Debian package and unpacks it (dpkg-deb -x) into a temporary root; from each, runs
# the demo (`make demo`'s command on the installed example), reads the man page and asks the
# bash completion for a command and an option.
# Usage: install_test.sh CMAKE CPACK BUILD_DIR VERSION
set -euo pipefail
cmake=$1 cpack=$2 build=$3 version=$4
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The installed tree under $1 (a prefix such as /usr): binary, man page, completions, docs.
check_tree() {
  local prefix=$1 what=$2
  local bin=$prefix/bin/cncore doc=$prefix/share/doc/cncore
  [ -x "$bin" ] || fail "$what: no $bin"
  "$bin" --version | grep -qx "cncore $version" || fail "$what: --version is not cncore $version"
  for f in "$doc/README.md" "$doc/docs/cli.md" "$doc/examples/seed-line-arc-line.ngc" \
    "$prefix/share/zsh/vendor-completions/_cncore"; do
    [ -s "$f" ] || fail "$what: $f missing"
  done
  # The man page lists every command with its options (troff, from the help texts).
  local man=$prefix/share/man/man1/cncore.1
  grep -q '^\.SH NAME' "$man" || fail "$what: $man is not a man page"
  for c in run check table machine; do grep -q "^\.SS $c\$" "$man" || fail "$what: man: no $c"; done
  grep -q -- '--override-at' "$man" || fail "$what: man page without run's options"
  # The bash completion completes a command and an option of that command.
  local comp=$prefix/share/bash-completion/completions/cncore
  local got
  got=$(bash -c "source '$comp'; COMP_WORDS=(cncore ru); COMP_CWORD=1; _cncore; echo \${COMPREPLY[*]}")
  [ "$got" = run ] || fail "$what: bash completion of 'ru' gave '$got'"
  got=$(bash -c "source '$comp'; COMP_WORDS=(cncore run --overr); COMP_CWORD=2; _cncore; echo \${COMPREPLY[*]}")
  [ "$got" = "--override --override-at" ] || fail "$what: completion of 'run --overr' gave '$got'"
  # The demo, from the installed example, in an empty directory.
  mkdir -p "$tmp/demo-$what" && cd "$tmp/demo-$what"
  "$bin" run "$doc/examples/seed-line-arc-line.ngc" --summary s.json --trajectory t.csv \
    --report r.html >out.txt || fail "$what: the demo exits non-zero"
  grep -q '^cycle time    0\.9' out.txt || fail "$what: demo output: $(cat out.txt)"
  for f in s.json t.csv r.html; do [ -s "$f" ] || fail "$what: the demo wrote no $f"; done
  cd "$tmp"
  echo "ok: $what"
}

"$cmake" --install "$build" --prefix "$tmp/prefix" >/dev/null
check_tree "$tmp/prefix" "make-install"

"$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$tmp/pkg" >/dev/null
deb=$tmp/pkg/cncore_${version}_amd64.deb
[ -s "$deb" ] || fail "no $deb (got: $(ls "$tmp/pkg"))"
dpkg-deb -f "$deb" Depends | grep -q 'libfmt' || fail "Depends without libfmt: $(dpkg-deb -f "$deb" Depends)"
dpkg-deb -x "$deb" "$tmp/root"
check_tree "$tmp/root/usr" "package"
