#!/usr/bin/python3
"""How honest are momentid's standard errors, intervals and J test? A coverage study.

The Duffing oscillator (c = 0.5, k = 4, eps = 1; moving-average force K = 10, w = 0.1,
sigma = 20; dt = 0.01) is simulated with many seeds at each record length and noise level, and
identified each time:

  noise 0     y, v and x recorded; the zero-lag equations, degree 3
  noise f > 0 y and x recorded, white noise of f times the standard deviation of y added to
              y; the lagged equations (momentid's correction for measured data)

Each record is identified with the right model (least squares and the optimally weighted
estimate, `--weighting gmm`) and with the linear model (eps = 0) for the power of the J test.
Per cell and parameter the study reports the coverage of the 95% intervals, the spread of the
estimates across seeds over their mean standard error (spread/SE; 1 when the errors are
right), the bias over the mean standard error, the J test's rejection rate of the right model
at the 5% level (its size: 5% when right) and of the linear model (its power).

  study.py [--sizes 1e5:100,1e6:100,1e7:20] [--noise 0,0.01,0.05] [--summary OUT.txt]
           [--plot OUT.png] [--check]

--check fails (exit 1) when the coverage of any interval collapses below 50%: the short
version run by ctest. Uses build/momentid, or the MOMENTID environment variable.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0}
INPUT = "x=ma:K=10,w=0.1,sigma=20"
LINEAR = """model linear "the Duffing oscillator without its cubic term"
state y, v
input x
param c = 0.5, k = 4
y' = v
v' = -c*v - k*y + x
"""


def momentid(*args):
    return subprocess.run([MOMENTID, *map(str, args)], check=True, capture_output=True,
                          text=True).stdout


def one_run(samples, noise, seed, tmp, linear):
    """The estimates of one record: {method: {parameter: (estimate, error, low, high)}}, the J
    test's p-values of the right and the linear model, and the least-squares standard errors
    with half and with twice the default batch count, over those with the default."""
    record = os.path.join(tmp, "record.bin")
    observe = "y,v,x" if noise == 0 else "y,x"
    command = ["simulate", MODEL, "--samples", samples, "--input", INPUT, "--seed", seed,
               "--observe", observe, "--format", "bin", "-o", record]
    if noise > 0:
        command += ["--noise", f"y={noise}"]
    momentid(*command)
    options = ["--weighting", "gmm", "--format", "json"]
    if noise == 0:
        options += ["--degree", "3"]
    result = json.loads(momentid("identify", MODEL, record, *options))
    out = {}
    for method, key in (("ls", "least_squares"), ("gmm", "parameters")):
        out[method] = {name: (p["estimate"], p["std_error"], *p["ci95"])
                       for name, p in result[key].items()}
    right_p = result["diagnostics"].get("j_pvalue")
    wrong = json.loads(momentid("identify", linear, record, *options))
    batches = result["diagnostics"]["batches"]
    ratios = []
    for factor in (0.5, 2):
        other = json.loads(momentid("identify", MODEL, record, *options, "--batches",
                                    int(batches * factor)))
        ratios.append({name: p["std_error"] / out["ls"][name][1]
                       for name, p in other["least_squares"].items()})
    return out, right_p, wrong["diagnostics"].get("j_pvalue"), ratios


def cell(samples, noise, seeds):
    with tempfile.TemporaryDirectory() as tmp:
        linear = os.path.join(tmp, "linear.mom")
        with open(linear, "w") as f:
            f.write(LINEAR)
        runs = [one_run(samples, noise, seed, tmp, linear) for seed in range(1, seeds + 1)]
    rows = []
    for method in ("ls", "gmm"):
        for name, truth in TRUTH.items():
            values = np.array([r[0][method][name] for r in runs])
            estimate, error, low, high = values.T
            spread = estimate.std(ddof=1)
            rows.append({"method": method, "parameter": name,
                         "coverage": float(np.mean((low <= truth) & (truth <= high))),
                         "spread_se": float(spread / error.mean()),
                         "bias_se": float((estimate.mean() - truth) / error.mean())})
    right = [r[1] for r in runs if r[1] is not None]
    wrong = [r[2] for r in runs if r[2] is not None]
    size = float(np.mean(np.array(right) < 0.05)) if right else float("nan")
    power = float(np.mean(np.array(wrong) < 0.05)) if wrong else float("nan")
    # Per parameter: the mean least-squares error with half and twice the batches over the mean
    # with the default, and the median change of one record's error.
    batches = {}
    for name in TRUTH:
        default = np.mean([r[0]["ls"][name][1] for r in runs])
        batches[name] = [(float(np.mean([r[0]["ls"][name][1] * r[3][k][name] for r in runs]) /
                                default),
                          float(np.median([abs(r[3][k][name] - 1) for r in runs])))
                         for k in (0, 1)]
    return rows, size, power, batches


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1e5:100,1e6:100,1e7:20",
                        help="record lengths and seeds, SAMPLES:SEEDS,...")
    parser.add_argument("--noise", default="0,0.01,0.05")
    parser.add_argument("--summary", default=None)
    parser.add_argument("--plot", default=None)
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args()
    sizes = [(int(float(a)), int(b)) for a, b in (s.split(":") for s in args.sizes.split(","))]
    noises = [float(n) for n in args.noise.split(",")]

    lines = [f"{'samples':>9} {'seeds':>5} {'noise':>5} {'method':<6} {'param':<5} "
             f"{'coverage':>8} {'spread/SE':>9} {'bias/SE':>8}"]
    tests = [f"{'samples':>9} {'noise':>5} {'J size (5%)':>11} {'power vs linear':>15}"]
    halved = [f"{'samples':>9} {'noise':>5} {'param':<5} {'SE(B/2)/SE(B)':>13} {'median change':>13} "
              f"{'SE(2B)/SE(B)':>12} {'median change':>13}"]
    results = []
    for samples, seeds in sizes:
        for noise in noises:
            rows, size, power, batches = cell(samples, noise, seeds)
            results.append((samples, noise, rows))
            for r in rows:
                lines.append(f"{samples:9.0e} {seeds:5d} {noise:5.0%} {r['method']:<6} "
                             f"{r['parameter']:<5} {r['coverage']:8.0%} {r['spread_se']:9.2f} "
                             f"{r['bias_se']:8.2f}")
            tests.append(f"{samples:9.0e} {noise:5.0%} {size:11.0%} {power:15.0%}")
            for name, ((half, half_change), (double, double_change)) in batches.items():
                halved.append(f"{samples:9.0e} {noise:5.0%} {name:<5} {half:13.2f} "
                              f"{half_change:13.0%} {double:12.2f} {double_change:13.0%}")
            print("\n".join(lines[-len(rows):]), flush=True)
    text = ("\n".join(lines) + "\n\n" + "\n".join(tests) + "\n\n" + "\n".join(halved) +
            "\n")
    print()
    print("\n".join(tests))
    print()
    print("\n".join(halved))
    if args.summary:
        with open(args.summary, "w") as f:
            f.write(text)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        # Colour: the noise level; line: the method; marker: the parameter.
        for colour, noise in enumerate(noises):
            for method, style in (("ls", "-"), ("gmm", "--")):
                for name, marker in zip(TRUTH, "osd"):
                    points = [(s, r["coverage"], r["spread_se"]) for s, n, rows in results
                              if n == noise for r in rows
                              if r["method"] == method and r["parameter"] == name]
                    s, coverage, ratio = zip(*points)
                    label = f"{name}, {method}, noise {noise:.0%}"
                    for axis, values in ((axes[0], coverage), (axes[1], ratio)):
                        axis.plot(s, values, style, marker=marker, color=f"C{colour}",
                                  label=label)
        axes[0].set_xscale("log")
        axes[1].set_xscale("log")
        axes[1].set_yscale("log")
        axes[0].axhline(0.95, color="k", lw=0.5)
        axes[0].set(xlabel="samples", ylabel="coverage of the 95% intervals")
        axes[1].axhline(1, color="k", lw=0.5)
        axes[1].set(xlabel="samples", ylabel="spread of the estimates / mean standard error")
        axes[1].legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
    if args.check:
        bad = [(s, n, r) for s, n, rows in results for r in rows if r["coverage"] < 0.5]
        for s, n, r in bad:
            print(f"collapsed: {s:.0e} samples, noise {n:.0%}, {r['method']} {r['parameter']}: "
                  f"coverage {r['coverage']:.0%}, spread/SE {r['spread_se']:.2f}")
        sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
