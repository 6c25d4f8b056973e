#!/usr/bin/python3
"""The J test on the path that forms a state from its acceleration (--integrate), on records numpy
makes (lab_records.hardening, as coverage.py's `integrate` case: 2048 Hz, 10^5 samples, the force
with 2% noise), in three versions of each record:

  noisy    the acceleration with 2% noise, y formed by --integrate y;
  clean    the acceleration without noise, y formed by --integrate y;
  laser    the acceleration with 2% noise and y measured (2% noise), nothing formed.

Printed per version: the mean and standard deviation of J over its degrees of freedom, the mean
p-value and the records the 5% test rejects (the true model: J/d near 1, p-values uniform). A
study, not a test: docs/uncertainty.md quotes it. Extra arguments go to identify (--batches N).

Usage: formed_j.py MOMENTID WORKDIR [SEEDS] [identify options...]
"""
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import lab_records as lab
from coverage import HARDENING

VERSIONS = ("noisy", "clean", "laser")


def record(workdir, version, seed):
    path = os.path.join(workdir, f"{version}_{seed}.csv")
    if os.path.exists(path):
        return path
    rng = np.random.default_rng(seed)
    clean = lab.hardening(rng, 2048, 100000)
    columns = {"t": clean["t"],
               "a": lab.measured(rng, clean["a"], 0.0 if version == "clean" else 0.02),
               "x": lab.measured(rng, clean["x"], 0.02)}
    if version == "laser":
        columns["y"] = lab.measured(rng, clean["y"], 0.02)
    lab.write_csv(path + ".part", columns)
    os.replace(path + ".part", path)
    return path


def main():
    momentid, workdir = sys.argv[1], os.path.join(sys.argv[2], "formed_j")
    seeds = int(sys.argv[3]) if len(sys.argv) > 3 else 12
    extra = sys.argv[4:]
    os.makedirs(workdir, exist_ok=True)
    model = os.path.join(workdir, "hardening.mom")
    with open(model, "w") as out:
        out.write(HARDENING)
    for version in VERSIONS:
        formed = [] if version == "laser" else ["--integrate", "y"]

        def one(seed):
            result = subprocess.run([momentid, "identify", model, record(workdir, version, seed),
                                     "--format", "json", "--quiet", *formed, *extra],
                                    capture_output=True, text=True, check=True)
            d = json.loads(result.stdout)["diagnostics"]
            return d["j_statistic"] / d["j_dof"], d["j_pvalue"]

        with ThreadPoolExecutor(2) as pool:
            r = np.array(list(pool.map(one, range(20281000, 20281000 + seeds))))
        print(f"{version:6} J/d mean {r[:, 0].mean():.2f} sd {r[:, 0].std():.2f}, "
              f"mean p {r[:, 1].mean():.2f}, rejected at 5%: {(r[:, 1] < 0.05).sum()} of {seeds}")


if __name__ == "__main__":
    main()
