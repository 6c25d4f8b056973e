"""Lightly damped hardening oscillators under strong random force, as numpy and scipy compute
them, not momentid: the records of the statistical validation tests.

The force is Gaussian white noise through a 4th-order Butterworth low-pass filter (scipy),
sampled at 1 kHz and held between samples (the records say `input-hold=zoh`); the response is
integrated by the classical Runge-Kutta method with 4 steps per sample, written here, from rest,
after a burn-in of 10 s. Both systems are sensitive to their initial state: a perturbation of
1e-6 of the spread grows to the spread within the record.

sdof: y'' = -c y' - k y - eps y^3 + x (models/duffing.mom), with 1% white noise on y and v.
two_mass: models/duffing_2dof.mom, a cubic spring on mass 1 only, the force on mass 2, no noise.
"""
import numpy as np
from scipy import signal

DT = 1e-3
SDOF = {"c": 0.2, "k": 100.0, "eps": 1e4}
TWO_MASS = {"c1": 0.2, "k1": 100.0, "eps1": 1e4, "c2": 0.2, "k2": 150.0, "eps2": 0.0, "kc": 50.0}


def held_force(rng, samples, cutoff, rms):
    """Band-limited Gaussian force samples: white noise low-pass filtered at `cutoff` Hz."""
    b, a = signal.butter(4, cutoff * 2 * DT)
    force = signal.lfilter(b, a, rng.standard_normal(samples + 5000))[5000:]
    return force * rms / force.std()


def sdof_rates(p):
    c, k, eps = p["c"], p["k"], p["eps"]
    return lambda s, x: (s[1], x - c * s[1] - k * s[0] - eps * s[0] ** 3)


def two_mass_rates(p):
    c1, k1, e1, c2, k2, e2, kc = (p[n] for n in ("c1", "k1", "eps1", "c2", "k2", "eps2", "kc"))

    def rates(s, x):
        y1, v1, y2, v2 = s
        return (v1, -c1 * v1 - k1 * y1 - e1 * y1 ** 3 - kc * (y1 - y2),
                v2, -c2 * v2 - k2 * y2 - e2 * y2 ** 3 - kc * (y2 - y1) + x)
    return rates


def integrate(rates, force, states, substeps=4):
    """The states at every sample, the force held over each interval."""
    h = DT / substeps
    s = (0.0,) * states
    out = np.empty((len(force), states))
    for n, x in enumerate(force):
        out[n] = s
        for _ in range(substeps):
            k1 = rates(s, x)
            k2 = rates(tuple(a + 0.5 * h * b for a, b in zip(s, k1)), x)
            k3 = rates(tuple(a + 0.5 * h * b for a, b in zip(s, k2)), x)
            k4 = rates(tuple(a + h * b for a, b in zip(s, k3)), x)
            s = tuple(a + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
                      for a, b1, b2, b3, b4 in zip(s, k1, k2, k3, k4))
    return out


def record(case, seconds, seed, path):
    """Writes the record of `case` ("sdof" or "two_mass") to `path` (t, the states, x)."""
    rng = np.random.default_rng(seed)
    burn_in = int(10 / DT)
    samples = int(seconds / DT)
    if case == "sdof":
        force = held_force(rng, burn_in + samples, 20.0, 50.0)
        states = integrate(sdof_rates(SDOF), force, 2)[burn_in:]
        states += 0.01 * states.std(axis=0) * rng.standard_normal(states.shape)
        names = "y,v"
    else:
        force = held_force(rng, burn_in + samples, 20.0, 100.0)
        states = integrate(two_mass_rates(TWO_MASS), force, 4)[burn_in:]
        names = "y1,v1,y2,v2"
    t = DT * np.arange(samples)
    with open(path, "w") as out:
        out.write(f"# momentid: dt={DT} input-hold=zoh\nt,{names},x\n")
        np.savetxt(out, np.column_stack([t, states, force[burn_in:]]), delimiter=",",
                   fmt="%.12g")
    return states
