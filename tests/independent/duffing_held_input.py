#!/usr/bin/python3
"""The held-input correction, on records that numpy and scipy made.

The Duffing oscillator (c = 0.5, k = 4, eps = 1) is driven by a force held constant over each
sample interval of dt = 0.04 s: a moving average of 10 Gaussian values (sigma 20 after the
average), new at every sample. 40 runs of 5000 samples, after 25 s from rest, are integrated
together by scipy's DOP853 (tolerance 1e-10), one interval at a time, so that every kink of the
held force lies on an interval's end. momentid reads them as one file with a `run` column and
`input-hold=zoh`:
  - every parameter must lie within four reported standard errors of the truth;
  - without the correction c would lie more than four standard errors from the truth: the test
    would then fail.

Usage: duffing_held_input.py MOMENTID MODEL WORKDIR
"""
import json
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

from scipy_duffing import TRUTH

DT, RUNS, SAMPLES, BURN_IN, K, SIGMA = 0.04, 40, 5000, 625, 10, 20.0


def main():
    momentid, model, workdir = sys.argv[1:4]
    rng = np.random.default_rng(20261124)
    steps = BURN_IN + SAMPLES
    white = rng.standard_normal((RUNS, steps + K - 1)) * SIGMA * np.sqrt(K)
    force = np.stack([np.convolve(w, np.ones(K) / K, mode="valid") for w in white])

    def rates(_, state, x):
        y, v = state[:RUNS], state[RUNS:]
        return np.concatenate([v, -TRUTH["c"] * v - TRUTH["k"] * y - TRUTH["eps"] * y**3 + x])

    state = np.zeros(2 * RUNS)
    y = np.empty((RUNS, steps))
    v = np.empty((RUNS, steps))
    for n in range(steps):
        y[:, n], v[:, n] = state[:RUNS], state[RUNS:]
        solution = solve_ivp(rates, (0.0, DT), state, method="DOP853", args=(force[:, n],),
                             rtol=1e-10, atol=1e-10)
        assert solution.success, solution.message
        state = solution.y[:, -1]
    columns = [np.repeat(np.arange(1, RUNS + 1), SAMPLES)]
    columns += [a[:, BURN_IN:].ravel() for a in (y, v, force[:, :steps])]
    path = f"{workdir}/independent_held_input.csv"
    with open(path, "w") as out:
        out.write(f"# momentid: dt={DT:g} input-hold=zoh\nrun,y,v,x\n")
        np.savetxt(out, np.column_stack(columns), delimiter=",", fmt="%.17g")
    result = json.loads(subprocess.run([momentid, "identify", model, path, "--degree", "3",
                                        "--format", "json"],
                                       capture_output=True, text=True, check=True).stdout)
    shift = result["diagnostics"]["held_input_correction"]["shift"]
    failed = False
    for name, truth in TRUTH.items():
        p = result["parameters"][name]
        z = (p["estimate"] - truth) / p["std_error"]
        moved = shift[name] / p["std_error"]
        ok = abs(z) < 4 and (name != "c" or abs(z - moved) > 4)
        failed |= not ok
        print(f"{name}: {p['estimate']:.7g} +- {p['std_error']:.2g} ({z:+.2f} errors from the "
              f"truth), {z - moved:+.2f} without the correction, which moved it by "
              f"{shift[name]:+.3g} "
              f"{'ok' if ok else 'FAILED'}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
