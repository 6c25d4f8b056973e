#!/usr/bin/python3
"""Times `momentid identify` with its defaults on the ten-mass chain against an explicit window.

  benchmarks/chain_defaults.py [--samples 1e6] [--repeat 2] [--directory DIR]

The record is the one of tests/independent/lab_defaults.py's ten_mass case (a linear chain of
ten masses, 21 parameters, ten displacements and the force with 3% sensor noise, 1024 Hz, made
by numpy and scipy), as a CSV file of `samples` rows. It is identified with no option, and, as
the baseline in the same run, with `--lags 3..42 --instruments "y1, y5, y10"` (483 lagged
moments, within the budget of 3000). For each: the best wall time of `--repeat` runs, the
program's peak resident memory, the status and the largest distance of an estimate from the
truth in standard errors; then the defaults against the target of issue 32 (under 10 s and
1 GB, `ok`, every parameter within 3 standard errors).
"""
import argparse
import json
import os
import shlex
import shutil
import sys
import tempfile
import time

from bench_formats import run_with_peak

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "independent"))
import lab_defaults  # noqa: E402

MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
TARGET_SECONDS, TARGET_MB = 10.0, 1000.0


def identify(model, path, options, repeat, truth):
    """Best seconds, peak MB, status and the largest distance from the truth in standard
    errors; the message instead of the status when identify failed."""
    command = [MOMENTID, "identify", model, path, "--format", "json", *options]
    try:
        runs = [run_with_peak(command) for _ in range(repeat)]
    except RuntimeError as error:
        return None, None, str(error)[len(" ".join(command)) + 2:].strip(), None
    report = json.loads(runs[0][2])
    worst = max(abs(report["parameters"][n]["estimate"] - v) / report["parameters"][n]["std_error"]
                for n, v in truth.items())
    return (min(r[0] for r in runs), max(r[1] for r in runs), report["diagnostics"]["status"],
            worst)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=float, default=1e6)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--directory", default=None)
    args = parser.parse_args()
    samples = int(args.samples)
    directory = args.directory or tempfile.mkdtemp(prefix="momentid_chain_defaults_")
    os.makedirs(directory, exist_ok=True)
    try:
        start = time.perf_counter()
        model, path, truth = lab_defaults.ten_mass_record(directory, samples)
        print(f"ten-mass chain, {samples:.3g} samples, {os.path.getsize(path) / 1e6:.0f} MB "
              f"CSV, made in {time.perf_counter() - start:.1f} s; {os.cpu_count()} cores; "
              f"best of {args.repeat}")
        print(f"{'options':<52} {'s':>6} {'peak MB':>8} {'status':>10} {'worst SE':>9}")
        baseline = ["--lags", "3..42", "--instruments", lab_defaults.CHAIN_INSTRUMENTS]
        rows = {}
        for label, options in (("baseline: " + shlex.join(baseline), baseline),
                               ("defaults: no option", [])):
            seconds, peak, status, worst = rows[label] = identify(model, path, options,
                                                                  args.repeat, truth)
            if seconds is None:
                print(f"{label:<52} failed: {status}")
            else:
                print(f"{label:<52} {seconds:6.2f} {peak:8.0f} {status:>10} {worst:9.1f}")
        seconds, peak, status, worst = rows["defaults: no option"]
        if seconds is None:
            print("defaults: no result, the target is not met")
            return
        base_seconds = rows[next(iter(rows))][0]
        met = (seconds < TARGET_SECONDS and peak < TARGET_MB and status == "ok" and worst <= 3)
        print(f"defaults: {seconds / base_seconds:.2f} times the baseline's time; target "
              f"(< {TARGET_SECONDS:g} s, < {TARGET_MB:g} MB, ok within 3 SE) "
              f"{'met' if met else 'NOT met'}")
    finally:
        if args.directory is None:
            shutil.rmtree(directory)


if __name__ == "__main__":
    main()
