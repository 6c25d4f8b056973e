#!/usr/bin/python3
"""Refines the moment estimates of latent-state models by the simulation error, on records that
numpy made (latent_identify.py's generator: the filtered Duffing oscillator and the
two-mass chain sensed at mass 2, 10^5 samples at 0.01 s, 2% noise on the displacement and 1% on
the force, a continuous force sampled, not held).

Each record: `identify --refine` with no other option must read ok, every refined parameter within
4 of its standard errors of the truth and inside the moment estimate's 95% interval. Power: the
plain Duffing model (no filter, one mass) on the same displacement and force must not read ok,
and its refinement must move some parameter beyond the moment estimate's interval or leave a
simulation error at least twice the true model's.

Usage: refine_latent.py MOMENTID MODELS_DIR WORKDIR CASE [RECORDS]
"""
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from latent_identify import CASES, records_of, write  # noqa: E402


def identify(momentid, model, path):
    result = subprocess.run([momentid, "identify", model, path, "--refine", "--format", "json"],
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def main():
    momentid, models, workdir, case = sys.argv[1:5]
    records = int(sys.argv[5]) if len(sys.argv) > 5 else 2
    system, truth, name = CASES[case]
    model = f"{models}/" + {"filtered": "filtered_duffing.mom", "chain": "chain_sensed.mom"}[case]
    seed = {"filtered": 20261202, "chain": 20261203}[case]
    rngs = [np.random.default_rng([seed, n]) for n in range(records)]
    failed = False
    for n, (t, y, x) in enumerate(records_of(rngs, system, truth, 100000, 0.01, 60, 4.0, 1)):
        path, plain_path = f"{workdir}/refine_{case}_{n}.csv", f"{workdir}/refine_{case}_plain.csv"
        write(path, name, t, y, x)
        write(plain_path, "y", t, y, x)
        report = identify(momentid, model, path)
        status = report["diagnostics"]["status"]
        refined = report["refinement"]["parameters"]
        z = {p: (refined[p]["estimate"] - value) / refined[p]["std_error"]
             for p, value in truth.items()}
        moved = [p for p in truth if refined[p]["moved"]]
        rms = report["refinement"]["outputs"][name]["rms"]
        ok = status == "ok" and all(abs(v) < 4 for v in z.values()) and not moved
        plain = identify(momentid, f"{models}/duffing.mom", plain_path)
        plain_status = plain["diagnostics"]["status"]
        plain_moved = [p for p, v in plain["refinement"]["parameters"].items() if v["moved"]]
        plain_rms = plain["refinement"]["outputs"]["y"]["rms"]
        power = plain_status != "ok" and (plain_moved or plain_rms > 2 * rms)
        ok &= bool(power)
        failed |= not ok
        print(f"{case} record {n}: {status}, refined z " +
              ", ".join(f"{p} {v:+.2f}" for p, v in z.items()) +
              f", moved {moved or 'none'}, rms {rms:.4g}; plain Duffing {plain_status}, moved "
              f"{plain_moved or 'none'}, rms {plain_rms:.4g}: " + ("ok" if ok else "FAILED"))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
