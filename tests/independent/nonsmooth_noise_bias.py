"""The bias of the lagged equations on abs and sign terms of noisy channels, measured on records
of the independent generator (nonsmooth_records.py): the drag, friction and clearance
oscillators with y, v and the force measured, without noise and with white noise of 1% and 3%
of each channel's standard deviation on y and v (the force clean), and the clearance oscillator
from y and the force alone, without noise and with 3% on y. Prints, per record and method
(identify's default and the zero-lag equations), each estimate, its standard error and its
distance from the truth in standard errors: the table of docs/measured-data.md, "abs and sign
of noisy channels".

  nonsmooth_noise_bias.py MOMENTID WORKDIR [SAMPLES ...]   (default 100000 1000000)

Records are cached in WORKDIR as CASE_SAMPLES.npz (10^6 samples take about ten minutes each).
"""
import os
import sys

import numpy as np

import lab_records
import nonsmooth_records
from nonsmooth_identify import MODELS, write

SEED = {"drag": 11, "friction": 12, "clearance": 13}
# (case, channels, noise on the measured states)
RECORDS = [(case, ("y", "v", "x"), noise) for case in MODELS for noise in (0.0, 0.01, 0.03)] + [
    ("clearance", ("y", "x"), noise) for noise in (0.0, 0.03)]


def cached_record(case, samples, workdir):
    path = os.path.join(workdir, f"{case}_{samples}.npz")
    if not os.path.exists(path):
        record = nonsmooth_records.record(case, np.random.default_rng([SEED[case], samples]),
                                          samples)
        np.savez(path, **{k: record[k] for k in ("t", "y", "v", "x", "stuck")})
    return dict(np.load(path))


def main():
    momentid, workdir = sys.argv[1:3]
    lengths = [int(n) for n in sys.argv[3:]] or [100000, 1000000]
    print("case       channels  noise  samples  method    parameter  estimate    SE        SE/truth"
          "  distance/SE")
    for samples in lengths:
        for case, channels, noise in RECORDS:
            parameters, right, truth = MODELS[case]
            model = os.path.join(workdir, f"noise_bias_{case}.mom")
            with open(model, "w") as f:
                f.write(f"state y, v\ninput x\nparam {parameters}\ny' = v\nv' = {right}\n")
            record = cached_record(case, samples, workdir)
            path = os.path.join(workdir, f"noise_bias_{case}.csv")
            write(path, record, channels, noise,
                  np.random.default_rng([SEED[case], samples, round(1000 * noise)]))
            for method in ("auto", "zero-lag"):
                if method == "zero-lag" and "v" not in channels:
                    continue
                report = lab_records.identify(momentid, model, path, "--method", method)
                label = report.get("method", {}).get("name", "failed") if method == "auto" \
                    else "zero-lag"
                if "failed" in report:
                    print(f"{case:10} {','.join(channels):9} {noise:5.0%} {samples:8} {label:9} "
                          f"failed: {report['stderr']}")
                    continue
                for name in (n.strip() for n in parameters.split(",")):
                    p = report["parameters"][name]
                    z = (p["estimate"] - truth[name]) / p["std_error"]
                    print(f"{case:10} {','.join(channels):9} {noise:5.0%} {samples:8} {label:9} "
                          f"{name:10} {p['estimate']:<11.6g} {p['std_error']:<9.3g} "
                          f"{p['std_error'] / truth[name]:8.2%}  {z:+6.1f}")
                for warning in report["diagnostics"]["warnings"]:
                    if "abs" in warning or "sign" in warning:
                        print(f"    warning: {warning}")
            sys.stdout.flush()


if __name__ == "__main__":
    sys.exit(main())
