#!/usr/bin/python3
"""Identifies the Duffing oscillator behind a first-order input filter whose output no sensor
reads (models/filtered_duffing.mom, the latent state z), from records that numpy and scipy made.

The model, written here: y'' = -c y' - k y - eps y^3 + g z, z' = -a z + 2 x, with c 0.5, k 4,
eps 1, a 2, g 1, driven by a force x that is a sum of 60 cosines of random frequencies in
0.3..6 rad/s (RMS 4), evaluated exactly by DOP853 (tolerance 1e-9). The record holds y and x at
0.01 s with 2% white noise on y and 1% on x (of their RMS), and no z. With no options, identify
must eliminate z, read the equation without it from the lagged moments and give c, k, eps, a
and g each within 4 of its standard errors, status ok, on every record. The plain Duffing model
(no filter) on the same records must not read ok: the check has power.

Usage: latent_identify.py MOMENTID MODELS_DIR WORKDIR [RECORDS]
"""
import json
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0, "a": 2.0, "g": 1.0}
GAIN = 2.0  # the filter's gain, a constant of the model


def record(rng, samples, dt):
    omega = rng.uniform(0.3, 6.0, 60)
    phase = rng.uniform(0, 2 * np.pi, 60)
    amplitude = 4.0 * np.sqrt(2 / 60)

    def force(time):
        return amplitude * np.cos(np.multiply.outer(time, omega) + phase).sum(axis=-1)

    def rates(time, s):
        y, v, z = s
        return [v, -TRUTH["c"] * v - TRUTH["k"] * y - TRUTH["eps"] * y**3 + TRUTH["g"] * z,
                -TRUTH["a"] * z + GAIN * force(time)]

    t = 50.0 + dt * np.arange(samples)
    solution = solve_ivp(rates, (0.0, t[-1]), [0.0, 0.0, 0.0], method="DOP853", t_eval=t,
                         rtol=1e-9, atol=1e-9)
    assert solution.success, solution.message
    y, x = solution.y[0], force(t)
    y = y + 0.02 * np.std(y) * rng.standard_normal(samples)
    x = x + 0.01 * np.std(x) * rng.standard_normal(samples)
    return t, y, x


def identify(momentid, model, path):
    result = subprocess.run([momentid, "identify", model, path, "--format", "json"],
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def main():
    momentid, models, workdir = sys.argv[1:4]
    records = int(sys.argv[4]) if len(sys.argv) > 4 else 3
    rng = np.random.default_rng(20261130)
    failed = False
    for n in range(records):
        t, y, x = record(rng, 100000, 0.01)
        path = f"{workdir}/latent_identify_{n}.csv"
        with open(path, "w") as out:
            out.write("t,y,x\n")
            np.savetxt(out, np.column_stack([t, y, x]), delimiter=",", fmt="%.9g")
        report = identify(momentid, f"{models}/filtered_duffing.mom", path)
        status = report["diagnostics"]["status"]
        z = {name: (report["parameters"][name]["estimate"] - truth) /
             report["parameters"][name]["std_error"] for name, truth in TRUTH.items()}
        ok = status == "ok" and all(abs(v) < 4 for v in z.values())
        plain = identify(momentid, f"{models}/duffing.mom", path)["diagnostics"]["status"]
        ok &= plain != "ok"
        failed |= not ok
        latent = report["latent"]
        print(f"record {n}: {status}, z " +
              ", ".join(f"{name} {v:+.2f}" for name, v in z.items()) +
              f"; Q {latent['distance']:.3g} on {latent['dof']} dof; plain Duffing {plain}: " +
              ("ok" if ok else "FAILED"))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
