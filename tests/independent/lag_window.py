"""The default lag window against fixed ones on lightly damped resonances sampled coarsely or finely.

A linear oscillator y'' = -c y' - k y + x (resonance 5 Hz), driven by a force low-passed at twice
the resonance (second order, damping 0.7), sampled exactly by numpy/scipy (the matrix exponential
of the oscillator with its force filter, Van Loan's integral for the noise) at 8 to 100 samples per
period, damping ratios 0.01 to 0.1, 2% white noise on the displacement and the force, no velocity
column: `identify` takes the lagged equations. For each record the default window and each fixed
window (`--lags 3..L`); per cell the root mean square relative error of c and k over the seeds.

  /usr/bin/python3 tests/independent/lag_window.py build/momentid [--seeds 6] [--samples 100000]
"""
import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from lab_records import sample_exactly

FREQUENCY = 5.0
MODEL = """model oscillator "a linear oscillator"
state y, v
input x
param c = 1, k = 1000
y' = v
v' = -c*v - k*y + x
"""


def record(rng, zeta, per_period, samples, noise=0.02):
    """y and x of the oscillator with damping ratio `zeta`, `per_period` samples per period."""
    omega = 2 * np.pi * FREQUENCY
    c, k = 2 * zeta * omega, omega**2
    fs = per_period * FREQUENCY
    corner = 2 * np.pi * 2 * FREQUENCY
    # z = (y, v, x, x'), z' = A z + b w with w white.
    a = np.array([[0, 1, 0, 0], [-k, -c, 1, 0], [0, 0, 0, 1],
                  [0, 0, -corner**2, -2 * 0.7 * corner]], float)
    b = np.array([0, 0, 0, corner**2], float)
    z = sample_exactly(rng, a, b, fs, samples)
    y = z[:, 0] + noise * np.std(z[:, 0]) * rng.standard_normal(samples)
    x = z[:, 2] + noise * np.std(z[:, 2]) * rng.standard_normal(samples)
    return {"t": np.arange(samples) / fs, "y": y, "x": x}, {"c": c, "k": k}


def identify(momentid, model, path, *options):
    out = subprocess.run([momentid, "identify", model, path, "--format", "json", *options],
                         capture_output=True, text=True)
    if out.returncode != 0:
        return None
    return json.loads(out.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("momentid")
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--samples", type=int, default=100000)
    parser.add_argument("--zetas", default="0.01,0.03,0.1")
    parser.add_argument("--per-period", default="8,25,100")
    parser.add_argument("--windows", default="20,42,60,100,200,300")
    args = parser.parse_args()
    windows = [int(w) for w in args.windows.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        model = Path(tmp) / "oscillator.mom"
        model.write_text(MODEL)
        path = str(Path(tmp) / "record.csv")
        print("zeta  per-period  window   rms error c   rms error k   (default: lags chosen)")
        for zeta in (float(z) for z in args.zetas.split(",")):
            for per_period in (int(p) for p in args.per_period.split(",")):
                errors = {w: [] for w in ["default"] + windows}
                chosen = []
                for seed in range(args.seeds):
                    rng = np.random.default_rng(1000 * seed + 7)
                    columns, truth = record(rng, zeta, per_period, args.samples)
                    np.savetxt(path, np.column_stack([columns["t"], columns["y"], columns["x"]]),
                               delimiter=",", header="t,y,x", comments="", fmt="%.17g")
                    for w in errors:
                        options = [] if w == "default" else ["--lags", f"3..{w}"]
                        report = identify(args.momentid, str(model), path, *options)
                        if report is None:
                            errors[w].append((np.nan, np.nan))
                            continue
                        if w == "default":
                            lags = report["method"].get("lags", "?")
                            chosen.append("..".join(map(str, lags)) if isinstance(lags, list) else str(lags))
                        p = report["parameters"]
                        errors[w].append(tuple(p[n]["estimate"] / truth[n] - 1 for n in ("c", "k")))
                for w, e in errors.items():
                    e = np.array(e)
                    rms = np.sqrt(np.nanmean(e**2, axis=0))
                    label = f"default ({', '.join(sorted(set(chosen)))})" if w == "default" else w
                    print(f"{zeta:<5} {per_period:>6}      {str(label):<8} {rms[0]:12.3%} "
                          f"{rms[1]:12.3%}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
