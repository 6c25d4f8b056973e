#!/usr/bin/env bash
# A record read from a pipe (a FIFO, a shell's <(...), /dev/stdin) is read once, without hanging,
# and gives the report the same record gives from a file (but for the name it shows).
# Usage: pipes.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir"
record=$dir/record.csv
"$momentid" simulate "$model" --samples 20000 -o "$record"
"$momentid" identify "$model" "$record" | tail -n +2 >"$dir/from_file.txt"
failed=0
compare() {  # compare DESCRIPTION: the report in $dir/got.txt against the file's
  if tail -n +2 "$dir/got.txt" | cmp -s - "$dir/from_file.txt"; then
    echo "$1: the same report as from the file"
  else
    echo "FAILED: $1:"
    diff <(tail -n +2 "$dir/got.txt") "$dir/from_file.txt" || true
    failed=1
  fi
}
mkfifo "$dir/fifo"
cat "$record" >"$dir/fifo" &
timeout 120 "$momentid" identify "$model" "$dir/fifo" >"$dir/got.txt"
compare "a FIFO"
timeout 120 "$momentid" identify "$model" <(cat "$record") >"$dir/got.txt"
compare "<(cat record)"
# shellcheck disable=SC2002  # a pipe, not a redirection: /dev/stdin must not be a regular file
cat "$record" | timeout 120 "$momentid" identify "$model" /dev/stdin >"$dir/got.txt"
compare "/dev/stdin from a pipe"
exit $failed
