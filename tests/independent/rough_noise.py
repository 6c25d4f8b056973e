#!/usr/bin/python3
"""The noise on a displacement that a coarsely sampled record cannot tell from its signal, on
records made by numpy (lab_records.py), not momentid.

The Duffing oscillator of lab_records.SDOF with a damping ratio of 0.02 (c = 1.28), driven by a
shaker force up to 0.4 of the sample rate, integrated at 4 times the rate and sampled at 9
samples a period of its linear resonance; 2% noise on y and 1% on the force, 10^5 samples. Its
harmonics and the force's upper band make y rough at the sample scale: the sixth differences
that estimate the noise read about 12 times its variance, and the Hermite correction of y^3
that takes it moves k by about one standard error. `identify` with no option:

  - names the range on every record (the fourth differences beyond 1.25 times the sixth, up to
    100% of the estimate signal), and reads `ok` on at least 90% of them (the J test's size);
  - k's z = (estimate - truth) / standard error has a mean within 3/sqrt(N) of 0 and its 95%
    intervals cover the truth on at least 95% less three binomial standard errors of the
    records; the same records solved at the sixth differences' noise (given with --noise, as
    the estimate was before the range) fail that test, which shows its power;
  - on records of the same oscillator sampled at 1024 Hz (200 samples a period) no range is
    named.

Usage: rough_noise.py MOMENTID WORKDIR [RECORDS]
"""
import json
import os
import subprocess
import sys

import numpy as np

import lab_records as lab

ZETA, PER_PERIOD, FINE, SAMPLES = 0.02, 9, 4, 100000
MODEL = "state y, v\ninput x\nparam c, k, eps\ny' = v\nv' = -c*v - k*y - eps*y^3 + x\n"


def identify(momentid, model, path, *options):
    out = subprocess.run([momentid, "identify", model, path, "--format", "json", *options],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def coarse_records(workdir, count):
    p = dict(lab.SDOF, c=2 * ZETA * np.sqrt(lab.SDOF["k"]))
    f0 = np.sqrt(p["k"]) / (2 * np.pi)
    fs = PER_PERIOD * f0
    rngs = [np.random.default_rng(7000 + r) for r in range(count)]
    clean = lab.oscillators(rngs, lab.sdof_rates(p), ("y", "v"), FINE * fs, FINE * SAMPLES,
                            (0.5, 0.4 * fs), 800.0 * np.sqrt(ZETA / 0.0625), 10 / ZETA / f0)
    paths = []
    for r, record in enumerate(clean):
        y, x = record["y"][::FINE], record["x"][::FINE]
        columns = {"t": np.arange(SAMPLES) / fs,
                   "y": y + 0.02 * np.std(y) * rngs[r].standard_normal(SAMPLES),
                   "x": x + 0.01 * np.std(x) * rngs[r].standard_normal(SAMPLES)}
        paths.append(f"{workdir}/coarse_{r}.csv")
        lab.write_csv(paths[-1], columns)
    return paths, p


def coverage(name, zs):
    zs = np.array(zs)
    n = zs.size
    cover = np.mean(np.abs(zs) < 1.96)
    least = 0.95 - 3 * np.sqrt(0.95 * 0.05 / n)
    print(f"  {name}: k's z mean {zs.mean():+.2f} sd {zs.std(ddof=1):.2f}, 95% intervals cover "
          f"{cover:.0%} (at least {least:.0%} and a mean within {3 / np.sqrt(n):.2f} wanted)")
    return abs(zs.mean()) <= 3 / np.sqrt(n) and cover >= least


def main():
    momentid, workdir = sys.argv[1], sys.argv[2]
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 20
    workdir = f"{workdir}/rough_noise"
    os.makedirs(workdir, exist_ok=True)
    model = f"{workdir}/duffing.mom"
    with open(model, "w") as out:
        out.write(MODEL)
    passed = True
    paths, truth = coarse_records(workdir, count)
    z, z_given = [], []
    ok = 0
    for path in paths:
        report = identify(momentid, model, path)
        rough = report["method"]["rough_noise"]
        status = report["diagnostics"]["status"]
        k = report["parameters"]["k"]
        z.append((k["estimate"] - truth["k"]) / k["std_error"])
        print(f"{os.path.basename(path)}: {status}, k z {z[-1]:+.2f}, range {rough}")
        passed &= rough is not None and rough["share"] > 0.9
        ok += status == "ok"
        sixth = rough["sixth_difference"] if rough else report["method"]["noise_variance"]["y"]
        given = identify(momentid, model, path, "--noise", f"y={sixth!r}")
        k = given["parameters"]["k"]
        z_given.append((k["estimate"] - truth["k"]) / k["std_error"])
        passed &= given["method"]["rough_noise"] is None
    print(f"  {ok} of {count} records `ok` (at least 90% wanted: the J test's size is 1%)")
    passed &= ok >= 0.9 * count and coverage("the defaults", z)
    if coverage("solved at the sixth differences' noise", z_given):
        print("  the test has no power on these records")
        passed = False
    for seed in (7100, 7101):
        clean = lab.sdof(np.random.default_rng(seed), 1024, SAMPLES)
        rng = np.random.default_rng(seed + 1)
        path = f"{workdir}/lab_{seed}.csv"
        lab.write_csv(path, {"t": clean["t"], "y": lab.measured(rng, clean["y"], 0.02),
                             "x": lab.measured(rng, clean["x"], 0.01)})
        rough = identify(momentid, model, path)["method"]["rough_noise"]
        print(f"1024 Hz record {seed}: range {rough}")
        passed &= rough is None
    print("PASS" if passed else "FAIL")
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())
