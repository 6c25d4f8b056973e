#!/usr/bin/env bash
# An interrupted `simulate -o FILE` must leave neither FILE nor its temporary file behind.
# Usage: interrupt.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir"
for signal in INT TERM; do
  "$momentid" simulate "$model" --samples 100000000 -o "$dir/out.csv" &
  pid=$!
  # Wait until the temporary file exists, so the signal arrives while rows are being written.
  for _ in $(seq 100); do
    compgen -G "$dir/out.csv.partial-*" >/dev/null && break
    sleep 0.05
  done
  kill -s "$signal" "$pid"
  status=0
  wait "$pid" || status=$?
  leftovers=$(ls -A "$dir")
  if [[ -n $leftovers ]]; then
    echo "after SIG$signal (exit $status) the directory holds: $leftovers"
    exit 1
  fi
  echo "SIG$signal: exit $status, nothing left behind"
done
