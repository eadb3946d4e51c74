#!/usr/bin/env bash
# Writes the man page and the bash and zsh completions of `cncore` from its own help texts, so
# that they list exactly the commands and options the binary has.
# Usage: tools/gen-manual.sh CNCORE_BINARY OUTPUT_DIR  →  cncore.1, cncore.bash, _cncore
set -euo pipefail
bin=$1
out=$2
mkdir -p "$out"
commands=$("$bin" --help | sed -n '/^Subcommands:/,$p' | sed -nE 's/^  ([a-z]+) .*/\1/p')
version=$("$bin" --version | awk '{print $2}')

# Long options of one command, one per line (from its --help).
options_of() { "$bin" "$1" --help | grep -oE '^ +(-[a-zA-Z],)?--[a-z-]+' | grep -oE -- '--[a-z-]+'; }

# Help text as troff: backslashes doubled, a leading dot or quote protected.
troff_text() { sed -e 's/\\/\\e/g' -e "s/^\([.']\)/\\\\\&\1/"; }

{
  echo ".TH CNCORE 1 \"\" \"cncore $version\" \"User Commands\""
  echo ".SH NAME"
  echo "cncore \\- CNC numerical-control kernel on a simulated machine"
  echo ".SH SYNOPSIS"
  for c in $commands; do echo ".B cncore $c"; echo "[OPTIONS]"; echo ".br"; done
  echo ".SH DESCRIPTION"
  echo ".nf"
  "$bin" --help | troff_text
  echo ".fi"
  echo ".SH COMMANDS"
  for c in $commands; do
    echo ".SS $c"
    echo ".nf"
    "$bin" "$c" --help | troff_text
    echo ".fi"
  done
  echo ".SH EXIT STATUS"
  echo "0 success; 1 the program or another input is wrong (FILE:LINE:COL: error: MESSAGE);"
  echo "2 wrong usage; 3 internal failure."
  echo ".SH SEE ALSO"
  echo "The documentation in /usr/share/doc/cncore (README.md, docs/, examples/)."
} >"$out/cncore.1"

{
  echo "# bash completion for cncore (generated from its --help by tools/gen-manual.sh)"
  echo "_cncore() {"
  echo '  local cur=${COMP_WORDS[COMP_CWORD]} cmd=${COMP_WORDS[1]}'
  echo '  if [ "$COMP_CWORD" -eq 1 ]; then'
  echo "    COMPREPLY=(\$(compgen -W \"$(echo $commands) --help --version\" -- \"\$cur\"))"
  echo "    return"
  echo "  fi"
  echo '  local opts=""'
  echo '  case $cmd in'
  for c in $commands; do echo "    $c) opts=\"$(options_of "$c" | tr '\n' ' ')\" ;;"; done
  echo "  esac"
  echo '  if [[ $cur == -* ]]; then'
  echo '    COMPREPLY=($(compgen -W "$opts" -- "$cur"))'
  echo "  else"
  echo '    COMPREPLY=($(compgen -f -- "$cur"))'
  echo "  fi"
  echo "}"
  echo "complete -o filenames -F _cncore cncore"
} >"$out/cncore.bash"

{
  echo "#compdef cncore"
  echo "# zsh completion for cncore (generated from its --help by tools/gen-manual.sh)"
  echo "_cncore() {"
  echo "  if (( CURRENT == 2 )); then"
  echo "    compadd -- $(echo $commands) --help --version"
  echo "    return"
  echo "  fi"
  echo '  case ${words[2]} in'
  for c in $commands; do
    echo "    $c) _arguments -s '*:file:_files' $(options_of "$c" | sed "s/.*/'&[]'/" | tr '\n' ' ') ;;"
  done
  echo "  esac"
  echo "}"
  echo '_cncore "$@"'
} >"$out/_cncore"
