#!/usr/bin/python3
"""Validates the Duffing oscillator on a record that scipy made, not momentid, and reads its plot.

The record holds displacement and force only, sampled every 0.1 s (about ten samples per period
of the fastest force component): the force is a sum of 30 sinusoids below 0.95 Hz, evaluated
exactly by scipy's DOP853 (tolerance 1e-11), so the samples are those of continuous signals.
With the true parameters, `momentid validate` must reproduce y with a fit above 99.9% through
band-limited interpolation of the force and a velocity estimated from the first samples of y,
and `simulate --input-file` must agree with scipy's y to 1e-5 of its spread once the estimated
initial velocity is forgotten, except in the last 24 rows, too near the end for the band-limited
stencil.
With the stiffness 20% off the fit must fall well below.

The SVG written by `--plot` is then parsed: its panels, the data ranges they declare, the first
plotted points mapped back to the measured and simulated values, and the correlation stems.

Usage: duffing_validate.py MOMENTID MODEL WORKDIR
"""
import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np

from scipy_duffing import TRUTH, duffing

SVG = "{http://www.w3.org/2000/svg}"


def run(command):
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(command)} failed:\n{result.stderr}")
    return result.stdout


def main():
    momentid, model, workdir = sys.argv[1:4]
    rng = np.random.default_rng(20261124)
    dt, burn_in, samples = 0.1, 60.0, 20000
    t = burn_in + dt * np.arange(samples)
    y, _, force = duffing(rng, 0.2, 6.0, 30, 5.0, t, 1e-11)
    path = f"{workdir}/independent_validate.csv"
    with open(path, "w") as out:
        out.write("# momentid: input-hold=sample\nt,y,x\n")
        np.savetxt(out, np.column_stack([t, y, force(t)]), delimiter=",", fmt="%.17g")

    plot = f"{workdir}/independent_validate.svg"
    result = json.loads(run([momentid, "validate", model, path, "--format", "json",
                             "--plot", plot, "--lags", "10"]))
    fit = result["outputs"]["y"]["fit_percent"]
    skip = result["skip"][0]
    print(f"true parameters: fit {fit:.4f}%, skip {skip} rows, "
          f"interpolation {result['interpolation']['x']}")
    failed = result["interpolation"]["x"] != "sinc" or not fit > 99.9

    replayed = f"{workdir}/independent_replay.csv"
    run([momentid, "simulate", model, "--input-file", path, "-o", replayed])
    simulated = np.loadtxt(replayed, delimiter=",", comments="#", skiprows=2)[:, 1]
    # Right after the skip, what is left of the estimated initial velocity shows (the skip ends
    # where a perturbation of 10% of the spread has fallen to 1% of itself); it is gone after
    # twice the skip. The last 24 intervals are too near the end for the band-limited stencil:
    # they take the cubic, whose error at ten samples per period shows there.
    spread = np.std(y)
    start = np.max(np.abs(simulated[skip:-24] - y[skip:-24])) / spread
    interior = np.max(np.abs(simulated[2 * skip:-24] - y[2 * skip:-24])) / spread
    end = np.max(np.abs(simulated[-24:] - y[-24:])) / spread
    print(f"simulate --input-file against scipy, relative to std(y): {start:.2e} after the "
          f"skip, {interior:.2e} after twice the skip, {end:.2e} over the last 24 rows")
    failed = failed or not start < 1e-3 or not interior < 1e-5 or not end < 1e-3

    off = json.loads(run([momentid, "validate", model, path, "--format", "json",
                          "--set", "k=4.8"]))
    off_fit = off["outputs"]["y"]["fit_percent"]
    print(f"k 20% off: fit {off_fit:.2f}%")
    failed = failed or not off_fit < 90

    failed = check_plot(plot, t, y, simulated, skip) or failed
    failed = check_thinned_plot(momentid, model, path, f"{workdir}/independent_long.svg",
                                t, y, skip) or failed
    if failed:
        sys.exit("FAILED")
    print("ok")


def check_plot(plot, t, y, simulated, skip):
    """Maps the plot back to numbers; True when something does not match."""
    root = ET.parse(plot).getroot()
    panels = [g for g in root.iter(f"{SVG}g") if "panel" in g.get("class", "").split()]
    kinds = [g.get("class").split()[1] for g in panels]
    print(f"plot panels: {kinds}")
    failed = kinds != ["signals", "error", "autocorrelation", "cross-correlation"]
    signals = panels[0]
    left, top = float(signals.get("data-left")), float(signals.get("data-top"))
    width, height = float(signals.get("data-width")), float(signals.get("data-height"))
    xmin, xmax = float(signals.get("data-xmin")), float(signals.get("data-xmax"))
    ymin, ymax = float(signals.get("data-ymin")), float(signals.get("data-ymax"))
    lines = {p.get("class"): p.get("points").split() for p in signals.iter(f"{SVG}polyline")}
    # The default window: 2000 rows from the first compared one.
    failed = failed or len(lines["measured"]) != 2000 or len(lines["simulated"]) != 2000
    failed = failed or abs(xmin - t[skip]) > 1e-9 or abs(xmax - t[skip + 1999]) > 1e-9
    for name, series in (("measured", y), ("simulated", simulated)):
        for k in (0, 777, 1999):
            px, py = (float(v) for v in lines[name][k].split(","))
            time = xmin + (px - left) / width * (xmax - xmin)
            value = ymin + (top + height - py) / height * (ymax - ymin)
            # Points are written to 0.01 px: about 1e-5 of the ranges.
            if abs(time - t[skip + k]) > 2e-5 * (xmax - xmin) or \
                    abs(value - series[skip + k]) > 1e-4 * (ymax - ymin):
                print(f"{name} point {k} reads ({time}, {value}), the data hold "
                      f"({t[skip + k]}, {series[skip + k]})")
                failed = True
    stems = [s for s in panels[2].iter(f"{SVG}line") if "stem" in s.get("class", "")]
    bands = [s for s in panels[2].iter(f"{SVG}line") if s.get("class") == "band"]
    cross = [s for s in panels[3].iter(f"{SVG}line") if "stem" in s.get("class", "")]
    print(f"correlation stems: {len(stems)} and {len(cross)}, bands {len(bands)}")
    failed = failed or len(stems) != 10 or len(cross) != 21 or len(bands) != 2
    return failed


def check_thinned_plot(momentid, model, path, plot, t, y, skip):
    """A window of more than 4000 rows keeps each stretch's extremes; True when it does not."""
    run([momentid, "validate", model, path, "--plot", plot, "--window", f"{t[skip]}:{t[-1]}"])
    root = ET.parse(plot).getroot()
    signals = next(g for g in root.iter(f"{SVG}g") if "signals" in g.get("class", ""))
    top, height = float(signals.get("data-top")), float(signals.get("data-height"))
    ymin, ymax = float(signals.get("data-ymin")), float(signals.get("data-ymax"))
    measured = next(p for p in signals.iter(f"{SVG}polyline") if p.get("class") == "measured")
    values = [ymin + (top + height - float(point.split(",")[1])) / height * (ymax - ymin)
              for point in measured.get("points").split()]
    window = y[skip:]
    print(f"thinned plot: {len(values)} points for {len(window)} rows, extremes "
          f"{min(values):.5f} {max(values):.5f} (data {window.min():.5f} {window.max():.5f})")
    resolution = 1e-4 * (ymax - ymin)
    return not (len(values) <= 4000 and abs(min(values) - window.min()) < resolution and
                abs(max(values) - window.max()) < resolution)


if __name__ == "__main__":
    main()
