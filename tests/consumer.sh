#!/usr/bin/env bash
# Installs momentid from the build directory $1 into a staging prefix under $2, builds the
# library example (examples/library) against it as a separate project would, and runs it on a
# record that the installed executable simulates.
set -euo pipefail
build=$1 work=$2 source=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$source/examples/library" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" >/dev/null
cd "$work"
./prefix/bin/momentid simulate "$source/models/duffing.mom" --input ma:K=10,w=0.1,sigma=20 \
  --samples 100000 -o duffing.csv
./build/identify_duffing "$source/models/duffing.mom" duffing.csv
