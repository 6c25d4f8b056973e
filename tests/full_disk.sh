#!/usr/bin/env bash
# `convert` onto a disk that fills up (a file size limit stands in for it: writes past it fail
# with EFBIG, as they would with ENOSPC): for every format, exit status 2 with one line, no
# temporary file left, and the existing target unchanged.
# Usage: full_disk.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir"
"$momentid" simulate "$model" --samples 40000 -o "$dir/record.csv"
failed=0
for format in csv bin npy mat mat73 h5; do
  extension=$format
  [[ $format == mat73 ]] && extension=mat
  target=$dir/out.$extension
  echo "an existing good file" >"$target"
  cp "$target" "$dir/before"
  status=0
  # 300 KB: the header and the first rows fit, the whole record (about 1.4 MB) does not.
  bash -c 'ulimit -f 300; trap "" XFSZ; exec "$@"' - \
    "$momentid" convert "$dir/record.csv" "$target" --format "$format" 2>"$dir/err" || status=$?
  lines=$(wc -l <"$dir/err")
  leftovers=$(compgen -G "$target.partial-*" || true)
  if [[ $status != 2 || $lines != 1 || -n $leftovers ]] || ! cmp -s "$target" "$dir/before" ||
     ! grep -q "^momentid: $target: " "$dir/err"; then
    echo "FAILED: $format: exit $status, $lines lines of errors, temporary files: '$leftovers', " \
         "target $(cmp -s "$target" "$dir/before" && echo unchanged || echo changed):"
    head -5 "$dir/err"
    failed=1
  else
    echo "$format: exit 2, $(cat "$dir/err"); the target unchanged"
  fi
done
exit $failed
