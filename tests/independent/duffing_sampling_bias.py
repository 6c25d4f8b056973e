#!/usr/bin/python3
"""The sampling bias of the zero-lag estimate, on a record that numpy and scipy made.

The Duffing oscillator (c = 0.5, k = 4, eps = 1) is driven by a sum of 200 sinusoids from 0.02
to 1.5 Hz and integrated by scipy's DOP853 (tolerance 1e-10) over 3000 s; y, v and the force are
sampled every 0.02, 0.04 and 0.08 s, the same continuous signals each time (input hold
`sample`). `identify --extrapolate dt` estimates each record's bias from every other sample:
  - the difference of the estimate and the estimate from every other sample must lie within
    four of its reported errors of the difference between the estimates at dt and 2 dt measured
    from the records themselves (the 0.04 s record is every other sample of the 0.02 s one);
  - the reported bias must be consistent with an error of order dt^2: over dt = 0.02 .. 0.08 the
    differences of successive estimates grow by 2^p, and p is printed.

Usage: duffing_sampling_bias.py MOMENTID MODEL WORKDIR
"""
import json
import subprocess
import sys

import numpy as np

from scipy_duffing import TRUTH, duffing


def main():
    momentid, model, workdir = sys.argv[1:4]
    rng = np.random.default_rng(20261124)
    burn_in, duration = 100.0, 3000.0
    t = burn_in + 0.02 * np.arange(int(duration / 0.02))
    y, v, force = duffing(rng, 2 * np.pi * 0.02, 2 * np.pi * 1.5, 200, 15.0, t, 1e-10)
    reports = {}
    for step in (1, 2, 4):
        dt = 0.02 * step
        path = f"{workdir}/independent_sampling_{step}.csv"
        with open(path, "w") as out:
            out.write(f"# momentid: dt={dt:g} input-hold=sample\nt,y,v,x\n")
            np.savetxt(out, np.column_stack([t, y, v, force(t)])[::step],
                       delimiter=",", fmt="%.17g")
        result = subprocess.run([momentid, "identify", model, path, "--degree", "3",
                                 "--extrapolate", "dt", "--format", "json"],
                                capture_output=True, text=True, check=True)
        reports[step] = json.loads(result.stdout)
    failed = False
    for name in TRUTH:
        fine = reports[1]["parameters"][name]["estimate"]
        bias = reports[1]["diagnostics"]["sampling_bias"]
        order = bias["order"]
        p = bias["parameters"][name]
        # What every other sample of the 0.02 s record gave, against the 0.04 s record itself
        # (both halves averaged against one of them: within the difference's error).
        coarse_difference = p["coarse"] - fine
        measured = reports[2]["parameters"][name]["estimate"] - fine
        ok = abs(coarse_difference - measured) < 4 * p["difference_error"]
        failed |= not ok
        wider = reports[4]["parameters"][name]["estimate"] - reports[2]["parameters"][name]["estimate"]
        growth = wider / measured if measured else float("nan")
        print(f"{name}: {fine:.9g}, from every other sample {p['coarse']:.9g} (difference "
              f"{coarse_difference:+.3g}, error {p['difference_error']:.3g}); the 0.04 s record "
              f"{measured:+.3g} {'ok' if ok else 'FAILED'}; next doubling {wider:+.3g}: "
              f"ratio {growth:.2f} (order {np.log2(abs(growth)):.2f}, assumed {order})")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
