#!/usr/bin/python3
"""How honest are momentid's standard errors, intervals and J test? A coverage study.

The Duffing oscillator (c = 0.5, k = 4, eps = 1; moving-average force K = 10, w = 0.1,
sigma = 20; dt = 0.01) is simulated with many seeds at each record length and noise level, and
identified each time:

  noise 0     y, v and x recorded; the zero-lag equations (degree 3)
  noise f > 0 y and x recorded, white noise of f times the standard deviation of y added to
              y; the lagged equations (momentid's correction for measured data)

Each record is identified with identify's defaults (which choose the equations above and the
optimally weighted estimate, whose first step is the least-squares one), with the right model
and with the linear model (eps = 0) for the power of the J test.
Per cell and parameter the study reports the coverage of the 95% intervals, the spread of the
estimates across seeds over their mean standard error (spread/SE; 1 when the errors are
right), the bias over the mean standard error, the J test's rejection rate of the right model
at the 5% level (its size: 5% when right) and of the linear model (its power).

  study.py [--sizes 1e5:100,1e6:100,1e7:160] [--noise-free-sizes 1e5:100,1e6:500,1e7:500]
           [--noise 0,0.01,0.05] [--first-seed 1] [--raw OUT.json] [--from RAW.json ...]
           [--summary OUT.txt]
           [--markdown OUT.md] [--plot OUT.png] [--check]

Without noise the errors are the record's ends, (g(T) - g(0))/T for powers g of the states,
whose distribution has a kurtosis of 17 to 110 (ends.py): with exact standard errors, the
spread over 120 seeds would fall below 0.64-0.87 or above 1.18-1.46 times the error one time
in ten each, so those cells take more seeds (--noise-free-sizes). Each cell's spread/SE comes with a 90% bootstrap interval over its seeds
and each coverage with a 90% Wilson interval. --raw keeps every record's results (written
after each cell); --from summarises such files (several: their cells are joined) without
running momentid; a cell that several files hold has the seeds of all of them
(--first-seed runs more seeds for a cell without repeating those run before).

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
    options = ["--format", "json"]  # the defaults: zero-lag without noise, lagged with it
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


def run_cell(samples, noise, seeds, first):
    """One_run for `seeds` seeds from `first` on."""
    with tempfile.TemporaryDirectory() as tmp:
        linear = os.path.join(tmp, "linear.mom")
        with open(linear, "w") as f:
            f.write(LINEAR)
        return [one_run(samples, noise, seed, tmp, linear) for seed in range(first, first + seeds)]


def wilson(hits, n, z=1.645):
    """The 90% Wilson interval of a proportion."""
    p = hits / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def spread_se(estimate, error):
    return estimate.std(ddof=1) / error.mean()


def bootstrap(estimate, error, draws=2000):
    """The 90% percentile interval of spread/SE over seeds drawn with replacement (fixed seed)."""
    rng = np.random.default_rng(0)
    picks = rng.integers(0, len(estimate), size=(draws, len(estimate)))
    ratios = [spread_se(estimate[i], error[i]) for i in picks]
    return tuple(np.quantile(ratios, [0.05, 0.95]))


def summarise(runs):
    rows = []
    for method in ("ls", "gmm"):
        for name, truth in TRUTH.items():
            values = np.array([r[0][method][name] for r in runs])
            estimate, error, low, high = values.T
            hits = int(np.sum((low <= truth) & (truth <= high)))
            rows.append({"method": method, "parameter": name,
                         "coverage": hits / len(runs),
                         "coverage_90": wilson(hits, len(runs)),
                         "spread_se": float(spread_se(estimate, error)),
                         "spread_se_90": bootstrap(estimate, error),
                         "bias_se": float((estimate.mean() - truth) / error.mean())})
    right = [r[1] for r in runs if r[1] is not None]
    wrong = [r[2] for r in runs if r[2] is not None]
    rejections = int(np.sum(np.array(right) < 0.05))
    size = (rejections / len(right), *wilson(rejections, len(right))) if right else (np.nan,) * 3
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


def markdown(summaries):
    """The summaries as tables (docs/uncertainty.md): one row per cell and method, the parameters
    side by side."""
    out = ["| samples | seeds | noise | method | coverage c, k, eps | spread/SE (90% interval) | "
           "bias/SE |", "| --- | --- | --- | --- | --- | --- | --- |"]
    tests = ["| samples | seeds | noise | J size at 5% (90% interval) | power against the linear "
             "model |", "| --- | --- | --- | --- | --- |"]
    halved = ["| samples | noise | SE(B/2)/SE(B), c, k, eps | SE(2B)/SE(B) | median change of one "
              "record's SE (B/2; 2B) |", "| --- | --- | --- | --- | --- |"]
    for (samples, noise), (seeds, (rows, size, power, batches)) in sorted(summaries.items()):
        lead = f"| {samples:.0e} | {seeds} | {noise:.0%} |"
        for method in ("ls", "gmm"):
            mine = [r for r in rows if r["method"] == method]
            coverage = ", ".join(f"{r['coverage']:.0%}" for r in mine)
            spread = ", ".join("%.2f (%.2f–%.2f)" % (r["spread_se"], *r["spread_se_90"])
                               for r in mine)
            bias = ", ".join(f"{r['bias_se']:.2f}" for r in mine)
            out.append(f"{lead} {method} | {coverage} | {spread} | {bias} |")
        tests.append(f"{lead} {size[0]:.0%} ({size[1]:.0%}–{size[2]:.0%}) | {power:.0%} |")
        halves = ", ".join(f"{b[0][0]:.2f}" for b in batches.values())
        doubles = ", ".join(f"{b[1][0]:.2f}" for b in batches.values())
        changes = (", ".join(f"{b[0][1]:.0%}" for b in batches.values()) + "; " +
                   ", ".join(f"{b[1][1]:.0%}" for b in batches.values()))
        halved.append(f"| {samples:.0e} | {noise:.0%} | {halves} | {doubles} | {changes} |")
    return "\n".join(out) + "\n\n" + "\n".join(tests) + "\n\n" + "\n".join(halved) + "\n"


def sizes_of(text):
    return [(int(float(a)), int(b)) for a, b in (s.split(":") for s in text.split(","))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1e5:100,1e6:100,1e7:160",
                        help="record lengths and seeds with noise, SAMPLES:SEEDS,...")
    parser.add_argument("--noise-free-sizes", default="1e5:100,1e6:500,1e7:500",
                        help="record lengths and seeds without noise")
    parser.add_argument("--noise", default="0,0.01,0.05")
    parser.add_argument("--first-seed", type=int, default=1,
                        help="the first seed of every cell (to add seeds to a study)")
    parser.add_argument("--raw", default=None, help="write every record's results here")
    parser.add_argument("--from", dest="sources", nargs="+", default=None,
                        help="summarise these --raw files instead of running")
    parser.add_argument("--summary", default=None)
    parser.add_argument("--markdown", default=None, help="the tables of docs/uncertainty.md")
    parser.add_argument("--plot", default=None)
    parser.add_argument("--check", action="store_true")
    args = parser.parse_args()

    # cells: (samples, noise) -> the runs of its seeds.
    cells = {}
    if args.sources:
        for source in args.sources:
            with open(source) as f:
                for c in json.load(f):
                    cells.setdefault((c["samples"], c["noise"]), []).extend(c["runs"])
    else:
        for noise in (float(n) for n in args.noise.split(",")):
            for samples, seeds in sizes_of(args.noise_free_sizes if noise == 0 else args.sizes):
                cells[(samples, noise)] = run_cell(samples, noise, seeds, args.first_seed)
                print(f"{samples:.0e} samples, noise {noise:.0%}: {seeds} seeds", flush=True)
                if args.raw:  # after every cell, so that an interrupted study keeps its cells
                    with open(args.raw, "w") as f:
                        json.dump([{"samples": s, "noise": n, "runs": r}
                                   for (s, n), r in cells.items()], f)
    noises = sorted({n for _, n in cells})

    lines = [f"{'samples':>9} {'seeds':>5} {'noise':>5} {'method':<6} {'param':<5} "
             f"{'coverage':>8} {'(90% interval)':>14} {'spread/SE':>9} {'(90% interval)':>14} "
             f"{'bias/SE':>8}"]
    tests = [f"{'samples':>9} {'seeds':>5} {'noise':>5} {'J size (5%)':>11} "
             f"{'(90% interval)':>14} {'power vs linear':>15}"]
    halved = [f"{'samples':>9} {'noise':>5} {'param':<5} {'SE(B/2)/SE(B)':>13} {'median change':>13} "
              f"{'SE(2B)/SE(B)':>12} {'median change':>13}"]
    summaries = {cell: (len(runs), summarise(runs)) for cell, runs in cells.items()}
    results = []
    for (samples, noise), (seeds, (rows, size, power, batches)) in sorted(summaries.items()):
        results.append((samples, noise, rows))
        for r in rows:
            lines.append(f"{samples:9.0e} {seeds:5d} {noise:5.0%} {r['method']:<6} "
                         f"{r['parameter']:<5} {r['coverage']:8.0%} "
                         f"{'[%3.0f%%, %3.0f%%]' % tuple(100 * x for x in r['coverage_90']):>14} "
                         f"{r['spread_se']:9.2f} "
                         f"{'[%4.2f, %4.2f]' % r['spread_se_90']:>14} {r['bias_se']:8.2f}")
        tests.append(f"{samples:9.0e} {seeds:5d} {noise:5.0%} {size[0]:11.0%} "
                     f"{'[%3.0f%%, %3.0f%%]' % tuple(100 * x for x in size[1:]):>14} "
                     f"{power:15.0%}")
        for name, ((half, half_change), (double, double_change)) in batches.items():
            halved.append(f"{samples:9.0e} {noise:5.0%} {name:<5} {half:13.2f} "
                          f"{half_change:13.0%} {double:12.2f} {double_change:13.0%}")
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(markdown(summaries))
    text = ("\n".join(lines) + "\n\n" + "\n".join(tests) + "\n\n" + "\n".join(halved) +
            "\n")
    print(text)
    if args.summary:
        with open(args.summary, "w") as f:
            f.write(text)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        # Colour: the noise level; line: the method; marker: the parameter; bars: the 90%
        # intervals, the series shifted a little apart along the record length.
        shift = iter(np.linspace(0.9, 1.1, 6 * len(noises)))
        for colour, noise in enumerate(noises):
            for method, style in (("ls", "-"), ("gmm", "--")):
                for name, marker in zip(TRUTH, "osd"):
                    points = [(s, r) for s, n, rows in results if n == noise for r in rows
                              if r["method"] == method and r["parameter"] == name]
                    x = np.array([s for s, _ in points]) * next(shift)
                    label = f"{name}, {method}, noise {noise:.0%}"
                    for axis, key in ((axes[0], "coverage"), (axes[1], "spread_se")):
                        values = np.array([r[key] for _, r in points])
                        low, high = np.array([r[key + "_90"] for _, r in points]).T
                        axis.errorbar(x, values, yerr=np.clip([values - low, high - values], 0, None),
                                      fmt=style,
                                      marker=marker, color=f"C{colour}", label=label, lw=0.8,
                                      elinewidth=0.5, markersize=4)
        axes[0].axhspan(0.90, 0.99, color="0.9", zorder=0)
        axes[1].axhspan(0.8, 1.25, color="0.9", zorder=0)
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
