#!/usr/bin/env bash
# The whole method on the Duffing oscillator: derive the moment equations, simulate data with
# known parameters (c = 0.5, k = 4, eps = 1), and identify the parameters from the data.
#
# Usage: examples/quickstart.sh [SAMPLES]   (default 200000; uses build/momentid, or $MOMENTID)
set -euo pipefail
cd "$(dirname "$0")/.."
momentid=${MOMENTID:-build/momentid}
samples=${1:-200000}
data=$(mktemp --suffix=.csv)
trap 'rm -f "$data"' EXIT

echo "== momentid derive models/duffing.mom --degree 3"
"$momentid" derive models/duffing.mom --degree 3
echo
echo "== momentid simulate models/duffing.mom --samples $samples --input ma:K=10,w=0.1,sigma=20"
"$momentid" simulate models/duffing.mom --samples "$samples" --input ma:K=10,w=0.1,sigma=20 \
  --seed 1 -o "$data"
echo "wrote $samples samples (true values: c = 0.5, k = 4, eps = 1)"
echo
echo "== momentid identify models/duffing.mom DATA --degree 3"
"$momentid" identify models/duffing.mom "$data" --degree 3
