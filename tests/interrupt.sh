#!/usr/bin/env bash
# An interrupted output must leave neither the target nor its temporary file behind: `simulate
# -o FILE` (SIGINT, SIGTERM, SIGHUP; and SIGINT in .npy, .mat and HDF5), and `convert` to .mat,
# .mat (level 7.3) and HDF5, whose libraries write the temporary file themselves; nor an
# interrupted read of standard input the file it is stored in.
# Usage: interrupt.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir/out"

# interrupt SIGNAL COMMAND...: starts the command, which writes $dir/out/out.*, signals it once
# its temporary file exists, and checks that nothing is left in $dir/out.
interrupt() {
  local signal=$1
  shift
  "$@" &
  local pid=$!
  # Wait until the temporary file exists, so the signal arrives while it is being written.
  local seen=0
  for _ in $(seq 3000); do  # up to a minute: the .mat writers create it only once all rows are in
    if compgen -G "$dir/out/out.*.partial-*" >/dev/null; then
      seen=1
      break
    fi
    sleep 0.02
  done
  kill -s "$signal" "$pid" 2>/dev/null || true
  local status=0
  wait "$pid" || status=$?
  local leftovers
  leftovers=$(ls -A "$dir/out")
  if [[ $seen == 0 || -n $leftovers ]]; then
    echo "$* after SIG$signal (exit $status; temporary file seen: $seen) leaves: $leftovers"
    exit 1
  fi
  echo "$*: SIG$signal, exit $status, nothing left behind"
}

for signal in INT TERM HUP; do
  interrupt "$signal" "$momentid" simulate "$model" --samples 100000000 -o "$dir/out/out.csv"
done
# simulate in the array formats: .npy and HDF5 fill their temporary file as the rows come, the
# .mat writers once all rows are in.
for target in out.npy out.h5; do
  interrupt INT "$momentid" simulate "$model" --samples 100000000 -o "$dir/out/$target"
done
interrupt INT "$momentid" simulate "$model" --samples 3000000 -o "$dir/out/out.mat"
"$momentid" simulate "$model" --samples 3000000 --format bin -o "$dir/record.bin"
for format in mat mat73 h5; do
  extension=$format
  [[ $format == mat73 ]] && extension=mat
  for signal in INT TERM HUP; do
    interrupt "$signal" "$momentid" convert "$dir/record.bin" "$dir/out/out.$extension" \
      --format "$format"
  done
done

# Standard input, endless, being stored: the signal removes the stored file.
mkdir -p "$dir/tmp"
for signal in INT TERM HUP; do
  { yes "0.1,0.2,0.3,0.4" | TMPDIR=$dir/tmp "$momentid" identify "$model" - 2>/dev/null; } &
  pipeline=$!
  seen=0
  for _ in $(seq 3000); do
    if compgen -G "$dir/tmp/momentid_stream_*" >/dev/null; then
      seen=1
      break
    fi
    sleep 0.02
  done
  pkill -"$signal" -f "$momentid identify $model -" || true
  wait "$pipeline" 2>/dev/null || true
  if [[ $seen == 0 || -n $(ls -A "$dir/tmp") ]]; then
    echo "standard input after SIG$signal (stored file seen: $seen) leaves: $(ls -A "$dir/tmp")"
    exit 1
  fi
  echo "standard input: SIG$signal, nothing left behind"
done
