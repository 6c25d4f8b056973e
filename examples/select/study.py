#!/usr/bin/python3
"""Term selection with momentid select against thresholding, on records numpy makes.

  study.py run RESULTS.json [--samples N ...] [--noise P ...] [--seeds S] [--systems NAME ...]
                                  runs the study, writing its results after every record
  study.py table RESULTS.json ...      the recovery rates and parameter errors as a table
  study.py plot OUT.png RESULTS.json ...   draws them (matplotlib; the extension picks the format)

Three oscillators driven by a shaker force, the displacement y (with white noise of P percent of
its standard deviation) and the force x recorded at 1024 Hz:

  duffing      y'' = -4 y' - 1024 y - 400 y^3 + x
  asymmetric   y'' = -4 y' - 1024 y - 300 y^2 - 400 y^3 + x
  van_der_pol  y'' = 2 (1 - y^2) y' - 400 y + x

and the library {y, y^2, y^3, y^4, y^5, v, y v, y^2 v, x} (library.mom beside this file). Each
record is given to three selectors:

  select     momentid select with no options;
  threshold  sequential thresholding on the same moment equations: momentid identify fits the
             library, the candidates whose estimates are smaller than a threshold in magnitude
             are fixed at zero, and the rest fitted again until nothing changes (the thresholds
             are absolute sizes, as in SINDy's STLSQ, so they depend on the units);
  equation   the equation-error baseline: y'' and y' by central differences of the measured y,
             the library fitted to y'' by least squares and thresholded as above.

A record's selection counts as recovered when it keeps exactly the true terms. The parameter
error of a record is the largest relative error of the true model's parameters (of the selected
model, when it is the true one).

Uses the momentid executable (build/momentid, or the MOMENTID environment variable).
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
LIBRARY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "library.mom")

FS = 1024.0
BAND = (1.0, 40.0)
BURN_IN = 10.0

# Each system: its true library coefficients and the RMS of its force.
SYSTEMS = {
    "duffing": ({"v_y": -1024.0, "v_y3": -400.0, "v_v": -4.0, "v_x": 1.0}, 800.0),
    "asymmetric": ({"v_y": -1024.0, "v_y2": -300.0, "v_y3": -400.0, "v_v": -4.0, "v_x": 1.0},
                   800.0),
    "van_der_pol": ({"v_y": -400.0, "v_v": 2.0, "v_y2_v": -2.0, "v_x": 1.0}, 200.0),
}
THRESHOLDS = (0.5, 5.0)


def library_terms(y, v, x):
    """The library's terms, by their parameters' names."""
    return {"v_y": y, "v_y2": y**2, "v_y3": y**3, "v_y4": y**4, "v_y5": y**5, "v_v": v,
            "v_y_v": y * v, "v_y2_v": y**2 * v, "v_x": x}


LIBRARY_NAMES = list(library_terms(0.0, 0.0, 0.0))


def acceleration(truth, y, v, x):
    """The library's right-hand side with the coefficients `truth`."""
    terms = library_terms(y, v, x)
    return sum(value * terms[name] for name, value in truth.items())


def forces(rng, seeds, samples, rms):
    """Periodic Gaussian forces (one row per seed) with a flat spectrum on BAND, on the grid of
    half the sample interval, 2 samples + 1 values each."""
    n = 2 * samples
    frequency = np.fft.rfftfreq(n, 1 / (2 * FS))
    lines = (frequency >= BAND[0]) & (frequency <= BAND[1])
    spectrum = np.zeros((seeds, frequency.size), complex)
    shape = (seeds, int(lines.sum()))
    spectrum[:, lines] = rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    force = np.fft.irfft(spectrum, n, axis=1)
    force *= rms / force.std(axis=1, keepdims=True)
    return np.concatenate([force, force[:, :1]], axis=1)


def records(system, seeds, samples, seed):
    """`seeds` clean records of `system` (y, v and x, rows by seed), integrated together by
    classical Runge-Kutta with the sample interval as the step, from rest, after BURN_IN s."""
    truth, rms = SYSTEMS[system]
    total = samples + int(BURN_IN * FS)
    force = forces(np.random.default_rng(seed), seeds, total, rms)
    dt = 1 / FS
    y, v = np.zeros(seeds), np.zeros(seeds)
    out = np.empty((3, seeds, samples))
    first = total - samples

    def rates(y, v, x):
        return v, acceleration(truth, y, v, x)
    for i in range(total):
        x0, x1, x2 = force[:, 2 * i], force[:, 2 * i + 1], force[:, 2 * i + 2]
        if i >= first:
            out[:, :, i - first] = y, v, x0
        a1, b1 = rates(y, v, x0)
        a2, b2 = rates(y + dt / 2 * a1, v + dt / 2 * b1, x1)
        a3, b3 = rates(y + dt / 2 * a2, v + dt / 2 * b2, x1)
        a4, b4 = rates(y + dt * a3, v + dt * b3, x2)
        y = y + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        v = v + dt / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
    return out


def write_record(path, y, x):
    t = np.arange(y.size) / FS
    with open(path, "w") as out:
        out.write("t,y,x\n")
        np.savetxt(out, np.column_stack([t, y, x]), delimiter=",", fmt="%.17g")


def momentid(*args):
    result = subprocess.run([MOMENTID, *args, "--format", "json", "--quiet"],
                            capture_output=True, text=True)
    if result.returncode not in (0, 1):
        raise RuntimeError(f"momentid {' '.join(args)}: {result.stderr.strip()}")
    return json.loads(result.stdout)


def by_select(path):
    report = momentid("select", LIBRARY, path)
    estimates = {name: p["estimate"] for name, p in report["parameters"].items()}
    changes = {t["candidate"]: t["j_change"] for t in report["selection"]["tests"]}
    return sorted(report["selected"]), estimates, report["diagnostics"]["j_pvalue"], changes


def by_threshold(path, threshold):
    """Sequential thresholding of the library's moment estimates (momentid identify)."""
    zero = []
    while True:
        fixes = ["--fix", ",".join(f"{name}=0" for name in zero)] if zero else []
        report = momentid("identify", LIBRARY, path, *fixes)
        estimates = {name: p["estimate"] for name, p in report["parameters"].items()
                     if name not in zero}
        small = [name for name, value in estimates.items() if abs(value) < threshold]
        if not small or len(zero) + len(small) == len(LIBRARY_NAMES):
            kept = sorted(name for name in estimates if name not in small)
            return kept, {name: estimates[name] for name in kept}
        zero += small


def by_equation_error(y, x, threshold):
    """Least squares of the central-difference acceleration on the library, thresholded."""
    dt = 1 / FS
    a = (y[2:] - 2 * y[1:-1] + y[:-2]) / dt**2
    v = (y[2:] - y[:-2]) / (2 * dt)
    columns = library_terms(y[1:-1], v, x[1:-1])
    kept = list(LIBRARY_NAMES)
    while True:
        matrix = np.column_stack([columns[name] for name in kept])
        coefficients = np.linalg.lstsq(matrix, a, rcond=None)[0]
        estimates = dict(zip(kept, coefficients))
        small = [name for name, value in estimates.items() if abs(value) < threshold]
        if not small or len(small) == len(kept):
            return sorted(kept), estimates
        kept = [name for name in kept if name not in small]


def worst_error(truth, kept, estimates):
    if kept != sorted(truth):
        return None
    return max(abs(estimates[name] / value - 1) for name, value in truth.items())


def run(args):
    results = []

    def save():
        with open(args.results, "w") as out:
            json.dump({"thresholds": list(args.thresholds), "results": results}, out, indent=1)
            out.write("\n")
    with tempfile.TemporaryDirectory() as workdir:
        path = os.path.join(workdir, "record.csv")
        for system in args.systems:
            truth = SYSTEMS[system][0]
            for samples in args.samples:
                clean = records(system, args.seeds, samples, 20261125 + samples)
                for noise in args.noise:
                    rng = np.random.default_rng(int(noise * 1000) + samples)
                    for seed in range(args.seeds):
                        y, x = clean[0, seed], clean[2, seed]
                        y = y + noise / 100 * y.std() * rng.standard_normal(y.size)
                        write_record(path, y, x)
                        row = {"system": system, "samples": samples, "noise": noise,
                               "seed": seed}
                        kept, estimates, pvalue, changes = by_select(path)
                        row["select"] = {"kept": kept, "j_pvalue": pvalue, "j_change": changes,
                                         "error": worst_error(truth, kept, estimates)}
                        for threshold in args.thresholds:
                            kept, estimates = by_threshold(path, threshold)
                            row[f"threshold {threshold:g}"] = {
                                "kept": kept, "error": worst_error(truth, kept, estimates)}
                            kept, estimates = by_equation_error(y, x, threshold)
                            row[f"equation {threshold:g}"] = {
                                "kept": kept, "error": worst_error(truth, kept, estimates)}
                        results.append(row)
                        save()
                        print(f"{system} {samples} {noise}% seed {seed}: select "
                              f"{', '.join(row['select']['kept'])}", file=sys.stderr)


def load(paths):
    """The results of the files `paths`, one study."""
    results = []
    for path in paths:
        with open(path) as f:
            results += json.load(f)["results"]
    return {"results": results}


def cells(study):
    """The results grouped by (system, samples, noise): for each selector that ran on the cell
    the records recovered, the records, the median worst parameter error of the recovered ones
    and (select) the chosen models its J test rejects at 1%."""
    grouped = {}
    for row in study["results"]:
        grouped.setdefault((row["system"], row["samples"], row["noise"]), []).append(row)
    selectors = list(dict.fromkeys(name for row in study["results"] for name in row
                                   if isinstance(row[name], dict)))
    summary = {}
    for key, rows in grouped.items():
        summary[key] = {}
        for selector in selectors:
            if selector not in rows[0]:
                continue
            errors = [row[selector]["error"] for row in rows if row[selector]["error"] is not None]
            rejected = sum(1 for row in rows if selector == "select"
                           and (row[selector]["j_pvalue"] or 0) < 0.01)
            summary[key][selector] = (len(errors), len(rows),
                                      float(np.median(errors)) if errors else None, rejected)
    return selectors, summary


def table(args):
    study = load(args.results)
    selectors, summary = cells(study)
    print(f"{'system':12} {'samples':>8} {'noise':>5}  " +
          "  ".join(f"{name:>18}" for name in selectors))
    for (system, samples, noise), entry in summary.items():
        line = f"{system:12} {samples:8d} {noise:4g}%  "
        for selector in selectors:
            if selector not in entry:
                line += f"  {'':18}"
                continue
            hits, count, error, _ = entry[selector]
            median = f"{100 * error:.2f}%" if error is not None else "-"
            line += f"  {hits:3d}/{count:<3d} {median:>10}"
        print(line)
    rejected = sum(entry["select"][3] for entry in summary.values())
    print(f"select's chosen models rejected by their J test at 1%: {rejected}")
    for noisy in (False, True):
        pvalues = [row["select"]["j_pvalue"] for row in study["results"]
                   if row["select"]["error"] is not None and (row["noise"] > 0) == noisy]
        if pvalues:
            size = np.mean(np.array(pvalues) < 0.05)
            kind = "with" if noisy else "without"
            print(f"the J test's size at 5% at the true model, records {kind} noise: "
                  f"{100 * size:.1f}% of {len(pvalues)}")


def plot(args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    study = load(args.results)
    selectors, summary = cells(study)
    systems = list(dict.fromkeys(key[0] for key in summary))
    lengths = sorted({key[1] for key in summary})
    noises = sorted({key[2] for key in summary})
    figure, axes = plt.subplots(2, len(systems), figsize=(4 * len(systems), 6.5), squeeze=False,
                                sharey="row")
    for column, system in enumerate(systems):
        for selector in selectors:
            for samples, style in zip(lengths, ("-", "--", ":")):
                if any(selector not in summary.get((system, samples, noise), {})
                       for noise in noises):
                    continue
                rate = [summary[(system, samples, noise)][selector] for noise in noises]
                axes[0][column].plot(noises, [hits / count for hits, count, _, _ in rate], style,
                                     marker="o", label=f"{selector}, {samples:.0e}")
                errors = [100 * e if e is not None else np.nan for _, _, e, _ in rate]
                axes[1][column].semilogy(noises, errors, style, marker="o")
        axes[0][column].set_title(system.replace("_", " "))
        axes[1][column].set_xlabel("noise on y, % of its standard deviation")
    axes[0][0].set_ylabel("records with exactly the true terms")
    axes[1][0].set_ylabel("median worst parameter error, %")
    axes[0][-1].legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(args.out, dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    study = commands.add_parser("run")
    study.add_argument("results")
    study.add_argument("--samples", type=int, nargs="+", default=[100000, 1000000])
    study.add_argument("--noise", type=float, nargs="+", default=[0.0, 5.0, 10.0])
    study.add_argument("--seeds", type=int, default=10)
    study.add_argument("--systems", nargs="+", default=list(SYSTEMS), choices=list(SYSTEMS))
    study.add_argument("--thresholds", type=float, nargs="*", default=list(THRESHOLDS))
    commands.add_parser("table").add_argument("results", nargs="+")
    drawing = commands.add_parser("plot")
    drawing.add_argument("out")
    drawing.add_argument("results", nargs="+")
    args = parser.parse_args()
    {"run": run, "table": table, "plot": plot}[args.command](args)


if __name__ == "__main__":
    main()
