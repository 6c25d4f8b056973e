#!/usr/bin/python3
"""identify's zero-lag check on records with every state measured, from generators that numpy and
scipy run, not momentid: 10^5 samples at 1024 Hz, 3% white noise on y and v, no options.

  drag   an oscillator with quadratic drag c2 |v| v (nonsmooth_records.py), identified with a
         cubic-damping model c3 v^3: the lagged J test accepts it, the check must reject it
         (p < 0.01, status doubtful, the warning); the true drag model: a check that does not
         reject (its zero-lag equations hold abs(v) of the noisy v, uncorrected), status ok; select with the library {y, y^3, v,
         v^3, x}, which lacks the drag: the selection warns that the check rejects its choice.
  cubic  the generator's cubic-damping oscillator with the cubic-damping model: the check made
         and not rejecting, status ok, every parameter within 3 standard errors.
  size   the Duffing oscillator of lab_records.SDOF, 12 seeds, with 1% noise on the force too: under
         the true model the check's p-values are uniform, their mean within three standard
         errors of 1/2 (sqrt(1/12/12) = 0.083), and at most one of the 12 below 0.01 (the chance
         of two or more is 0.6%). No record draws the offset warning for v, whose mean over a
         record is (y(end) - y(start)) / T (it did on 4 of 40 before the ends' error was counted);
         the first record with v offset by 2% of its standard deviation does.

  study  not a test: the check's p-values over DRAG seeds of the drag record with the
         cubic-damping model (force clean and with 3% noise) and over TRUE seeds of the Duffing
         record with the true model: the figures of docs/measured-data.md, "The zero-lag check"
         (8 and 60).

Usage: zero_lag_check.py CASE MOMENTID WORKDIR [DRAG TRUE]
"""
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import lab_records
import nonsmooth_records

NOISE = 0.03
SAMPLES = 100000
DRAG_MODEL = "-c*v - c2*abs(v)*v - k*y + x"
CUBIC_MODEL = "-c*v - c3*v^3 - k*y + x"
SIZE_SEEDS = 12
WARNING = "the zero-lag check rejects the model"


def write_model(workdir, name, parameters, right):
    path = os.path.join(workdir, f"{name}.mom")
    with open(path, "w") as f:
        f.write(f"state y, v\ninput x\nparam {parameters}\ny' = v\nv' = {right}\n")
    return path


def measured(workdir, name, record, rng, force_noise=0.0):
    """The record with white noise on y and v (and on the force when asked) as a CSV."""
    columns = {"t": record["t"], "y": lab_records.measured(rng, record["y"], NOISE),
               "v": lab_records.measured(rng, record["v"], NOISE),
               "x": lab_records.measured(rng, record["x"], force_noise) if force_noise
               else record["x"]}
    path = os.path.join(workdir, f"{name}.csv")
    lab_records.write_csv(path, columns)
    return path


def check_of(report):
    diagnostics = report["diagnostics"]
    return diagnostics["status"], diagnostics.get("zero_lag_check"), diagnostics["warnings"]


def drag(momentid, workdir):
    rng = np.random.default_rng(1)
    path = measured(workdir, "drag", nonsmooth_records.record("drag", rng, SAMPLES), rng)
    cubic = lab_records.identify(momentid, write_model(workdir, "cubic", "c, c3, k", CUBIC_MODEL),
                                 path)
    status, check, warnings = check_of(cubic)
    print(f"cubic model: status {status}, J p {cubic['diagnostics']['j_pvalue']:.3g}, "
          f"check {check}")
    failed = []
    if not check or check["p_value"] is None or check["p_value"] >= 0.01:
        failed.append("the check does not reject the cubic-damping model")
    if status != "doubtful" or not any(w.startswith(WARNING) for w in warnings):
        failed.append(f"status {status} without the check's warning")
    true = lab_records.identify(momentid, write_model(workdir, "drag", "c, c2, k", DRAG_MODEL),
                                path)
    status, check, _ = check_of(true)
    print(f"drag model: status {status}, check {check}")
    if status != "ok":
        failed.append(f"the true drag model is {status}")
    if not check or check["p_value"] is None or check["p_value"] < 0.01:
        failed.append("the drag model's check, abs(v) of the noisy v uncorrected, is not made "
                      "or rejects the true model")
    library = os.path.join(workdir, "library.mom")
    with open(library, "w") as f:
        f.write("state y, v\ninput x\ny' = v\nv' = 0\nlibrary v': y, y^3, v, v^3, x\n")
    result = subprocess.run([momentid, "select", library, path, "--format", "json"],
                            capture_output=True, text=True)
    warnings = json.loads(result.stdout)["selection"]["warnings"] if result.returncode == 0 else []
    print(f"select: exit {result.returncode}, warnings {warnings}")
    if not any(w.startswith("the zero-lag check rejects the chosen model") for w in warnings):
        failed.append("select does not warn that the check rejects its choice")
    return failed


def cubic(momentid, workdir):
    rng = np.random.default_rng(2)
    path = measured(workdir, "cubic", nonsmooth_records.record("cubic", rng, SAMPLES), rng)
    report = lab_records.identify(
        momentid, write_model(workdir, "cubic", "c, c3, k", CUBIC_MODEL), path)
    status, check, _ = check_of(report)
    print(f"status {status}, check {check}")
    worst = lab_records.describe(report, {name: nonsmooth_records.CUBIC[name]
                                          for name in ("c", "c3", "k")})
    failed = []
    if status != "ok" or worst > 3:
        failed.append(f"status {status}, a parameter {worst:.1f} standard errors from the truth")
    if not check or check["p_value"] is None or check["degree"] != 5:
        failed.append("no check at degree 5")
    return failed


def size(momentid, workdir):
    model = os.path.join(workdir, "duffing.mom")
    with open(model, "w") as f:
        f.write("state y, v\ninput x\nparam c, k, eps\ny' = v\nv' = -c*v - k*y - eps*y^3 + x\n")

    def one(seed):
        rng = np.random.default_rng(20271500 + seed)
        record = lab_records.sdof(rng, 1024, SAMPLES)
        path = measured(workdir, f"duffing{seed}", record, rng, force_noise=0.01)
        _, check, warnings = check_of(lab_records.identify(momentid, model, path))
        if seed == 0:
            record["v"] = record["v"] + 0.02 * np.std(record["v"])
            path = measured(workdir, "duffing_v_offset", record, rng, force_noise=0.01)
            _, _, offset_warnings = check_of(lab_records.identify(momentid, model, path))
            warnings = warnings + ["offset: " + w for w in offset_warnings]
        return check["p_value"], warnings

    with ThreadPoolExecutor(2) as pool:
        results = list(pool.map(one, range(SIZE_SEEDS)))
    pvalues = np.array([p for p, _ in results])
    print("p-values:", " ".join(f"{p:.3f}" for p in np.sort(pvalues)))
    bound = 3 * np.sqrt(1 / 12 / SIZE_SEEDS)
    failed = []
    offset = "'v' has the mean"
    for seed, (_, warnings) in enumerate(results):
        if any(w.startswith(offset) for w in warnings):
            failed.append(f"record {seed}: the true record draws an offset warning for v")
    if not any(w.startswith("offset: " + offset) for w in results[0][1]):
        failed.append("the record with v offset by 2% draws no offset warning")
    if abs(pvalues.mean() - 0.5) > bound:
        failed.append(f"mean p-value {pvalues.mean():.3f} outside 0.5 +- {bound:.3f}")
    if np.sum(pvalues < 0.01) > 1:
        failed.append(f"{np.sum(pvalues < 0.01)} of {SIZE_SEEDS} true models rejected at 1%")
    return failed


def study(momentid, workdir, seeds, true_seeds):
    cubic_model = write_model(workdir, "cubic", "c, c3, k", CUBIC_MODEL)
    duffing = os.path.join(workdir, "duffing.mom")
    with open(duffing, "w") as f:
        f.write("state y, v\ninput x\nparam c, k, eps\ny' = v\nv' = -c*v - k*y - eps*y^3 + x\n")

    def drag_record(seed):
        rng = np.random.default_rng(seed)
        record = nonsmooth_records.record("drag", rng, SAMPLES)
        return [check_of(lab_records.identify(momentid, cubic_model,
                                              measured(workdir, f"drag{seed}_{noise}", record,
                                                       rng, force_noise=noise)))[1]["p_value"]
                for noise in (0.0, NOISE)]

    def duffing_record(seed):
        rng = np.random.default_rng(20271600 + seed)
        path = measured(workdir, f"duffing_study{seed}", lab_records.sdof(rng, 1024, SAMPLES), rng,
                        force_noise=0.01)
        return check_of(lab_records.identify(momentid, duffing, path))[1]["p_value"]

    with ThreadPoolExecutor(2) as pool:
        rejected = np.array([p for pair in pool.map(drag_record, range(1, seeds + 1))
                             for p in pair])
        true = np.array(list(pool.map(duffing_record, range(true_seeds))))
    for name, p in (("drag, cubic-damping model", rejected), ("Duffing, true model", true)):
        print(f"{name}: {len(p)} records, p < 0.01: {np.sum(p < 0.01)}, p < 0.05: "
              f"{np.sum(p < 0.05)}, mean p {p.mean():.3f}")


def main():
    case, momentid, workdir = sys.argv[1], sys.argv[2], os.path.join(sys.argv[3], "zero_lag_check")
    os.makedirs(workdir, exist_ok=True)
    if case == "study":
        study(momentid, workdir, *(int(n) for n in sys.argv[4:6]))
        return 0
    failed = {"drag": drag, "cubic": cubic, "size": size}[case](momentid, workdir)
    for f in failed:
        print("FAILED:", f)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
