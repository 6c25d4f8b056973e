#!/usr/bin/env bash
# A record read from a pipe (a FIFO, a shell's <(...), /dev/stdin) is read once, without hanging,
# and gives the report the same record gives from a file (but for the name it shows); an endless
# standard input stops at --stdin-limit, with its message, leaving no stored file.
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

mkdir "$dir/tmp"
status=0
yes "0.1,0.2,0.3,0.4" | TMPDIR=$dir/tmp timeout 60 "$momentid" identify "$model" - \
  --stdin-limit 10M 2>"$dir/error.txt" || status=$?
expected="momentid: <stdin>: more than 10485760 bytes arrived, the most stored from a stream (the \
limit keeps an endless stream from filling the disk): give the data as a file, or a larger limit \
(--stdin-limit)"
if [[ $status == 2 && "$(cat "$dir/error.txt")" == "$expected" && -z "$(ls -A "$dir/tmp")" ]]; then
  echo "an endless standard input: stopped at --stdin-limit, nothing left behind"
else
  echo "FAILED: an endless standard input: exit $status, $(cat "$dir/error.txt"), left: $(ls -A "$dir/tmp")"
  failed=1
fi
exit $failed
