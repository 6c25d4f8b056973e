#!/usr/bin/python3
"""Checks the generator of the non-smooth records (nonsmooth_records.py) before tests trust it.

  1. integration: for every case, held and continuous, 2 s after 1 s from rest, the record
     differs from the same integration at a ten times tighter tolerance by less than the
     accuracy the module states (relative to each state's standard deviation), and the
     continuous force's interpolation from its exact sum of lines by less than its stated
     accuracy. The sticky friction must stick, so that the stick logic is part of the check;
  2. moment equations: on 3e4 continuous samples of every case with y, v and x, the least-squares
     solution of the zero-lag moment equations, each batch's with its end terms, lies within 4
     standard errors (batch means) of the truth: with all six multipliers, and for friction
     also with the four that vanish with v, which sticking and the jumps of sign(v) between
     samples do not reach;
  3. sticking: the default friction sticks for less than STICK_BOUND of the record's time.

Prints a line per check; exits with 1 when one fails.
"""
import sys

import numpy as np

import nonsmooth_records as ns

SEED = 20270435
CASES = ("drag", "friction", "contact", "clearance", "cubic")
# Multipliers with a factor v: zero while the mass sticks and at every reversal.
MOVING = ("v", "y^2 v", "y v^2", "v^3")


def report(ok, text):
    """Prints the outcome of one check; returns it."""
    print(f"{'ok    ' if ok else 'FAILED'} {text}")
    return ok


def integration(case, params, hold):
    """Check 1 for one case and convention."""
    records = [ns.record(case, np.random.default_rng(SEED), 2048, hold=hold, params=params,
                         burn_in=1.0, rtol=rtol) for rtol in (ns.RTOL, ns.RTOL / 10)]
    difference = max(np.max(np.abs(records[0][s] - records[1][s])) / np.std(records[1][s])
                     for s in ("y", "v"))
    bound = ns.HELD_ACCURACY if hold == "held" else ns.CONTINUOUS_ACCURACY
    ok = report(difference < bound, f"{case} {params or ''} {hold}: largest difference "
                f"{difference:.1e} of std at a ten times tighter tolerance (bound {bound:g}), "
                f"{records[0]['switches']} switches, {records[0]['sticks']} sticks")
    if params is ns.STICKY_FRICTION:
        ok &= report(records[0]["sticks"] > 0, "the sticky friction sticks")
    return ok


def force_interpolation():
    """Check 1 for the continuous force."""
    rng = np.random.default_rng(SEED)
    force = ns.ShakerForce(rng, 20480, ns.FS, ns.BAND, ns.RMS)
    times = rng.uniform(0, 20479 / ns.FS, 2000)
    error = np.max(np.abs([force(t) for t in times] - force.exact(times))) / ns.RMS
    return report(error < ns.FORCE_ACCURACY, f"continuous force: largest interpolation error "
                  f"{error:.1e} of the RMS (bound {ns.FORCE_ACCURACY:g})")


def equations(case, record, multipliers):
    """Check 2 for one case and set of multipliers."""
    truth = ns.oscillator(case).params
    estimates = ns.moment_estimates(record, case, multipliers=multipliers, ends=True)
    ok = True
    for name, (estimate, se) in estimates.items():
        z = (estimate - truth[name]) / se
        ok &= report(abs(z) < 4, f"{case} {name}: {estimate:.7g} +- {se:.2g} (truth "
                     f"{truth[name]:g}, {z:+.1f} SE) from {', '.join(multipliers)}")
    return ok


def main():
    ok = force_interpolation()
    for case in CASES:
        for hold in ("held", "continuous"):
            ok &= integration(case, None, hold)
    for hold in ("held", "continuous"):
        ok &= integration("friction", ns.STICKY_FRICTION, hold)
    for case in CASES:
        record = ns.record(case, np.random.default_rng(SEED), 30000)
        ok &= equations(case, record, tuple(ns.MULTIPLIERS))
        if case == "friction":
            ok &= equations(case, record, MOVING)
            fraction = record["stick_fraction"]
            ok &= report(fraction < ns.STICK_BOUND, f"friction sticks {record['sticks']} times, "
                         f"{fraction:.2%} of the time (bound {ns.STICK_BOUND:.0%})")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
