#!/usr/bin/python3
"""Are the noise-free standard errors right? Their errors against the record's ends.

Without noise, the error of the zero-lag estimate is what the record's ends leave in its moment
equations: the rates E[(g)'] = (g(T) - g(0)) / T of powers g of the states, which the estimate
takes as 0 and `identify --format json` lists among its moments. This script simulates the
Duffing oscillator of study.py without noise for seeds 1 to N, identifies each record (least
squares and GMM, degree 3) and, per parameter:

  1. regresses the errors on the records' rates: the share of the error variance they explain,
     and the coefficients a, so that error = sum_g a_g (g(T) - g(0)) / T = (h(T) - h(0)) / T
     for the polynomial h = sum_g a_g g;
  2. compares the mean reported standard error with sqrt(2 Var(h)) / T, Var(h) over the first
     record (the two ends independent draws of the stationary state), and with the spread of
     the errors;
  3. draws pairs of ends from points of that record 5 s apart, many times N of them, and gives
     the 10%, 50% and 90% points of their spread over sqrt(2 Var(h)) / T: the range of
     spread/SE that N seeds give when the standard errors are exactly right, with the kurtosis
     of h that makes it wide; and how often such an error lies within 1.96 of those standard
     errors: the coverage of exact 95% intervals under the ends' own law.

  ends.py [--samples 1e6] [--seeds 120] [--check]

--check fails (exit 1) when the rates explain less than 80% of some error's variance: the short
version run by ctest (a few records, where the regression's 16 coefficients overfit, so it only
catches errors that are no longer the record's ends).

Uses build/momentid, or the MOMENTID environment variable.
"""
import argparse
import json
import os
import re
import subprocess
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0}
DT = 0.01


def momentid(*args):
    return subprocess.run([MOMENTID, *map(str, args)], check=True, capture_output=True,
                          text=True).stdout


def power_of(rate, y, v):
    """The values of g for the moment name E[(g)'], g a product of powers of y and v."""
    g = np.ones_like(y)
    for factor in re.fullmatch(r"E\[\((.*)\)'\]", rate).group(1).split("*"):
        name, _, exponent = factor.partition("^")
        g = g * {"y": y, "v": v}[name] ** int(exponent or 1)
    return g


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=float, default=1e6)
    parser.add_argument("--seeds", type=int, default=120)
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args()
    samples = int(args.samples)
    errors = {("ls", p): [] for p in TRUTH} | {("gmm", p): [] for p in TRUTH}
    reported = {key: [] for key in errors}
    rates, names = [], None
    with tempfile.TemporaryDirectory() as tmp:
        record = os.path.join(tmp, "record.bin")
        for seed in range(1, args.seeds + 1):
            momentid("simulate", MODEL, "--samples", samples, "--input",
                     "x=ma:K=10,w=0.1,sigma=20", "--seed", seed, "--observe", "y,v,x",
                     "--format", "bin", "-o", record)
            result = json.loads(momentid("identify", MODEL, record, "--weighting", "gmm",
                                         "--degree", 3, "--format", "json"))
            for (method, p) in errors:
                estimate = result["least_squares" if method == "ls" else "parameters"][p]
                errors[(method, p)].append(estimate["estimate"] - TRUTH[p])
                reported[(method, p)].append(estimate["std_error"])
            if names is None:
                names = [m for m in result["moments"] if m.endswith(")']")]
                momentid("convert", record, os.path.join(tmp, "first.npy"))
                first = np.load(os.path.join(tmp, "first.npy"))
            rates.append([result["moments"][m] for m in names])
    rates = np.array(rates)
    y, v = first[:, 1], first[:, 2]
    span = DT * (len(y) - 1)
    powers = np.array([power_of(m, y, v) for m in names])
    apart = int(5 / DT)
    rng = np.random.default_rng(0)

    print(f"{args.seeds} records of {samples:.0e} samples without noise\n")
    print(f"{'method':<6} {'param':<5} {'explained':>9} {'SE':>9} {'sqrt(2Var h)/T':>14} "
          f"{'spread':>9} {'kurtosis h':>10} {'spread/SE if right: 10%':>23} {'50%':>5} "
          f"{'90%':>5} {'coverage if right':>17}")
    design = np.column_stack([rates, np.ones(len(rates))])
    unexplained = []
    for (method, p), e in errors.items():
        e = np.array(e)
        coefficients, *_ = np.linalg.lstsq(design, e, rcond=None)
        explained = 1 - np.var(e - design @ coefficients) / np.var(e)
        if explained < 0.8:
            unexplained.append(f"{method} {p}")
        h = coefficients[:-1] @ powers / span
        model = np.sqrt(2 * h.var())
        points = h[::apart]
        kurtosis = np.mean((points - points.mean()) ** 4) / points.var() ** 2
        draws = rng.choice(points, (2000, 2, args.seeds))
        ratios = np.std(draws[:, 0] - draws[:, 1], axis=1, ddof=1) / model
        low, median, high = np.quantile(ratios, [0.1, 0.5, 0.9])
        differences = rng.choice(points, 200000) - rng.choice(points, 200000)
        coverage = np.mean(np.abs(differences) < 1.96 * model)
        print(f"{method:<6} {p:<5} {explained:9.1%} {np.mean(reported[(method, p)]):9.3g} "
              f"{model:14.3g} {np.std(e, ddof=1):9.3g} {kurtosis:10.0f} {low:23.2f} "
              f"{median:5.2f} {high:5.2f} {coverage:17.1%}")
    if args.check and unexplained:
        print("the rates explain less than 80% of the errors of " + ", ".join(unexplained))
        raise SystemExit(1)


if __name__ == "__main__":
    main()
