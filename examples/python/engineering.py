#!/usr/bin/python3
"""The numbers engineers read from an identified hardening oscillator, drawn with matplotlib.

  PYTHONPATH=build/python examples/python/engineering.py [--samples N] [--plot OUT.png]

A lightly damped Duffing oscillator under strong random forcing (displacement, velocity and
force recorded) is identified; the script prints its linearised natural frequency and damping
ratio, and draws (1) the restoring force with its 95% band against the true one, (2) the
backbone, the frequency of free oscillation against amplitude by harmonic balance, with its band
against the true model's, and (3) validate's comparison of the response spectrum with the band
that simulations of the identified model give. A lightly damped hardening oscillator's
trajectory is sensitive to its parameters: a fraction of a percent in k makes the simulation
drift from the record over a few hundred periods, while its statistics stay inside their bands.
"""
import argparse

import numpy as np

import momentid

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--samples", type=int, default=100_000)
parser.add_argument("--plot", help="draw the three panels (PNG)")
args = parser.parse_args()

model = momentid.Model("""
    model hardening "Lightly damped hardening oscillator"
    state y, v
    input x
    param c, k, eps
    y' = v
    v' = -c*v - k*y - eps*y^3 + x
""")
truth = {"c": 0.2, "k": 4.0, "eps": 2.0}
excitation = {"x": "ma:K=10,w=0.1,sigma=20"}
record = momentid.simulate(model, truth, samples=args.samples, inputs=excitation, seed=21)
checking = momentid.simulate(model, truth, samples=20_000, inputs=excitation, seed=22)

result = momentid.identify(model, record)
print(f"status {result.status}; estimates " +
      ", ".join(f"{n} = {v:.4g}" for n, v in result.estimates.items()))
(frequency, frequency_se), = result.natural_frequencies
(ratio, ratio_se), = result.damping_ratios
print(f"linearised: {frequency:.5f} +- {frequency_se:.2g} Hz (truth "
      f"{np.sqrt(truth['k']) / (2 * np.pi):.5f}), damping ratio {ratio:.4f} +- {ratio_se:.2g} "
      f"(truth {truth['c'] / (2 * np.sqrt(truth['k'])):.4f})")

force = result.engineering["restoring_force"]
backbone = result.engineering["backbone"]
y0 = result.engineering["equilibrium"]["y"]
amplitude = np.array(backbone["amplitude"])
true_backbone = np.sqrt(truth["k"] + 3 * truth["eps"] * y0**2
                        + 0.75 * truth["eps"] * amplitude**2) / (2 * np.pi)
z = np.abs(np.array(backbone["frequency_hz"]) - true_backbone) / np.array(backbone["std_error"])
print(f"backbone: {backbone['frequency_hz'][0]:.4f} Hz at amplitude {amplitude[0]:.3g} to "
      f"{backbone['frequency_hz'][-1]:.4f} Hz at {amplitude[-1]:.3g}; the true model's within "
      f"{z.max():.2f} standard errors")

check = momentid.validate(model, checking, result.estimates)
statistics = check.statistics or {}
print(f"validate: trajectory fit {check.fit['y']:.1f}% (sensitive: {check.sensitive}); "
      f"{statistics.get('outside', 'no')} of {len(statistics.get('checks', []))} statistics of "
      f"the response outside their bands")

if args.plot:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    y = np.array(force["displacement"])
    estimate, band = np.array(force["force"]), 1.96 * np.array(force["std_error"])
    axes[0].fill_between(y, estimate - band, estimate + band, color="C0", alpha=0.3,
                         label="95% band")
    axes[0].plot(y, estimate, color="C0", label="identified")
    axes[0].plot(y, truth["k"] * y + truth["eps"] * y**3, "k--", lw=1, label="true")
    axes[0].set_xlabel("displacement y")
    axes[0].set_ylabel("restoring force")
    axes[0].legend(fontsize=8)

    estimate, band = np.array(backbone["frequency_hz"]), 1.96 * np.array(backbone["std_error"])
    axes[1].fill_between(amplitude, estimate - band, estimate + band, color="C1", alpha=0.3,
                         label="95% band")
    axes[1].plot(amplitude, estimate, color="C1", label="identified")
    axes[1].plot(amplitude, true_backbone, "k--", lw=1, label="true (harmonic balance)")
    axes[1].set_xlabel("amplitude")
    axes[1].set_ylabel("frequency [Hz]")
    axes[1].legend(fontsize=8)

    psd = None
    if check.statistics and "checks" in check.statistics:
        psd = next((c for c in check.statistics["checks"]
                    if c["output"] == "y" and c["kind"] == "psd"), None)
    if psd is not None:
        f = np.array(psd["at"])
        axes[2].fill_between(f, psd["low"], psd["high"], color="C2", alpha=0.3,
                             label="simulations of the model")
        axes[2].semilogy(f, psd["measured"], color="k", lw=1, label="record")
        shown = f <= 2
        axes[2].set_xlim(0, 2)
        axes[2].set_ylim(0.5 * np.min(np.array(psd["low"])[shown]),
                         2 * np.max(np.array(psd["high"])[shown]))
        axes[2].legend(fontsize=8)
    axes[2].set_xlabel("frequency [Hz]")
    axes[2].set_ylabel("power spectral density of y")
    fig.tight_layout()
    fig.savefig(args.plot, dpi=120)
    print(f"wrote {args.plot}")
