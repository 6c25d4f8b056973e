"""identify with no options on oscillators with drag, Coulomb friction and a clearance spring,
from records of the independent generator (nonsmooth_records.py): y, v and the force measured
without noise, 10^5 samples at 1024 Hz of a continuous 1-40 Hz force. Each must come out `ok`
with every parameter within 3 standard errors of the truth.

  nonsmooth_identify.py CASE MOMENTID WORKDIR     (CASE: drag, friction or clearance)
"""
import os
import sys

import numpy as np

import lab_records
import nonsmooth_records

MODELS = {
    "drag": ("c, c2, k", "-c*v - c2*abs(v)*v - k*y + x", nonsmooth_records.DRAG),
    "friction": ("c, f, k", "-c*v - f*sign(v) - k*y + x", nonsmooth_records.FRICTION),
    "clearance": ("c, k, kc", "-c*v - k*y - kc*abs(y)*y + x", nonsmooth_records.CLEARANCE),
}
SEED = {"drag": 1, "friction": 2, "clearance": 3}


def main():
    case, momentid, workdir = sys.argv[1:4]
    parameters, right, truth = MODELS[case]
    model = os.path.join(workdir, f"nonsmooth_{case}.mom")
    with open(model, "w") as f:
        f.write(f"state y, v\ninput x\nparam {parameters}\ny' = v\nv' = {right}\n")
    record = nonsmooth_records.record(case, np.random.default_rng(SEED[case]), 100000)
    path = os.path.join(workdir, f"nonsmooth_{case}.csv")
    nonsmooth_records.write(path, record)
    report = lab_records.identify(momentid, model, path)
    names = [name.strip() for name in parameters.split(",")]
    worst = lab_records.describe(report, {name: truth[name] for name in names})
    status = report.get("diagnostics", {}).get("status")
    if status != "ok" or worst > 3:
        print(f"FAILED: status {status}, a parameter {worst:.1f} standard errors from the truth")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
