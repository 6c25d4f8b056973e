#!/usr/bin/env bash
# Fails when a source file includes a GiNaC header, directly or through the headers it includes,
# and prints the chain of includes that leads there. A program that identifies a record needs
# no computer algebra (docs/library.md), so the headers it includes must not bring GiNaC in.
# Usage: ginac_free.sh COMPILER INCLUDE_DIR... -- FILE...
set -euo pipefail
compiler=$1
shift
includes=()
while [[ $1 != -- ]]; do
  includes+=("-I$1")
  shift
done
shift
status=0
for file in "$@"; do
  # -H lists every header opened, one line each, indented by one dot per level of nesting.
  tree=$("$compiler" -std=c++20 -x c++ -E -H "${includes[@]}" "$file" 2>&1 >/dev/null)
  chain=$(awk '/^\.+ / {
      depth = length($1); path[depth] = $2
      if ($2 ~ /\/ginac\//) {
        for (d = 1; d <= depth; ++d) print "  " path[d]
        exit
      }
    }' <<<"$tree")
  if [[ -n $chain ]]; then
    echo "$file includes GiNaC:"
    echo "$chain"
    status=1
  else
    echo "$file: no GiNaC header"
  fi
done
exit $status
