#!/usr/bin/env bash
# Installs momentid from the build directory $1 into a staging prefix under $2, builds the
# library example (examples/library) against it as a separate project would, and runs it.
set -euo pipefail
build=$1 work=$2 source=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$source/examples/library" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/build" >/dev/null
cd "$work" && ./build/identify_duffing "$source/models/duffing.mom"
