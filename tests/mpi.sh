#!/usr/bin/env bash
# mpirun -np 2 and 4 give the one-process result to the last bit, on a record cut into shards
# and on a record in several files; a data error in a shard that another process reads stops
# every process with the located error and exit status 2; an error every process finds is said
# once; a file that one process sees shorter than the others, or of the same size with other
# contents, and a pattern that matches other files on one process, are an error on every
# process; a process that stops answering ends the job after a minute.
# Usage: mpi.sh MPIRUN MOMENTID MODEL DIRECTORY
set -euo pipefail
mpirun=$1 momentid=$2 model=$3 dir=$4
rm -rf "$dir" && mkdir -p "$dir"
# The tests run as root in CI; Open MPI refuses root unless told.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
launch() { "$mpirun" --oversubscribe -np "$@"; }

"$momentid" simulate "$model" --samples 60000 --runs 2 --seed 4 -o "$dir/record.csv"
for k in 1 2 3; do
  "$momentid" simulate "$model" --samples 20000 --seed "$k" --format bin -o "$dir/part$k.bin"
done
for data in "$dir/record.csv" "$dir/part*.bin"; do
  # shellcheck disable=SC2086  # the glob is momentid's to expand
  "$momentid" identify "$model" $data --shard-size 64k --format json >"$dir/one.json"
  for n in 2 4; do
    # shellcheck disable=SC2086
    launch "$n" "$momentid" identify "$model" $data --shard-size 64k --format json >"$dir/many.json"
    if ! cmp -s "$dir/one.json" "$dir/many.json"; then
      echo "mpirun -np $n on $data differs from one process:"
      diff "$dir/one.json" "$dir/many.json" | head -20
      exit 1
    fi
    echo "mpirun -np $n on $data: the one-process result"
  done
done

# Row 100000 of the 120000, in the second half that the second process reads, is bad.
awk 'NR == 100000 { sub(/,[^,]*,/, ",oops,") } 1' "$dir/record.csv" >"$dir/bad.csv"
line=$(grep -n oops "$dir/bad.csv" | cut -d: -f1)
status=0
launch 2 "$momentid" identify "$model" "$dir/bad.csv" --shard-size 64k >"$dir/out.txt" 2>"$dir/err.txt" ||
  status=$?
expected="$dir/bad.csv:$line:"
if [[ $status -ne 2 ]] || [[ $(grep -c "^$expected.*expected a number, found 'oops'" "$dir/err.txt") -ne 1 ]] ||
  [[ -s $dir/out.txt ]]; then
  echo "a bad row read by the second process: exit $status (expected 2), standard error:"
  cat "$dir/err.txt"
  exit 1
fi
echo "a bad row read by the second process: exit 2, located once at line $line"

# An error every process finds before any pass (a model file that does not exist), and a
# command that does not share its work: said once, with the command's exit status.
status=0
launch 2 "$momentid" identify "$dir/none.mom" "$dir/record.csv" >"$dir/out.txt" 2>"$dir/err.txt" ||
  status=$?
if [[ $status -ne 2 ]] || [[ $(grep -c "none.mom: cannot open the model file" "$dir/err.txt") -ne 1 ]]; then
  echo "a missing model under mpirun: exit $status (expected 2), standard error:"
  cat "$dir/err.txt"
  exit 1
fi
status=0
launch 2 "$momentid" derive "$model" >"$dir/out.txt" 2>"$dir/err.txt" || status=$?
if [[ $status -ne 1 ]] || [[ $(grep -c "run derive as one process" "$dir/err.txt") -ne 1 ]]; then
  echo "derive under mpirun: exit $status (expected 1), standard error:"
  cat "$dir/err.txt"
  exit 1
fi
echo "errors every process has: said once, exit 2 and 1"

# Each process runs in a directory of its own, rank0 or rank1, which the cases below fill.
for r in 0 1; do mkdir -p "$dir/rank$r"; done

# on_each_rank CASE EXPECTED DATA: identify DATA in each process's own directory under mpirun -np
# 2 must end with exit status 2, print nothing, and say EXPECTED once.
on_each_rank() {
  local case=$1 expected=$2 data=$3 status=0
  # shellcheck disable=SC2016  # the rank is the launched shell's to expand
  launch 2 bash -c 'cd "$1/rank$OMPI_COMM_WORLD_RANK" && exec "$2" identify "$3" "$4"' \
    - "$dir" "$momentid" "$model" "$data" >"$dir/out.txt" 2>"$dir/err.txt" || status=$?
  if [[ $status -ne 2 ]] || [[ $(grep -cxF "$expected" "$dir/err.txt") -ne 1 ]] ||
     [[ -s $dir/out.txt ]]; then
    echo "$case: exit $status (expected 2), standard error:"
    cat "$dir/err.txt"
    exit 1
  fi
  echo "$case: exit 2, $expected"
}

# One process sees a shorter copy of the record (a stale copy on one node): the whole record or
# its first 90000 rows.
cp "$dir/record.csv" "$dir/rank0/record.csv"
head -n 90000 "$dir/record.csv" >"$dir/rank1/record.csv"
sizes="$(stat -c %s "$dir/rank0/record.csv") on process 0, $(stat -c %s "$dir/rank1/record.csv") on process 1"
on_each_rank "one process seeing a shorter file" \
  "momentid: record.csv: the processes of the job see different files (bytes: $sizes): give every process the same file" \
  record.csv

# One process sees another record of the same size (a stale binary record of the same length).
cp "$dir/part1.bin" "$dir/rank0/record.bin"
cp "$dir/part2.bin" "$dir/rank1/record.bin"
on_each_rank "one process seeing another file of the same size" \
  "momentid: record.bin: the processes of the job see different files ($(stat -c %s "$dir/part1.bin") bytes each, other contents on process 1 than on process 0): give every process the same file" \
  record.bin

# A pattern that matches other files on one process (two parts there, three on the other).
cp "$dir"/part[12].bin "$dir/rank0/"
cp "$dir"/part[123].bin "$dir/rank1/"
on_each_rank "a pattern matching other files on one process" \
  "momentid: part1.bin and 1 more file: the processes of the job see different files (2 files on process 0, 3 on process 1): give every process the same files" \
  "part*.bin"

# A process that stops answering (here it waits for a writer to a FIFO that never comes, before
# the pass): the others give up after a minute, and the job ends with exit status 2.
rm -f "$dir/rank1/record.csv" && mkfifo "$dir/rank1/record.csv"
status=0
start=$SECONDS
# shellcheck disable=SC2016
launch 2 bash -c 'cd "$1/rank$OMPI_COMM_WORLD_RANK" && exec "$2" identify "$3" record.csv' \
  - "$dir" "$momentid" "$model" >"$dir/out.txt" 2>"$dir/err.txt" || status=$?
expected="momentid (process 0): waited 60 s for the other processes of the job to finish their part of the pass (one has stopped, or is far slower): the job ends"
if [[ $status -ne 2 ]] || [[ $(grep -cxF "$expected" "$dir/err.txt") -ne 1 ]]; then
  echo "a process that stops answering: exit $status (expected 2), standard error:"
  cat "$dir/err.txt"
  exit 1
fi
echo "a process that stops answering: exit 2 after $((SECONDS - start)) s, $expected"
