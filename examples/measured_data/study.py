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

  study.py [--samples N,N,...] [--noise F,F,...] [--seed S] [--coarse-samples N] [--plot OUT.png]

Prints the relative error of every estimate; with --plot draws them against the noise level
(matplotlib). Uses build/momentid, or the MOMENTID environment variable.
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


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", default="100000,1000000")
    parser.add_argument("--noise", default="0,0.02,0.05,0.1,0.2")
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--coarse-samples", type=int, default=300000)
    parser.add_argument("--plot")
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
    for method, estimates in coarse(n, args.seed).items():
        errors = [(estimates[p] - t) / t for p, t in TRUTH.items()]
        print(f"{n:>8} {0.01:>6.0%}  {method:<18}" + "".join(f"{e:>+12.3%}" for e in errors))
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
