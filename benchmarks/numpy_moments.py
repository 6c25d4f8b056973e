"""Baseline for bench_identify: load a momentid CSV with numpy and compute the same time averages
(held-input products by the cubic rule, the rest by the trapezoidal rule) for the given moments.

Usage: numpy_moments.py FILE STATES INPUTS MOMENT...
  STATES, INPUTS: comma-separated column names; MOMENT: exponents over states then inputs,
  comma-separated (e.g. 2,0,1 for y^2*x). Prints the seconds taken and the first moments.
"""
import sys
import time

import numpy as np


def main():
    path, states, inputs = sys.argv[1], sys.argv[2].split(","), sys.argv[3].split(",")
    moments = [[int(e) for e in m.split(",")] for m in sys.argv[4:]]
    start = time.perf_counter()
    with open(path) as f:
        header = None
        skip = 0
        for line in f:
            skip += 1
            if not line.startswith("#"):
                header = line.strip().split(",")
                break
    names = states + inputs
    columns = [header.index(n) for n in names]
    data = np.loadtxt(path, delimiter=",", skiprows=skip, usecols=columns)
    nstates = len(states)
    results = []
    for m in moments:
        g = np.ones(len(data))
        h = np.ones(len(data))
        for j, e in enumerate(m):
            if e:
                (g if j < nstates else h)[:] *= data[:, j] ** e
        if any(m[nstates:]):
            w = np.empty(len(data) - 1)
            w[1:-1] = (-g[:-3] + 13 * g[1:-2] + 13 * g[2:-1] - g[3:]) / 24
            w[0] = (5 * g[0] + 8 * g[1] - g[2]) / 12
            w[-1] = (-g[-3] + 8 * g[-2] + 5 * g[-1]) / 12
            results.append(np.mean(h[:-1] * w))
        else:
            f = g * h
            results.append(np.mean((f[:-1] + f[1:]) / 2))
    seconds = time.perf_counter() - start
    print(f"{seconds:.6f}", " ".join(f"{r:.10g}" for r in results[:3]))


if __name__ == "__main__":
    main()
