#!/usr/bin/python3
"""Identifies the Duffing oscillator from a record that numpy and scipy made, not momentid.

The record holds displacement and force only (no velocity), sampled every 0.01 s: the lagged
moment equations must recover c = 0.5, k = 4, eps = 1. The force is a sum of 60 sinusoids with
random frequencies and phases, evaluated exactly by the integrator (scipy's DOP853, tolerance
1e-10), so the samples are those of continuous signals (input hold `sample`). Without sensor
noise the equations hold on the record itself, so the estimates are exact to the integrator's
and the stencils' accuracy (1e-6 here); with 3% white noise that numpy adds to y they must lie
within four reported standard errors.

Usage: duffing_lagged.py MOMENTID MODEL WORKDIR
"""
import json
import subprocess
import sys

import numpy as np

from scipy_duffing import TRUTH, duffing


def main():
    momentid, model, workdir = sys.argv[1:4]
    rng = np.random.default_rng(20261123)
    dt, burn_in, samples = 0.01, 100.0, 200000
    t = burn_in + dt * np.arange(samples)
    clean, _, force = duffing(rng, 0.3, 6.0, 60, 6.0, t, 1e-10)  # force RMS 6
    failed = False
    for noise in (0.0, 0.03):
        y = clean + noise * np.std(clean) * rng.standard_normal(samples)
        path = f"{workdir}/independent_duffing.csv"
        with open(path, "w") as out:
            out.write("# momentid: dt=0.01 input-hold=sample\nt,y,x\n")
            np.savetxt(out, np.column_stack([t, y, force(t)]), delimiter=",", fmt="%.17g")
        result = subprocess.run([momentid, "identify", model, path, "--format", "json"],
                                capture_output=True, text=True, check=True)
        report = json.loads(result.stdout)
        assert report["method"]["name"] == "lagged", report["method"]
        for name, truth in TRUTH.items():
            p = report["parameters"][name]
            error = p["estimate"] - truth
            if noise == 0:
                ok = abs(error) < 1e-6 * truth
            else:
                # Four reported standard errors, and 2% as a plain bound.
                ok = abs(error) < 4 * p["std_error"] and abs(error) < 0.02 * truth
            failed |= not ok
            print(f"noise {noise:.0%}: {name}: {p['estimate']:.9g} (truth {truth}, std error "
                  f"{p['std_error']:.3g}, relative error {error / truth:+.5%}) "
                  f"{'ok' if ok else 'FAILED'}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
