#!/usr/bin/python3
"""Identifies models with latent states from records that numpy and scipy made, with no options.

filtered: the Duffing oscillator behind a first-order input filter whose output z no sensor reads
  (models/filtered_duffing.mom): y'' = -c y' - k y - eps y^3 + g z, z' = -a z + 2 x, with c 0.5,
  k 4, eps 1, a 2, g 1. The record holds y and x.
chain: two masses on linear springs and dampers to the ground and to each other, a cubic spring
  at mass 2, the force at mass 2, a sensor on mass 2 only (models/chain_sensed.mom, mass 1
  latent): y1'' = -c1 y1' - k1 y1 - c2 (y1' - y2') - k2 (y1 - y2), y2'' = -c2 (y2' - y1') -
  k2 (y2 - y1) - eps y2^3 + x, with c1 0.3, k1 5, c2 0.2, k2 3, eps 1. The record holds y2 and x.

The force is a sum of 60 cosines of random frequencies in 0.3..6 rad/s (RMS 4), evaluated exactly
by DOP853 (tolerance 1e-9); the record holds the measured displacement and the force at 0.01 s
with 2% and 1% white noise (of their RMS), 10^5 samples. Each parameter must lie within 4 of its
standard errors, status ok, on every record; the plain Duffing model (no filter, one mass) on the
same displacement and force must not read ok: the check has power.

Usage: latent_identify.py MOMENTID MODELS_DIR WORKDIR CASE [RECORDS]
"""
import json
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp


def filtered(p, force):
    def rates(time, s):
        y, v, z = s
        return [v, -p["c"] * v - p["k"] * y - p["eps"] * y**3 + p["g"] * z,
                -p["a"] * z + 2.0 * force(time)]
    return rates, 3, 0


def chain(p, force):
    def rates(time, s):
        y1, v1, y2, v2 = s
        return [v1, -p["c1"] * v1 - p["k1"] * y1 - p["c2"] * (v1 - v2) - p["k2"] * (y1 - y2),
                v2, -p["c2"] * (v2 - v1) - p["k2"] * (y2 - y1) - p["eps"] * y2**3 + force(time)]
    return rates, 4, 2


CASES = {
    "filtered": (filtered, {"c": 0.5, "k": 4.0, "eps": 1.0, "a": 2.0, "g": 1.0}, "y"),
    "chain": (chain, {"c1": 0.3, "k1": 5.0, "c2": 0.2, "k2": 3.0, "eps": 1.0}, "y2"),
}


def record(rng, system, truth, samples, dt):
    omega = rng.uniform(0.3, 6.0, 60)
    phase = rng.uniform(0, 2 * np.pi, 60)
    amplitude = 4.0 * np.sqrt(2 / 60)

    def force(time):
        return amplitude * np.cos(np.multiply.outer(time, omega) + phase).sum(axis=-1)

    rates, size, measured = system(truth, force)
    t = 50.0 + dt * np.arange(samples)
    solution = solve_ivp(rates, (0.0, t[-1]), np.zeros(size), method="DOP853", t_eval=t,
                         rtol=1e-9, atol=1e-9)
    assert solution.success, solution.message
    y, x = solution.y[measured], force(t)
    y = y + 0.02 * np.std(y) * rng.standard_normal(samples)
    x = x + 0.01 * np.std(x) * rng.standard_normal(samples)
    return t, y, x


def identify(momentid, model, path):
    result = subprocess.run([momentid, "identify", model, path, "--format", "json"],
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout)


def write(path, name, t, y, x):
    with open(path, "w") as out:
        out.write(f"t,{name},x\n")
        np.savetxt(out, np.column_stack([t, y, x]), delimiter=",", fmt="%.9g")


def main():
    momentid, models, workdir, case = sys.argv[1:5]
    records = int(sys.argv[5]) if len(sys.argv) > 5 else 3
    system, truth, name = CASES[case]
    model = f"{models}/" + {"filtered": "filtered_duffing.mom", "chain": "chain_sensed.mom"}[case]
    rng = np.random.default_rng({"filtered": 20261130, "chain": 20261201}[case])
    failed = False
    for n in range(records):
        t, y, x = record(rng, system, truth, 100000, 0.01)
        path, plain_path = f"{workdir}/latent_{case}_{n}.csv", f"{workdir}/latent_{case}_plain.csv"
        write(path, name, t, y, x)
        write(plain_path, "y", t, y, x)
        report = identify(momentid, model, path)
        status = report["diagnostics"]["status"]
        z = {p: (report["parameters"][p]["estimate"] - value) /
             report["parameters"][p]["std_error"] for p, value in truth.items()}
        ok = status == "ok" and all(abs(v) < 4 for v in z.values())
        plain = identify(momentid, f"{models}/duffing.mom", plain_path)["diagnostics"]["status"]
        ok &= plain != "ok"
        failed |= not ok
        latent = report["latent"]
        print(f"{case} record {n}: {status}, z " +
              ", ".join(f"{p} {v:+.2f}" for p, v in z.items()) +
              f"; Q {latent['distance']:.3g} on {latent['dof']} dof; plain Duffing {plain}: " +
              ("ok" if ok else "FAILED"))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
