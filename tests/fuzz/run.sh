#!/usr/bin/env bash
# Builds the fuzz targets with clang (libFuzzer, ASan, UBSan) and runs one for a given time.
#
# Usage: tests/fuzz/run.sh model|data SECONDS [extra libFuzzer options]
# The corpus grows in build-fuzz/corpus-TARGET (seeded from models/ or tests/data/); crashes
# and hangs are written to build-fuzz/findings-TARGET/.
set -euo pipefail
cd "$(dirname "$0")/../.."
target=$1
seconds=$2
shift 2
cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DMOMENTID_FUZZ=ON -DMOMENTID_BUILD_TESTS=OFF -DMOMENTID_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-fuzz -j2 --target "fuzz_$target" >/dev/null
if [[ $target == data ]]; then cmake --build build-fuzz -j2 --target momentid >/dev/null; fi
corpus=build-fuzz/corpus-$target
findings=build-fuzz/findings-$target
mkdir -p "$corpus" "$findings"
if [[ $target == model ]]; then
  cp -n models/*.mom tests/data/*.mom "$corpus"/ 2>/dev/null || true
else
  cp -n tests/data/*.csv tests/expected/*.csv "$corpus"/ 2>/dev/null || true
  # Small files of the other formats, so that mutations reach their readers.
  for format in bin npy mat mat73 h5; do
    [[ -e $corpus/seed.$format ]] || build-fuzz/momentid convert tests/data/two_runs.csv \
      "$corpus/seed.$format" --format "$format" 2>/dev/null || true
  done
fi
# matio allocates what a damaged header claims before the reader can refuse it (a 1.5 kB file
# asked calloc for 4.8 GB). A normal build survives that, as the memory is never touched, and
# refuses the file with exit status 2; here an allocation above 128 MB fails instead, as matio
# handles, rather than ending the run. Inputs of at most 4096 bytes need far less: the reader
# refuses a variable that claims more than 1032 values per byte of its file (34 MB a column).
export ASAN_OPTIONS=allocator_may_return_null=1:max_allocation_size_mb=128${ASAN_OPTIONS:+:$ASAN_OPTIONS}
exec "build-fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -timeout=10 \
  -rss_limit_mb=4096 -max_len=4096 -artifact_prefix="$findings/" -print_final_stats=1 "$@"
