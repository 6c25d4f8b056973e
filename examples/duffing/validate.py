#!/usr/bin/python3
"""Identifies the Duffing oscillator on one record and validates the estimates on another.

  validate.py [--samples N] [--plot OUT.png]

The estimation record (seed 11) and the validation record (seed 12) are simulated with the same
input as sweep.py, 2% white noise on y and no velocity column, as a measured record would be.
The script prints the estimates, then `momentid validate`'s figures for them and for values 20%
off (the fit, the correlation checks, the noise band and the verdict); with --plot it draws the validation record against both simulations and the correlation
checks of the estimates' simulation error (matplotlib).
Uses the momentid executable (build/momentid, or the MOMENTID environment variable).
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
INPUT = "ma:K=10,w=0.1,sigma=20"


def momentid(*args):
    return subprocess.run([MOMENTID, *args], check=True, capture_output=True, text=True).stdout


def simulate(path, samples, seed):
    momentid("simulate", MODEL, "--samples", str(samples), "--input", INPUT, "--seed", str(seed),
             "--observe", "y,x", "--noise", "y=0.02", "-o", path)


def column(path, name):
    with open(path) as f:
        at, header = next((i, line) for i, line in enumerate(f) if not line.startswith("#"))
    index = header.strip().split(",").index(name)
    return np.loadtxt(path, delimiter=",", skiprows=at + 1, usecols=index)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--plot")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fit, test = os.path.join(tmp, "fit.csv"), os.path.join(tmp, "test.csv")
        simulate(fit, args.samples, 11)
        simulate(test, 20000, 12)
        estimates = os.path.join(tmp, "estimates.json")
        with open(estimates, "w") as out:
            out.write(momentid("identify", MODEL, fit, "--format", "json"))
        with open(estimates) as f:
            values = {p: v["estimate"] for p, v in json.load(f)["parameters"].items()}
        print("estimates: " + ", ".join(f"{p} = {v:.5f}" for p, v in values.items()))
        off = ",".join(f"{p}={0.8 * v!r}" for p, v in values.items())
        results, simulated = {}, {}
        for name, options in (("estimates", ["--estimates", estimates]),
                              ("20% low", ["--set", off])):
            results[name] = json.loads(momentid("validate", MODEL, test, *options,
                                                "--format", "json"))
            replay = os.path.join(tmp, "replay.csv")
            momentid("simulate", MODEL, "--input-file", test, "-o", replay,
                     *(["--set", ",".join(f"{p}={v!r}" for p, v in values.items())]
                       if name == "estimates" else ["--set", off]))
            simulated[name] = column(replay, "y")
        t, y = column(test, "t"), column(test, "y")
    print(f"{'parameters':<12} {'fit %':>8} {'rms error':>10} {'rms first 10%':>14} "
          f"{'rms rest':>10} {'autocorr. out':>14} {'cross-corr. out':>16} "
          f"{'band error/limit':>17} {'consistent':>11}")
    for name, result in results.items():
        out = result["outputs"]["y"]
        auto, cross = out["autocorrelation"], out["cross_correlation"]["x"]
        band = result["noise_band"]["outputs"]["y"]
        print(f"{name:<12} {out['fit_percent']:>8.3f} {out['rms']:>10.4g} "
              f"{out['rms_first_10pct']:>14.4g} {out['rms_rest']:>10.4g} "
              f"{auto['outside']:>9d} of {len(auto['values']):<2d} "
              f"{cross['outside']:>11d} of {len(cross['values']):<2d} "
              f"{band['error'] / band['limit']:>17.3g} {str(result['consistent']):>11}")
    if not args.plot:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure = plt.figure(figsize=(12, 8.5))
    grid = figure.add_gridspec(3, 2, height_ratios=[2, 1, 1.3])
    skip = results["estimates"]["skip"][0]
    window = slice(skip, skip + 2000)
    ax = figure.add_subplot(grid[0, :])
    ax.plot(t[window], y[window], color="0.2", lw=1, label="measured y (2% noise)")
    for name, colour in (("estimates", "tab:red"), ("20% low", "tab:blue")):
        fit = results[name]["outputs"]["y"]["fit_percent"]
        ax.plot(t[window], simulated[name][window], color=colour, lw=1,
                label=f"simulated, {name} (fit {fit:.1f}%)")
    ax.set_title("Duffing oscillator: the validation record and two models driven by its force")
    ax.legend(loc="upper right", fontsize=8)
    ax = figure.add_subplot(grid[1, :], sharex=figure.axes[0])
    ax.plot(t[window], y[window] - simulated["estimates"][window], color="tab:red", lw=0.8)
    ax.set_title("measured - simulated with the estimates", fontsize=10)
    ax.set_xlabel("t (s)")
    out = results["estimates"]["outputs"]["y"]
    for col, (check, title) in enumerate(
            ((out["autocorrelation"], "autocorrelation of the error"),
             (out["cross_correlation"]["x"], "cross-correlation of the error with x"))):
        ax = figure.add_subplot(grid[2, col])
        ax.stem(check["lags"], check["values"], basefmt="k-")
        ax.axhline(check["band99"], color="tab:blue", linestyle="--", label="99% band")
        ax.axhline(-check["band99"], color="tab:blue", linestyle="--")
        ax.set_title(f"estimates: {title}", fontsize=10)
        ax.set_xlabel("lag (samples)")
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(args.plot, dpi=90)


if __name__ == "__main__":
    main()
