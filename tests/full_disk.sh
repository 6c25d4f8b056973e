#!/usr/bin/env bash
# `convert` onto a disk that fills up: for every format, exit status 2 with one line, no
# temporary file left, and the existing target unchanged. Twice: under a file size limit (writes
# past it fail with EFBIG), and on a real 2 MiB tmpfs (ENOSPC) where the test may mount one (as
# root, which CI is); elsewhere the second is skipped with a line that says so.
# Usage: full_disk.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
disk=$dir/disk
if mountpoint -q "$disk" 2>/dev/null; then umount "$disk"; fi
rm -rf "$dir" && mkdir -p "$dir"
# About 3.6 MB of CSV, 3.2 MB of values: no format fits in 2 MiB.
"$momentid" simulate "$model" --samples 100000 -o "$dir/record.csv"
failed=0

# convert to FORMAT into directory TARGET_DIR, run through the command WRAPPER... (the disk),
# which must say the system's CAUSE (text formats) or LIBRARY_CAUSE (.mat, HDF5).
attempt() {
  local disk_name=$1 format=$2 target_dir=$3 cause=$4 library_cause=$5
  shift 5
  local extension=$format
  [[ $format == mat73 ]] && extension=mat
  local target=$target_dir/out.$extension
  local expected="momentid: $target: writing the output file failed: $cause"
  case $format in
    mat | mat73) expected="momentid: $target: cannot write the MATLAB file: $library_cause" ;;
    h5) expected="momentid: $target: cannot write the HDF5 file: $library_cause" ;;
  esac
  echo "an existing good file" >"$target"
  cp "$target" "$dir/before"
  local status=0
  "$@" "$momentid" convert "$dir/record.csv" "$target" --format "$format" 2>"$dir/err" ||
    status=$?
  local lines leftovers
  lines=$(wc -l <"$dir/err")
  leftovers=$(compgen -G "$target.partial-*" || true)
  if [[ $status != 2 || $lines != 1 || -n $leftovers ]] || ! cmp -s "$target" "$dir/before" ||
     [[ $(cat "$dir/err") != "$expected" ]]; then
    echo "FAILED: $disk_name, $format: exit $status, $lines lines of errors, temporary files:" \
         "'$leftovers', target $(cmp -s "$target" "$dir/before" && echo unchanged || echo changed):"
    head -5 "$dir/err"
    failed=1
  else
    echo "$disk_name, $format: exit 2, $(cat "$dir/err"); the target unchanged"
  fi
  rm -f "$target"
}

size_limit() { bash -c 'ulimit -f 300; trap "" XFSZ; exec "$@"' - "$@"; }
for format in csv bin npy mat mat73 h5; do
  attempt "a 300 kB file size limit" "$format" "$dir" "File too large" \
    "the file reached the size limit (ulimit -f)" size_limit
done

mkdir -p "$disk"
if mount -t tmpfs -o size=2m tmpfs "$disk" 2>/dev/null; then
  trap 'umount "$disk"' EXIT
  for format in csv bin npy mat mat73 h5; do
    attempt "a full 2 MiB tmpfs" "$format" "$disk" "No space left on device" \
      "no space left on the device" env
  done
else
  echo "a full 2 MiB tmpfs: skipped (no permission to mount one here)"
fi
exit $failed
