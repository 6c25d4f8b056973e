#!/usr/bin/python3
"""The J test's size and power, and its law, on records numpy makes (lab_records.py), not momentid.

Two cases, each identified with no options by the true model and by wrong ones:
  duffing   the Duffing oscillator of lab.SDOF driven by a shaker force, y and x recorded at
            1024 Hz, 10^5 samples, 3% white noise on y and 1% on x; wrong models: a linear
            spring (the cubic term left out) and a quintic spring instead of the cubic;
  friction  Coulomb friction (nonsmooth_records.py, f = 120), y, v and x with 2% noise, 10^5
            samples; the wrong model: quadratic drag c2 |v| v instead of f sign(v).
Printed per model: how often the J test rejects at 5% and at 1%, how often the zero-lag check
does at 1%, how often the law check does (the other law of v added, |z| > 4), how many records
read `ok`, the median of J over its degrees of freedom, and the median of its law's parameters
(JLaw: F(dof, denominator_dof) of J/dof times scale). The test fails when the true model is
rejected at 5% more often than three binomial standard errors above 5%, or reads `ok` on fewer
than all records but one; or when a wrong Duffing model reads `ok` on more than a tenth of the
records, the drag model on friction records on any (the J test sees a wrong non-smooth law
weakly; the law check sees it: docs/uncertainty.md).

Usage: j_power.py duffing|friction MOMENTID WORKDIR [SEEDS]
"""
import json
import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np

import lab_records as lab
import nonsmooth_records as nonsmooth

FS = 1024
SAMPLES = 100000
# The friction records' integration tolerance: their error up to 4e-5 of each state's standard
# deviation (measured against 1e-7 on one record), 500 times below the 2% sensor noise, in 45%
# of the time of the module's default.
RTOL = 1e-6
MODELS = {
    "duffing": {"true": ("c, k, eps, b", "-c*v - k*y - eps*y^3 + b*x"),
                "linear": ("c, k, b", "-c*v - k*y + b*x"),
                "quintic": ("c, k, eps, b", "-c*v - k*y - eps*y^5 + b*x")},
    "friction": {"true": ("c, f, k", "-c*v - f*sign(v) - k*y + x"),
                 "drag": ("c, c2, k", "-c*v - c2*abs(v)*v - k*y + x")},
}


def model_text(name, params, rates):
    values = ", ".join(f"{p} = 1" for p in params.split(", "))
    return f"model {name}\nstate y, v\ninput x\nparam {values}\ny' = v\nv' = {rates}\n"


def record(case, workdir, seed):
    rng = np.random.default_rng(20271900 + seed)
    path = os.path.join(workdir, f"{case}{seed}.csv")
    if case == "duffing":
        clean = lab.sdof(rng, FS, SAMPLES)
        lab.write_csv(path, {"t": clean["t"], "y": lab.measured(rng, clean["y"], 0.03),
                             "x": lab.measured(rng, clean["x"], 0.01)})
    else:
        nonsmooth.write(path, nonsmooth.record("friction", rng, SAMPLES, rtol=RTOL), noise=0.02,
                        rng=rng)
    return path


def j_test(momentid, model, path):
    result = subprocess.run([momentid, "identify", model, path, "--format", "json", "--quiet"],
                            capture_output=True, text=True, check=True)
    report = json.loads(result.stdout)
    d = report["diagnostics"]
    law = d["j_law"]
    check = d.get("zero_lag_check") or {}
    laws = d.get("law_check", [])
    return (d["j_statistic"] / d["j_dof"], d["j_pvalue"], law["dof"], law["denominator_dof"],
            law["scale"], d["status"] == "ok",
            np.nan if check.get("p_value") is None else check["p_value"],
            max((abs(c["z"]) for c in laws), default=np.nan))


def main():
    case, momentid = sys.argv[1], sys.argv[2]
    workdir = os.path.join(sys.argv[3], "j_power")
    seeds = int(sys.argv[4]) if len(sys.argv) > 4 else 20
    os.makedirs(workdir, exist_ok=True)
    with ProcessPoolExecutor(2) as pool:
        paths = list(pool.map(record, [case] * seeds, [workdir] * seeds, range(seeds)))
    print(f"{case}, {seeds} records")
    print(f"{'model':10} {'5%':>6} {'1%':>6} {'check':>6} {'laws':>6} {'ok':>4} {'J/dof':>8} "
          f"{'law dof':>8} {'denom':>8} {'scale':>6}")
    passed = True
    for name, (params, rates) in MODELS[case].items():
        model = os.path.join(workdir, f"{case}_{name}.mom")
        with open(model, "w") as out:
            out.write(model_text(name, params, rates))
        with ThreadPoolExecutor(2) as pool:
            r = np.array(list(pool.map(lambda path: j_test(momentid, model, path), paths)))
        rejected, ok = int(np.sum(r[:, 1] < 0.05)), int(r[:, 5].sum())
        print(f"{name:10} {rejected / seeds:6.2f} {np.mean(r[:, 1] < 0.01):6.2f} "
              f"{np.mean(r[:, 6] < 0.01):6.2f} {np.mean(r[:, 7] > 4):6.2f} {ok:4d} "
              f"{np.median(r[:, 0]):8.3g} {np.median(r[:, 2]):8.3g} {np.median(r[:, 3]):8.3g} "
              f"{np.median(r[:, 4]):6.3f}")
        if name == "true":
            passed &= rejected <= int(0.05 * seeds + 3 * np.sqrt(seeds * 0.05 * 0.95))
            passed &= ok >= seeds - 1
        else:
            passed &= ok <= (seeds // 10 if case == "duffing" else 0)
    print("PASS" if passed else "FAIL")
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())
