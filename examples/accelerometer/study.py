#!/usr/bin/python3
"""Shaker records with an accelerometer: a hardening oscillator and a linear chain of two masses,
every channel with 2% white sensor noise, 2048 Hz, the force band-limited to 5-150 Hz (the
chain's force low-passed at 40 Hz), identified with no options but those named:

  (a) y       displacement and force (the model without the `measured` statement)
  (b) y+a     displacement, acceleration and force
  (c) a       acceleration and force alone, the linear model (the oscillator's k3 left out)
  (d) a, int  acceleration and force alone, `--integrate` forming the displacements
  baseline    the restoring-force practice in numpy: the acceleration integrated twice in the
              frequency domain with a high-pass at the same corner as (d), the velocity once,
              then least squares of m a - x = -(c v + k y + k3 y^3) with its textbook errors

Records are made by numpy and scipy (tests/independent/lab_records.py), not by momentid: the
oscillator by classical Runge-Kutta on a force known between samples, the chain sampled exactly
from its stationary distribution. For each method and record length the study prints, per
parameter, the mean error over the seeds in percent of the truth, the rms of error/standard
error, and how many 95% intervals hold the truth.

  study.py [--samples N,N,...] [--seeds K] [--plot OUT.png] [--json OUT.json]

Uses build/momentid, or the MOMENTID environment variable.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "independent"))
import lab_records as lab  # noqa: E402

FS = 2048
NOISE = 0.02
HARDENING = lab.HARDENING

MODEL = """model hardening "hardening oscillator on a shaker"
state y, v
input x
{measured}param c = 10, k = 4e4{cubic}
const m = 1
y' = v
m*v' = -c*v - k*y{cubic_term} + x
"""


def oscillator_model(measured, cubic=True):
    return MODEL.format(measured="measured a = v'\n" if measured else "",
                        cubic=", k3 = 4e9" if cubic else "",
                        cubic_term=" - k3*y^3" if cubic else "")


def hardening_record(seed, samples):
    rng = np.random.default_rng(seed)
    return rng, lab.hardening(rng, FS, samples)


def chain_record(seed, samples):
    rng = np.random.default_rng(seed)
    masses = [1.0, 1.5]
    truth = lab.chain_truth(rng, masses)
    clean = lab.chain(rng, masses, truth, FS, samples, 100.0)
    return rng, clean, masses, truth


def write(rng, clean, channels, path):
    columns = {"t": clean["t"]}
    for name in channels:
        columns[name] = lab.measured(rng, clean[name], NOISE)
    lab.write_csv(path, columns)


def identify(momentid, model_text, path, workdir, *options):
    model = os.path.join(workdir, "model.mom")
    with open(model, "w") as out:
        out.write(model_text)
    result = subprocess.run([momentid, "identify", model, path, "--format", "json", *options],
                            capture_output=True, text=True)
    if result.returncode != 0:
        return {"failed": result.stderr.strip()}
    report = json.loads(result.stdout)
    out = {name: (p["estimate"], p["std_error"]) for name, p in report["parameters"].items()}
    out["status"] = report["diagnostics"]["status"]
    if "integration" in report:
        out["corner"] = report["integration"]["corner_hz"]
    return out


def restoring_force(clean_noisy, corner, masses, dofs, cubic):
    """Integrate the accelerations in the frequency domain (1/(i w)^k, zero below the corner,
    a fourth-order Butterworth magnitude above), then least squares of the equations of motion
    written for the unknown parameters; the errors from the textbook OLS covariance."""
    n = clean_noisy["t"].size
    w = 2 * np.pi * np.fft.rfftfreq(n, 1 / FS)
    high_pass = np.zeros_like(w)
    high_pass[1:] = 1 / np.sqrt(1 + (2 * np.pi * corner / w[1:])**8)

    def integrated(signal, times):
        spectrum = np.fft.rfft(signal - signal.mean()) * high_pass
        spectrum[1:] /= (1j * w[1:])**times
        return np.fft.irfft(spectrum, n)
    filtered = {name: integrated(clean_noisy[name], 0) for name in clean_noisy if name != "t"}
    y = [integrated(clean_noisy[f"a{i}"], 2) for i in dofs]
    v = [integrated(clean_noisy[f"a{i}"], 1) for i in dofs]
    a = [filtered[f"a{i}"] for i in dofs]
    x = filtered["x"]
    keep = slice(n // 20, n - n // 20)  # the ends wrap around
    if len(dofs) == 1:
        columns = [-v[0], -y[0]] + ([-y[0]**3] if cubic else [])
        names = ["c", "k"] + (["k3"] if cubic else [])
        design = np.column_stack([c[keep] for c in columns])
        target = (masses[0] * a[0] - x)[keep]
    else:
        # m1 a1 = -c1 v1 - k1 y1 - c2 (v1 - v2) - k2 (y1 - y2)
        # m2 a2 = -c2 (v2 - v1) - k2 (y2 - y1) - kt y2 + x
        zero = np.zeros(n)
        rows1 = [-v[0], -(v[0] - v[1]), -y[0], -(y[0] - y[1]), zero]
        rows2 = [zero, -(v[1] - v[0]), zero, -(y[1] - y[0]), -y[1]]
        names = ["c1", "c2", "k1", "k2", "kt"]
        design = np.vstack([np.column_stack([c[keep] for c in rows1]),
                            np.column_stack([c[keep] for c in rows2])])
        target = np.concatenate([(masses[0] * a[0])[keep], (masses[1] * a[1] - x)[keep]])
    theta, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ theta
    sigma2 = residual @ residual / (target.size - theta.size)
    covariance = sigma2 * np.linalg.inv(design.T @ design)
    return {name: (theta[i], np.sqrt(covariance[i, i])) for i, name in enumerate(names)}


def run_hardening(momentid, seed, samples, workdir):
    rng, clean = hardening_record(seed, samples)
    noisy = {"t": clean["t"]}
    for name in ("y", "a", "x"):
        noisy[name] = lab.measured(rng, clean[name], NOISE)
    paths = {}
    for key, channels in (("y", ("y", "x")), ("ya", ("y", "a", "x")), ("a", ("a", "x"))):
        paths[key] = os.path.join(workdir, f"{key}.csv")
        lab.write_csv(paths[key], {"t": noisy["t"], **{c: noisy[c] for c in channels}})
    out = {
        "(a) y": identify(momentid, oscillator_model(False), paths["y"], workdir),
        "(b) y+a": identify(momentid, oscillator_model(True), paths["ya"], workdir),
        "(c) a": identify(momentid, oscillator_model(True, cubic=False), paths["a"], workdir),
        "(d) a, int": identify(momentid, oscillator_model(True), paths["a"], workdir,
                               "--integrate", "y"),
    }
    corner = out["(d) a, int"].get("corner", 2.5)
    renamed = {"t": noisy["t"], "a1": noisy["a"], "x": noisy["x"]}
    out["baseline"] = restoring_force(renamed, corner, [1.0], [1], cubic=True)
    return out, HARDENING


def run_chain(momentid, seed, samples, workdir):
    rng, clean, masses, truth = chain_record(seed, samples)
    noisy = {"t": clean["t"]}
    for name in ("y1", "y2", "a1", "a2", "x"):
        noisy[name] = lab.measured(rng, clean[name], NOISE)
    model = lab.chain_model(masses, truth)
    measured = model + "measured a1 = v1', a2 = v2'\n"
    paths = {}
    for key, channels in (("y", ("y1", "y2", "x")), ("ya", ("y1", "y2", "a1", "a2", "x")),
                          ("a", ("a1", "a2", "x"))):
        paths[key] = os.path.join(workdir, f"{key}.csv")
        lab.write_csv(paths[key], {"t": noisy["t"], **{c: noisy[c] for c in channels}})
    out = {
        "(a) y": identify(momentid, model, paths["y"], workdir),
        "(b) y+a": identify(momentid, measured, paths["ya"], workdir),
        "(c) a": identify(momentid, measured, paths["a"], workdir),
        "(d) a, int": identify(momentid, measured, paths["a"], workdir,
                               "--integrate", "y1,y2"),
    }
    corner = out["(d) a, int"].get("corner", 2.5)
    out["baseline"] = restoring_force(noisy, corner, masses, [1, 2], cubic=False)
    return out, truth


def summarise(results):
    """Per method and parameter over (fits, truth) pairs: mean error (% of truth), rms z, and
    the intervals that hold the truth."""
    table = {}
    for method in results[0][0]:
        rows = {}
        for name in results[0][1]:
            errors, zs = [], []
            for r, truth in results:
                value = truth[name]
                fit = r[method]
                if "failed" in fit or name not in fit:
                    continue
                estimate, se = fit[name]
                errors.append((estimate - value) / value)
                zs.append((estimate - value) / se if se else np.inf)
            if errors:
                zs = np.array(zs)
                rows[name] = {"mean_error_pct": 100 * float(np.mean(errors)),
                              "sd_error_pct": 100 * float(np.std(errors)),
                              "rms_z": float(np.sqrt(np.mean(zs**2))),
                              "covered": int(np.sum(np.abs(zs) <= 1.96)), "seeds": len(zs)}
        failures = [r[method]["failed"] for r, _ in results if "failed" in r[method]]
        if failures:
            rows["failed"] = {"count": len(failures), "first": failures[0]}
        table[method] = rows
    return table


def print_table(title, table):
    print(title)
    for method, rows in table.items():
        cells = [f"{name} {r['mean_error_pct']:+.2f}% (sd {r['sd_error_pct']:.2f}%, "
                 f"rms z {r['rms_z']:.1f}, {r['covered']}/{r['seeds']})"
                 for name, r in rows.items() if name != "failed"]
        if "failed" in rows:
            cells.append(f"failed {rows['failed']['count']} times: {rows['failed']['first']}")
        print(f"  {method:11s} " + "; ".join(cells))


def plot(summaries, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = list(summaries)
    fig, axes = plt.subplots(len(keys), 1, figsize=(9, 3.2 * len(keys)), squeeze=False)
    for ax, key in zip(axes[:, 0], keys):
        table = summaries[key]
        methods = list(table)
        names = sorted({n for rows in table.values() for n in rows if n != "failed"})
        width = 0.8 / len(methods)
        for i, method in enumerate(methods):
            means = [table[method].get(n, {}).get("mean_error_pct", np.nan) for n in names]
            sds = [table[method].get(n, {}).get("sd_error_pct", np.nan) for n in names]
            ax.bar(np.arange(len(names)) + i * width, means, width, yerr=sds, label=method)
        ax.set_xticks(np.arange(len(names)) + 0.4 - width / 2, names)
        ax.axhline(0, color="k", linewidth=0.5)
        ax.set_ylabel("error, % of truth")
        ax.set_title(key)
        ax.set_yscale("symlog", linthresh=1)
        ax.legend(fontsize=7, ncol=len(methods))
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", default="100000,1000000")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--plot")
    parser.add_argument("--json")
    args = parser.parse_args()
    momentid = os.environ.get("MOMENTID",
                              os.path.join(HERE, "..", "..", "build", "momentid"))
    summaries = {}
    with tempfile.TemporaryDirectory() as workdir:
        for samples in (int(s) for s in args.samples.split(",")):
            for label, run in (("hardening oscillator", run_hardening),
                               ("two-mass chain", run_chain)):
                results = [run(momentid, 20271200 + seed, samples, workdir)
                           for seed in range(args.seeds)]
                key = f"{label}, {samples} samples, {args.seeds} seeds"
                summaries[key] = summarise(results)
                print_table(key, summaries[key])
                sys.stdout.flush()
    if args.json:
        with open(args.json, "w") as out:
            json.dump(summaries, out, indent=1)
    if args.plot:
        plot(summaries, args.plot)


if __name__ == "__main__":
    main()
