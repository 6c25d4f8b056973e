#!/usr/bin/env bash
# A report that cannot reach standard output (a full disk, a closed descriptor) ends with exit
# status 2 and one line naming the cause, for every command that prints one (simulate its samples).
# A simulate -o FILE that cannot write FILE (a directory missing, a file in its place, one without
# write permission), or whose simulation blows up midway, ends the same way in every format and
# leaves nothing: neither FILE nor its temporary file.
# Usage: unwritable_output.sh MOMENTID MODEL DIRECTORY
set -euo pipefail
momentid=$1 model=$2 dir=$3
rm -rf "$dir" && mkdir -p "$dir"
record=$dir/record.csv
"$momentid" simulate "$model" --samples 20000 -o "$record"
failed=0
expect() {  # expect full|closed MESSAGE COMMAND...: runs it with its standard output there
  local output=$1 message=$2
  shift 2
  local description="$* (standard output $output)" status=0
  if [[ $output == full ]]; then
    "$@" >/dev/full 2>"$dir/err" || status=$?
  else
    "$@" >&- 2>"$dir/err" || status=$?
  fi
  local err
  err=$(cat "$dir/err")
  if [[ $status != 2 || $err != "$message" ]]; then
    echo "FAILED: $description: exit $status, standard error: $err"
    failed=1
  else
    echo "$description: exit 2, $err"
  fi
}
full="momentid: cannot write to standard output: No space left on device"
closed="momentid: cannot write to standard output: Bad file descriptor"
for command in "derive $model" "simulate $model" "check $record" "identify $model $record" \
               "identify $model $record --format json" "validate $model $record"; do
  # shellcheck disable=SC2086
  expect full "$full" "$momentid" $command
  # shellcheck disable=SC2086
  expect closed "$closed" "$momentid" $command
done

# leaves_nothing WHAT MESSAGE COMMAND...: runs simulate, which must fail with exit 2 and one line
# that begins with MESSAGE, and leave $dir/out as it was (empty).
leaves_nothing() {
  local what=$1 message=$2 status=0
  shift 2
  "$@" 2>"$dir/err" || status=$?
  local lines leftovers
  lines=$(wc -l <"$dir/err")
  leftovers=$(ls -A "$dir/out")
  if [[ $status != 2 || $lines != 1 || $(cat "$dir/err") != "$message"* || -n $leftovers ]]; then
    echo "FAILED: $what: exit $status, $lines lines of errors, left in out/: '$leftovers':"
    head -3 "$dir/err"
    failed=1
  else
    echo "$what: exit 2, $(cat "$dir/err"); nothing left"
  fi
}
mkdir -p "$dir/out"
touch "$dir/out.file"
# Permissions do not stop root: a missing directory and a file in a directory's place do.
unwritable=("$dir/out/missing" "$dir/out.file")
if [[ $(id -u) != 0 ]]; then
  mkdir -p "$dir/read_only" && chmod 555 "$dir/read_only"
  unwritable+=("$dir/read_only")
fi
for format in csv bin npy mat mat73 h5; do
  extension=$format
  [[ $format == mat73 ]] && extension=mat
  for place in "${unwritable[@]}"; do
    target=$place/record.$extension
    leaves_nothing "$format into $place" "momentid: $target: " \
      "$momentid" simulate "$model" --samples 1000 --format "$format" -o "$target"
    if [[ -d $place ]] && [[ -n $(ls -A "$place") ]]; then
      echo "FAILED: $format into $place leaves $(ls -A "$place")"
      failed=1
    fi
  done
  target=$dir/out/record.$extension
  leaves_nothing "blow-up of $format" "momentid: the simulation blew up: " \
    "$momentid" simulate "$model" --set eps=-1 --input ma:K=10,w=0.1,sigma=20 --burn-in 0 \
    --format "$format" -o "$target"
done
exit $failed
