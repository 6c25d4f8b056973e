#!/usr/bin/python3
"""The Duffing oscillator (c = 0.5, k = 4, eps = 1) identified from displacement and force
alone, with white sensor noise on the displacement, by three methods:

  lagged      momentid's lagged moment equations (the record as it is, noise corrected)
  zero-lag    momentid's zero-lag equations, with the velocity formed by central differences
  eq. error   the usual equation-error baseline: velocity and acceleration by central
              differences, then least squares of y'' + c y' + k y + eps y^3 = x (numpy)

and, like a measured electronic Duffing circuit, from a band-limited record sampled about nine
times per period of the resonance (a multisine force evaluated exactly, no hold; 1% noise):

  coarse      the same three methods on that record (momentid chooses its 13-point stencils
              for sampled inputs; `coarse, held` forces the 5-point ones of held inputs)

and finally validates the coarse estimates (`momentid validate`) on a separate record whose
force grows steadily to three times the rms of the estimation record, past the amplitudes the
estimates were fitted to:

  validation  the fit of the lagged and of the baseline estimates, over the record's first 10%
              and the rest

  study.py [--samples N,N,...] [--noise F,F,...] [--seed S] [--coarse-samples N]
           [--validation-samples N] [--plot OUT.png] [--validation-plot OUT.png]

Prints the relative error of every estimate and the validation fits; with --plot draws the
errors against the noise level, with --validation-plot the validation record against the two
models' simulations (matplotlib). Uses build/momentid, or the MOMENTID environment variable.
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
TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0}
INPUT = "ma:K=10,w=0.1,sigma=20"
DT = 0.01
METHODS = ["lagged", "zero-lag", "eq. error"]


def read(path):
    """The t, y, x columns of a momentid CSV file."""
    with open(path) as f:
        lines = [line for _, line in zip(range(100), f)]
    at = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    header = lines[at].strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=at + 1)
    return {name: data[:, i] for i, name in enumerate(header)}


def identify(path, *options):
    out = subprocess.run([MOMENTID, "identify", MODEL, path, "--format", "json", *options],
                         check=True, capture_output=True, text=True).stdout
    return {p: v["estimate"] for p, v in json.loads(out)["parameters"].items()}


def equation_error(y, x):
    """Least squares of y'' = -c y' - k y - eps y^3 + x with central differences."""
    v = (y[2:] - y[:-2]) / (2 * DT)
    a = (y[2:] - 2 * y[1:-1] + y[:-2]) / DT**2
    # The held input over the two intervals the second difference spans.
    yy, xx = y[1:-1], (x[:-2] + x[1:-1]) / 2
    design = np.column_stack([-v, -yy, -yy**3])
    theta = np.linalg.lstsq(design, a - xx, rcond=None)[0]
    return dict(zip(TRUTH, theta))


def run(samples, noise, seed):
    with tempfile.TemporaryDirectory() as tmp:
        record = os.path.join(tmp, "y_x.csv")
        command = [MOMENTID, "simulate", MODEL, "--samples", str(samples), "--input", INPUT,
                   "--seed", str(seed), "--observe", "y,x", "-o", record]
        if noise > 0:
            command[-2:-2] = ["--noise", f"y={noise}"]
        subprocess.run(command, check=True)
        columns = read(record)
        y, x = columns["y"], columns["x"]
        # The zero-lag method needs a velocity column: central differences of the record.
        with_velocity = os.path.join(tmp, "y_v_x.csv")
        v = np.gradient(y, DT)
        with open(with_velocity, "w") as out:
            out.write("# momentid: dt=0.01 input-hold=zoh\nt,y,v,x\n")
            np.savetxt(out, np.column_stack([columns["t"], y, v, x]), delimiter=",", fmt="%.17g")
        return {"lagged": identify(record),
                "zero-lag": identify(with_velocity, "--degree", "3"),
                "eq. error": equation_error(y, x)}


# The coarse record: simulated at a tenth of its sampling interval (the multisine is evaluated at
# every integration stage) and every tenth sample kept. The resonance, near sqrt(k)/2pi = 0.32 Hz,
# is then sampled about nine times per period (a force of rms 5 keeps the cubic term small enough
# not to stiffen it much); the force spans 0.05..0.6 Hz.
COARSE_DT = 0.35
COARSE_INPUT = "multisine:f1=0.05,f2=0.6,lines=40,rms=5"


def coarse(samples, seed):
    with tempfile.TemporaryDirectory() as tmp:
        fine = os.path.join(tmp, "fine.csv")
        subprocess.run([MOMENTID, "simulate", MODEL, "--samples", str(10 * samples), "--dt",
                        str(COARSE_DT / 10), "--input", COARSE_INPUT, "--seed", str(seed),
                        "--observe", "y,x", "--noise", "y=0.01", "-o", fine], check=True)
        columns = read(fine)
        t, y, x = columns["t"][::10], columns["y"][::10], columns["x"][::10]
        record = os.path.join(tmp, "coarse.csv")
        with open(record, "w") as out:
            out.write(f"# momentid: dt={COARSE_DT} input-hold=sample\nt,y,x\n")
            np.savetxt(out, np.column_stack([t, y, x]), delimiter=",", fmt="%.17g")
        # The baseline's differences at this interval, with the force sampled at the middle row.
        v = (y[2:] - y[:-2]) / (2 * COARSE_DT)
        a = (y[2:] - 2 * y[1:-1] + y[:-2]) / COARSE_DT**2
        yy = y[1:-1]
        theta = np.linalg.lstsq(np.column_stack([-v, -yy, -yy**3]), a - x[1:-1], rcond=None)[0]
        return {"coarse": identify(record),
                "coarse, held": identify(record, "--input-hold", "zoh"),
                "coarse, eq. error": dict(zip(TRUTH, theta))}


# The validation record: a force with the coarse record's band, whose rms grows linearly from 2.5
# to 15 (the estimation record has 5), made at a tenth of the coarse interval by numpy and run
# through the model with `simulate --input-file` (the force is smooth: band-limited interpolation
# between its fine samples); every tenth sample is kept and 1% noise added to y, as before.
def validation_record(samples, seed, path):
    rng = np.random.default_rng(seed + 1000)
    fine_dt = COARSE_DT / 10
    t = fine_dt * np.arange(10 * samples)
    frequencies = rng.uniform(0.05, 0.6, 40)
    phases = rng.uniform(0, 2 * np.pi, 40)
    unit = np.sqrt(2 / 40) * np.cos(np.multiply.outer(t, 2 * np.pi * frequencies) + phases).sum(1)
    x = (2.5 + 12.5 * t / t[-1]) * unit
    with tempfile.TemporaryDirectory() as tmp:
        force = os.path.join(tmp, "force.csv")
        with open(force, "w") as out:
            # A y column of zeros: the response starts at rest and is written in its place.
            out.write("# momentid: input-hold=sample\nt,y,x\n")
            np.savetxt(out, np.column_stack([t, np.zeros_like(t), x]), delimiter=",",
                       fmt="%.17g")
        response = os.path.join(tmp, "response.csv")
        subprocess.run([MOMENTID, "simulate", MODEL, "--input-file", force, "-o", response],
                       check=True)
        y = read(response)["y"]
    y, x, t = y[::10], x[::10], t[::10]
    y = y + 0.01 * np.std(y) * rng.standard_normal(len(y))
    with open(path, "w") as out:
        out.write(f"# momentid: dt={COARSE_DT} input-hold=sample\nt,y,x\n")
        np.savetxt(out, np.column_stack([t, y, x]), delimiter=",", fmt="%.17g")
    return t, y, x


def validate(record, estimates, tmp, name):
    """The validate JSON and the simulated y for one set of estimates."""
    path = os.path.join(tmp, f"{name}.json")
    with open(path, "w") as out:
        json.dump({"model": "duffing",
                   "parameters": {p: {"estimate": v} for p, v in estimates.items()}}, out)
    result = json.loads(subprocess.run(
        [MOMENTID, "validate", MODEL, record, "--estimates", path, "--format", "json"],
        check=True, capture_output=True, text=True).stdout)
    simulated = os.path.join(tmp, f"{name}.csv")
    subprocess.run([MOMENTID, "simulate", MODEL, "--input-file", record, "--set",
                    ",".join(f"{p}={v!r}" for p, v in estimates.items()), "-o", simulated],
                   check=True)
    return result, read(simulated)["y"]


def validation(samples, seed, estimates, plot):
    with tempfile.TemporaryDirectory() as tmp:
        record = os.path.join(tmp, "validation.csv")
        t, y, x = validation_record(samples, seed, record)
        runs = {name: validate(record, estimates[name], tmp, name.replace(", ", "_").replace(
            ". ", "_")) for name in ("coarse", "coarse, eq. error")}
    print(f"\nvalidation on {samples} rows, force rms 2.5 -> 15 (estimated at 5), 1% noise:")
    print(f"{'estimates':<18} {'fit %':>8} {'rms first 10%':>14} {'rms rest':>10}  skip  "
          "substeps")
    for name, (result, _) in runs.items():
        out = result["outputs"]["y"]
        print(f"{name:<18} {out['fit_percent']:>8.2f} {out['rms_first_10pct']:>14.4g} "
              f"{out['rms_rest']:>10.4g}  {result['skip'][0]:>4}  {result['substeps']:>8}")
    if not plot:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure = plt.figure(figsize=(12, 9))
    grid = figure.add_gridspec(3, 2)
    span = int(60 / COARSE_DT)  # a minute of the record
    windows = (("start (force rms about 3)", runs["coarse"][0]["skip"][0]),
               ("end (force rms about 15)", len(t) - span))
    for row, (title, start) in enumerate(windows):
        ax = figure.add_subplot(grid[row, :])
        window = slice(start, start + span)
        ax.plot(t[window], y[window], "k.", markersize=4, label="measured y (every sample)")
        for (name, (result, simulated)), colour in zip(runs.items(), ("tab:red", "tab:blue")):
            ax.plot(t[window], simulated[window], color=colour,
                    label=f"{name} model (fit {result['outputs']['y']['fit_percent']:.1f}%)")
        ax.set_title(f"validation record, {title}")
        ax.set_xlabel("t (s)")
        ax.legend(loc="upper right", fontsize=8)
    outputs = runs["coarse"][0]["outputs"]["y"]
    for col, (check, title) in enumerate(
            ((outputs["autocorrelation"], "autocorrelation of the error"),
             (outputs["cross_correlation"]["x"], "cross-correlation of the error with x"))):
        ax = figure.add_subplot(grid[2, col])
        ax.stem(check["lags"], check["values"], basefmt="k-")
        ax.axhline(check["band99"], color="tab:blue", linestyle="--", label="99% band")
        ax.axhline(-check["band99"], color="tab:blue", linestyle="--")
        ax.set_title(f"coarse model: {title}", fontsize=10)
        ax.set_xlabel("lag (samples)")
        ax.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(plot, dpi=90)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", default="100000,1000000")
    parser.add_argument("--noise", default="0,0.02,0.05,0.1,0.2")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--coarse-samples", type=int, default=300000)
    parser.add_argument("--validation-samples", type=int, default=20000)
    parser.add_argument("--plot")
    parser.add_argument("--validation-plot")
    args = parser.parse_args()
    sizes = [int(n) for n in args.samples.split(",")]
    levels = [float(f) for f in args.noise.split(",")]
    results = {}
    print(f"{'samples':>8} {'noise':>6}  {'method':<18}" +
          "".join(f"{'error ' + p:>12}" for p in TRUTH))
    for n in sizes:
        for f in levels:
            results[n, f] = run(n, f, args.seed)
            for method in METHODS:
                errors = [(results[n, f][method][p] - t) / t for p, t in TRUTH.items()]
                print(f"{n:>8} {f:>6.0%}  {method:<18}" + "".join(f"{e:>+12.3%}" for e in errors))
    n = args.coarse_samples
    coarse_estimates = coarse(n, args.seed)
    for method, estimates in coarse_estimates.items():
        errors = [(estimates[p] - t) / t for p, t in TRUTH.items()]
        print(f"{n:>8} {0.01:>6.0%}  {method:<18}" + "".join(f"{e:>+12.3%}" for e in errors))
    validation(args.validation_samples, args.seed, coarse_estimates, args.validation_plot)
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        figure, axes = plt.subplots(len(sizes), 3, figsize=(12, 3.4 * len(sizes)), squeeze=False)
        for row, n in enumerate(sizes):
            for col, (p, t) in enumerate(TRUTH.items()):
                ax = axes[row][col]
                for method, marker in zip(METHODS, "os^"):
                    errors = [abs(results[n, f][method][p] - t) / t for f in levels]
                    ax.semilogy([100 * f for f in levels], np.maximum(errors, 1e-6), marker=marker,
                                label=method)
                ax.set_title(f"{p}, {n:.0e} samples")
                ax.set_xlabel("noise on y (% of its standard deviation)")
                ax.set_ylabel("|relative error|")
                ax.grid(True, which="both", alpha=0.3)
        axes[0][0].legend()
        figure.tight_layout()
        figure.savefig(args.plot, dpi=90)


if __name__ == "__main__":
    main()
