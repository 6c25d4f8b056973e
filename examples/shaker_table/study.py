#!/usr/bin/python3
"""A mass on a hardening spring mounted on a shaker table, measured as a lab measures it: one
accelerometer on the table, one on the mass, 2048 Hz, 2% white noise and an offset of 1% of each
channel's standard deviation, a CSV file with a units row as a DAQ writes it. The equations are
those of the motion relative to the table (models/base_excitation.mom), so the record's columns
enter as sums:

  momentid identify models/base_excitation.mom table_mass.csv \\
      --columns "z''=acc_mass-acc_table,a=acc_table" --integrate z

Each seed's record is identified that way (`sum`) and as a user without sums might try it, the
mass's absolute acceleration taken for the relative one (`absolute`: z''=acc_mass). The study
prints, per parameter and way, the mean error over the seeds in percent of the truth, the rms of
error / standard error and how many 95% intervals hold the truth, and each way's statuses.

Records are made by numpy and scipy (tests/independent/lab_records.py, classical Runge-Kutta on
a table acceleration known between samples), not by momentid.

  study.py [--samples N] [--seeds K] [--keep DIR]

Uses build/momentid, or the MOMENTID environment variable.
"""
import argparse
import collections
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tests", "independent"))
import lab_records as lab  # noqa: E402

FS = 2048
NOISE = 0.02
OFFSET = 0.01
TRUTH = lab.HARDENING  # c = 10, k = 4e4, k3 = 4e9 per unit mass
MODEL = os.path.join(ROOT, "models", "base_excitation.mom")
WAYS = {"sum": "z''=acc_mass-acc_table,a=acc_table", "absolute": "z''=acc_mass,a=acc_table"}


def record(seed, samples, path):
    """Writes a shaker-table record of `samples` rows to `path`: time, table and mass
    accelerations in m/s^2 under a units row."""
    rng = np.random.default_rng(seed)

    def rates(s, table):
        z, w = s
        return (w, -table - TRUTH["c"] * w - TRUTH["k"] * z - TRUTH["k3"] * z**3)
    # The table's acceleration: band-limited to 5-150 Hz, RMS 60 m/s^2.
    clean = lab.oscillator(rng, rates, ("z", "w"), FS, samples, (5.0, 150.0), 60.0, 2.0)
    table = clean["x"]
    relative = (-table - TRUTH["c"] * clean["w"] - TRUTH["k"] * clean["z"]
                - TRUTH["k3"] * clean["z"]**3)
    columns = [clean["t"], lab.measured(rng, table, NOISE, OFFSET),
               lab.measured(rng, table + relative, NOISE, OFFSET)]
    with open(path, "w") as out:
        out.write("Time,acc_table,acc_mass\ns,m/s^2,m/s^2\n")
        np.savetxt(out, np.column_stack(columns), delimiter=",", fmt="%.9g")


def identify(momentid, path, columns):
    done = subprocess.run([momentid, "identify", MODEL, path, "--columns", columns,
                           "--integrate", "z", "--format", "json"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"momentid identify failed: {done.stderr}")
    return json.loads(done.stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=200000)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--keep", help="write the records into this directory")
    args = parser.parse_args()
    momentid = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
    errors = collections.defaultdict(list)
    statuses = collections.defaultdict(list)
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.keep or scratch
        for seed in range(1, args.seeds + 1):
            path = os.path.join(folder, f"table_mass_{seed}.csv")
            record(20261128 + seed, args.samples, path)
            for way, columns in WAYS.items():
                report = identify(momentid, path, columns)
                statuses[way].append(report["diagnostics"]["status"])
                for name, value in TRUTH.items():
                    p = report["parameters"][name]
                    errors[way, name].append((p["estimate"] - value, p["std_error"], value))
    print(f"{args.seeds} records of {args.samples} samples")
    print(f"{'way':9s} {'parameter':9s} {'mean error':>11s} {'rms z':>7s} {'in 95%':>7s}")
    for way in WAYS:
        for name in TRUTH:
            e = np.array(errors[way, name])
            z = e[:, 0] / e[:, 1]
            print(f"{way:9s} {name:9s} {100 * np.mean(e[:, 0] / e[:, 2]):+10.1f}% "
                  f"{np.sqrt(np.mean(z**2)):7.2f} {np.sum(np.abs(z) < 1.96):4d}/{len(z)}")
        counts = collections.Counter(statuses[way])
        print(f"{way:9s} status    " + ", ".join(f"{k} {n}" for k, n in sorted(counts.items())))


if __name__ == "__main__":
    main()
