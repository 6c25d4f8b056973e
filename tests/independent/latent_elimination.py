#!/usr/bin/python3
"""Checks the equations that `momentid derive` prints with the latent states eliminated on
trajectories that scipy integrates from the full models, written here in numpy.

Two models: the Duffing oscillator behind a first-order input filter (models/filtered_duffing.mom,
the filter's output z latent, y and x measured), and a two-mass chain with a cubic spring at the
second mass, sensed there only (models/chain_sensed.mom, mass 1 latent). The force is a sum of
sinusoids, differentiated exactly; the states come from DOP853 at a tolerance of 1e-12, and the
highest derivatives of the measured displacement from five-point central differences of the
model's accelerations (step 0.01 s, error about 1e-8 of the terms). On the trajectory of the
right parameters the printed equation's residual must be below 1e-5 of its terms' size; on one
whose parameter is 10% off (the filter's pole, the first mass's spring) it must be above 1e-3, so
the check can tell a wrong equation.

Usage: latent_elimination.py MOMENTID MODELS_DIR WORKDIR
"""
import json
import re
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp


class Force:
    """A sum of sinusoids and its exact derivatives."""

    def __init__(self, rng):
        self.a = rng.normal(0, 1, 12)
        self.w = rng.uniform(0.3, 4.0, 12)
        self.p = rng.uniform(0, 2 * np.pi, 12)

    def __call__(self, t, order=0):
        t = np.atleast_1d(t)[:, None]
        phase = self.w * t + self.p + order * np.pi / 2
        return (self.a * self.w**order * np.sin(phase)).sum(axis=1)


def filtered(p, force):
    def rhs(t, s):
        y, v, z = s
        x = force(t)[0]
        return [v, -p["c"] * v - p["k"] * y - p["eps"] * y**3 + p["g"] * z,
                -p["a"] * z + p["b"] * x]

    def acceleration(states, t):
        y, v, z = states
        return -p["c"] * v - p["k"] * y - p["eps"] * y**3 + p["g"] * z

    return rhs, acceleration, 0, 3


def chain(p, force):
    def acceleration(states, t):
        y1, v1, y2, v2 = states
        return (-p["c2"] * (v2 - v1) - p["k2"] * (y2 - y1) - p["eps"] * y2**3 + force(t))

    def rhs(t, s):
        y1, v1, y2, v2 = s
        a1 = -p["c1"] * v1 - p["k1"] * y1 - p["c2"] * (v1 - v2) - p["k2"] * (y1 - y2)
        return [v1, a1, v2, acceleration(np.array(s)[:, None], t)[0]]

    return rhs, acceleration, 2, 4


def derivatives(model, p, force, times):
    """y and its derivatives to order 4 at `times`, from one integration."""
    rhs, acceleration, at, size = model(p, force)
    solution = solve_ivp(rhs, (0, times[-1] + 1), np.zeros(size), method="DOP853",
                         rtol=1e-12, atol=1e-12, dense_output=True)
    h = 1e-2
    acc = {k: acceleration(solution.sol(times + k * h), times + k * h) for k in (-2, -1, 0, 1, 2)}
    state = solution.sol(times)
    # Five-point central differences, error O(h^4).
    return [state[at], state[at + 1], acc[0],
            (acc[-2] - 8 * acc[-1] + 8 * acc[1] - acc[2]) / (12 * h),
            (-acc[-2] + 16 * acc[-1] - 30 * acc[0] + 16 * acc[1] - acc[2]) / (12 * h**2)]


def cube_derivatives(d):
    y, y1, y2, y3 = d[:4]
    return [y**3, 3 * y**2 * y1, 6 * y * y1**2 + 3 * y**2 * y2,
            6 * y1**3 + 18 * y * y1 * y2 + 3 * y**2 * y3]


def residual(equation, values, d, force, times):
    """The printed equation's residual and the size of its terms, RMS over `times`."""
    cube = cube_derivatives(d)
    total, size = 0, 0
    for term in equation["terms"]:
        coefficient = eval(term["coefficient"].replace("^", "**"), {}, dict(values))
        order = term["order"]
        base = re.sub(r"(\^\(\d+\)|'+)$", "", term["signal"]).strip("()") if order else term["signal"]
        if base == "x":
            signal = force(times, order)
        elif base.endswith("^3"):
            signal = cube[order]
        else:
            signal = d[order]
        total = total + coefficient * signal
        size = size + (coefficient * signal) ** 2
    return np.sqrt(np.mean(total**2)), np.sqrt(np.mean(size))


def main():
    momentid, models, workdir = sys.argv[1:4]
    cases = [
        ("filtered_duffing", f"{models}/filtered_duffing.mom", "y,x", filtered,
         {"c": 0.5, "k": 4, "eps": 1, "a": 2, "g": 1, "b": 2}, "a"),
        ("chain", f"{models}/chain_sensed.mom", "y2,x", chain,
         {"c1": 0.3, "k1": 5, "c2": 0.2, "k2": 3, "eps": 1}, "k1"),
    ]
    rng = np.random.default_rng(20261130)
    times = np.linspace(20, 60, 4001)
    failed = False
    for name, path, measured, model, values, perturbed in cases:
        printed = subprocess.run(
            [momentid, "derive", path, "--lags", "3..42", "--measured", measured, "--format",
             "json"], capture_output=True, text=True, check=True)
        equation = json.loads(printed.stdout)["equations"][0]
        force = Force(rng)
        right = residual(equation, values, derivatives(model, values, force, times), force, times)
        off = dict(values, **{perturbed: 1.1 * values[perturbed]})
        wrong = residual(equation, values, derivatives(model, off, force, times), force, times)
        ok = right[0] < 1e-5 * right[1] and wrong[0] > 1e-3 * wrong[1]
        failed |= not ok
        print(f"{name}: residual {right[0] / right[1]:.2e} of the terms on the model's trajectory, "
              f"{wrong[0] / wrong[1]:.2e} with {perturbed} 10% off: {'ok' if ok else 'FAILED'}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
