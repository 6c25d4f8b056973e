#!/usr/bin/python3
"""Simulate, identify, validate and plot the Duffing oscillator from Python.

  PYTHONPATH=build/python examples/python/duffing.py [--samples N] [--plot OUT.png]

Written the way a notebook user would: arrays in, estimates out, no files. The estimation
record has 2% sensor noise on y and no velocity column, as a measured one would; a second
record (another seed) checks the identified model by simulation.
"""
import argparse

import numpy as np

import momentid

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--samples", type=int, default=200_000)
parser.add_argument("--plot", help="draw the validation record against the model (PNG)")
args = parser.parse_args()

model = momentid.Model("""
    model duffing "Forced Duffing oscillator"
    state y, v
    input x
    param c, k, eps
    y' = v
    v' = -c*v - k*y - eps*y^3 + x
""")
truth = {"c": 0.5, "k": 4.0, "eps": 1.0}
excitation = {"x": "ma:K=10,w=0.1,sigma=20"}

# Two records of displacement and force, with 2% noise on the displacement.
estimation = momentid.simulate(model, truth, samples=args.samples, inputs=excitation, seed=11,
                               observe=["y", "x"], noise={"y": 0.02})
checking = momentid.simulate(model, truth, samples=args.samples // 4, inputs=excitation,
                             seed=12, observe=["y", "x"], noise={"y": 0.02})
print(f"{len(estimation['t'])} samples of {', '.join(k for k in estimation if k != 't')}")

# Without a velocity column, identify uses the lagged moment equations.
result = momentid.identify(model, estimation)
print(result)
for name, value in result.estimates.items():
    low, high = result.ci95[name]
    print(f"{name:>4} = {value:.4f}  (truth {truth[name]}, 95% interval [{low:.4f}, {high:.4f}])")

# Does the identified model reproduce a record it was not fitted to?
fits = {}
for label, values in [("identified", result.estimates),
                      ("20% off", {name: 0.8 * v for name, v in truth.items()})]:
    check = momentid.validate(model, checking, values)
    fits[label] = check
    print(f"validation, {label}: fit {check.fit['y']:.2f}%, rms error {check.rms['y']:.4g}")

if args.plot:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # The model's response to the checking record's input, from its initial state.
    window = slice(2000, 3000)
    t = checking["t"][window]
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True,
                             gridspec_kw={"height_ratios": [3, 1]})
    axes[0].plot(t, checking["y"][window], color="0.6", lw=2, label="measured y (2% noise)")
    for (label, values), color in zip([("identified", result.estimates),
                                       ("20% off", {n: 0.8 * v for n, v in truth.items()})],
                                      ["C0", "C3"]):
        response = momentid.simulate(model, values, inputs=checking)
        axes[0].plot(t, response["y"][window], color=color, lw=1,
                     label=f"{label}: fit {fits[label].fit['y']:.1f}%")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_ylabel("y")
    axes[0].set_title("Duffing oscillator: a record the model was not fitted to")
    axes[1].plot(t, checking["x"][window], color="C2", lw=0.8)
    axes[1].set_ylabel("input x")
    axes[1].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(args.plot, dpi=120)
    print(f"wrote {args.plot}")
