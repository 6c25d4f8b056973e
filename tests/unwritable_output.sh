#!/usr/bin/env bash
# A report that cannot reach standard output (a full disk, a closed descriptor) ends with exit
# status 2 and one line naming the cause, for every command that prints one (simulate its samples).
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
exit $failed
