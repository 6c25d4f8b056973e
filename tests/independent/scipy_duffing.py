"""The Duffing oscillator as numpy and scipy compute it, not momentid: the record the independent
tests read.

duffing(rng, low, high, lines, rms, t, tolerance) drives y'' = -c y' - k y - eps y^3 + x(t) from
rest at time 0 with a force x that is a sum of `lines` cosines of angular frequencies drawn
uniformly from [low, high] rad/s and random phases, of RMS `rms`, evaluated exactly by the
integrator (DOP853, relative and absolute tolerance `tolerance`). Returns y and v at the times
`t`, and the force as a function of time.
"""
import numpy as np
from scipy.integrate import solve_ivp

TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0}


def duffing(rng, low, high, lines, rms, t, tolerance):
    omega = rng.uniform(low, high, lines)
    phase = rng.uniform(0, 2 * np.pi, lines)
    amplitude = rms * np.sqrt(2 / lines)

    def force(time):
        return amplitude * np.cos(np.multiply.outer(time, omega) + phase).sum(axis=-1)

    def rates(time, state):
        y, v = state
        return [v, -TRUTH["c"] * v - TRUTH["k"] * y - TRUTH["eps"] * y**3 + force(time)]

    solution = solve_ivp(rates, (0.0, t[-1]), [0.0, 0.0], method="DOP853", t_eval=t,
                         rtol=tolerance, atol=tolerance)
    assert solution.success, solution.message
    return solution.y[0], solution.y[1], force
