"""Records made the way a structural-dynamics lab makes them, by numpy and scipy, not momentid.

A shaker drives the structure with a band-limited random force; the acquisition system samples
the force and the responses at 1 to 2 kHz, with sensor noise of a few percent of each channel's
standard deviation and, where asked, a small offset on a displacement. The CSV files hold a `t`
column and no `# momentid:` metadata, so momentid reads the force as samples of a continuous
signal, which it is:
  - nonlinear oscillators: the force is a periodic Gaussian signal whose spectrum is flat on a
    band of Hz (random complex amplitudes on the FFT lines of the band), known exactly on a grid
    of half the sample interval, and the equations are integrated by classical Runge-Kutta with
    the sample interval as its step (a relative error of order (omega dt)^4, 1e-8 here);
  - linear chains: the force is the output of a second-order low-pass filter driven by white
    noise, and the chain with its filter is sampled exactly (the matrix exponential of the
    augmented system, Van Loan's integral for the noise), from the stationary distribution.
"""
import json
import subprocess

import numpy as np
from scipy.linalg import expm, solve_continuous_lyapunov
from scipy.signal import lfilter

# The Duffing oscillator m y'' = -c y' - k y - eps y^3 + x (models/duffing.mom, m = 1) at 5 Hz.
SDOF = {"c": 4.0, "k": 1024.0, "eps": 400.0}
# lab.hardening: m y'' + c y' + k y + k3 y^3 = x with m = 1, in SI units.
HARDENING = {"c": 10.0, "k": 4.0e4, "k3": 4.0e9}
# models/duffing_2dof.mom with time 15 times faster: modes at 5.5 and 8.2 Hz.
TWO_MASS = {"c1": 6.0, "k1": 900.0, "eps1": 225.0, "c2": 4.5, "k2": 2025.0, "eps2": 112.5,
            "kc": 450.0}


def shaker_force(rng, samples, fs, band, rms):
    """A periodic Gaussian force of period samples/fs with a flat spectrum on `band` (Hz) and RMS
    `rms`, on the grid of 1/(2 fs) from 0 to samples/fs inclusive (2 samples + 1 values)."""
    n = 2 * samples
    frequency = np.fft.rfftfreq(n, 1 / (2 * fs))
    lines = (frequency >= band[0]) & (frequency <= band[1])
    spectrum = np.zeros(frequency.size, complex)
    spectrum[lines] = rng.standard_normal(lines.sum()) + 1j * rng.standard_normal(lines.sum())
    force = np.fft.irfft(spectrum, n)
    force *= rms / np.std(force)
    return np.append(force, force[0])


def integrate(rates, state, force, dt):
    """Classical Runge-Kutta with step dt for state' = rates(state, x), the force given on the
    grid of dt/2; returns the states at the force's even grid points (rows). Each state may be an
    array over records, the force then (grid points x records)."""
    steps = (len(force) - 1) // 2
    out = np.empty((steps + 1, len(state)) + np.shape(state[0]))
    s = list(state)
    out[0] = s
    half = dt / 2
    for i in range(steps):
        x0, x1, x2 = force[2 * i], force[2 * i + 1], force[2 * i + 2]
        k1 = rates(s, x0)
        k2 = rates([a + half * b for a, b in zip(s, k1)], x1)
        k3 = rates([a + half * b for a, b in zip(s, k2)], x1)
        k4 = rates([a + dt * b for a, b in zip(s, k3)], x2)
        s = [a + dt / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(s, k1, k2, k3, k4)]
        out[i + 1] = s
    return out


def oscillator(rng, rates, states, fs, samples, band, rms, burn_in):
    """Drives `rates` from rest with a shaker force and returns the record after `burn_in`
    seconds: a dict of the named states and `x`, the force, with `t` from 0."""
    total = samples + int(burn_in * fs)
    force = shaker_force(rng, total, fs, band, rms).tolist()
    path = integrate(rates, [0.0] * len(states), force, 1 / fs)[-samples:]
    record = {name: path[:, i] for i, name in enumerate(states)}
    record["x"] = np.array(force[2 * (total - samples) + 2::2])
    record["t"] = np.arange(samples) / fs
    return record


def oscillators(rngs, rates, states, fs, samples, band, rms, burn_in):
    """`oscillator` for each generator of `rngs`, integrated side by side (numpy over the
    records, a step for all of them at once)."""
    total = samples + int(burn_in * fs)
    force = np.column_stack([shaker_force(rng, total, fs, band, rms) for rng in rngs])
    path = integrate(rates, [np.zeros(len(rngs))] * len(states), force, 1 / fs)[-samples:]
    return [{**{name: path[:, i, r] for i, name in enumerate(states)},
             "x": force[2 * (total - samples) + 2::2, r], "t": np.arange(samples) / fs}
            for r in range(len(rngs))]


def sdof_rates(p=SDOF, asymmetric=None):
    """The rates of the Duffing oscillator of `p`; `asymmetric` adds {"k2": .., "c3": ..}, the
    terms -k2 y^2 - c3 v^3 that a Duffing model lacks."""
    c, k, eps = p["c"], p["k"], p["eps"]
    if not asymmetric:
        return lambda s, x: (s[1], -c * s[1] - k * s[0] - eps * s[0]**3 + x)
    k2, c3 = asymmetric["k2"], asymmetric["c3"]
    return lambda s, x: (s[1], -c * s[1] - k * s[0] - eps * s[0]**3 - k2 * s[0]**2
                         - c3 * s[1]**3 + x)


def sdof(rng, fs, samples, rms=800.0, p=SDOF, asymmetric=None):
    """The Duffing oscillator of `p` (see sdof_rates)."""
    return oscillator(rng, sdof_rates(p, asymmetric), ("y", "v"), fs, samples, (1.0, 40.0), rms,
                      10.0)


def sdofs(rngs, fs, samples, rms=800.0, p=SDOF):
    """sdof for each generator of `rngs`, side by side."""
    return oscillators(rngs, sdof_rates(p), ("y", "v"), fs, samples, (1.0, 40.0), rms, 10.0)


# The hardening oscillator's force band (Hz), its RMS and the burn-in (s).
HARDENING_DRIVE = ((5.0, 150.0), 60.0, 2.0)


def hardening_rates(s, x):
    """The rates of the hardening oscillator of HARDENING (see hardening)."""
    p = HARDENING
    return (s[1], x - p["c"] * s[1] - p["k"] * s[0] - p["k3"] * s[0]**3)


def with_acceleration(clean):
    """`clean` with the acceleration `a` of the hardening oscillator."""
    clean["a"] = hardening_rates((clean["y"], clean["v"]), clean["x"])[1]
    return clean


def hardening(rng, fs, samples):
    """A shaker test of a hardening oscillator in physical units: m = 1, c = 10, k = 4e4 (31.8 Hz),
    k3 = 4e9 (k3 y^2 about 0.6 k at one standard deviation of y), the force band-limited to
    5-150 Hz with RMS 60; the record holds y, v, the acceleration a and the force x."""
    return with_acceleration(oscillator(rng, hardening_rates, ("y", "v"), fs, samples,
                                        *HARDENING_DRIVE))


def hardenings(rngs, fs, samples):
    """hardening for each generator of `rngs`, side by side."""
    return [with_acceleration(clean) for clean in
            oscillators(rngs, hardening_rates, ("y", "v"), fs, samples, *HARDENING_DRIVE)]


def two_mass(rng, fs, samples, rms, p=TWO_MASS):
    """models/duffing_2dof.mom with the parameters `p`, the force on mass 2."""
    c1, k1, e1, c2, k2, e2, kc = (p[n] for n in ("c1", "k1", "eps1", "c2", "k2", "eps2", "kc"))

    def rates(s, x):
        y1, v1, y2, v2 = s
        return (v1, -c1 * v1 - k1 * y1 - e1 * y1**3 - kc * (y1 - y2),
                v2, -c2 * v2 - k2 * y2 - e2 * y2**3 - kc * (y2 - y1) + x)
    return oscillator(rng, rates, ("y1", "v1", "y2", "v2"), fs, samples, (1.0, 40.0), rms, 10.0)


def chain_truth(rng, masses):
    """A chain of len(masses) masses, each linked to the one before (the first to the ground)
    by a spring k_i and a damper c_i, and the last held to the ground by a spring kt:
    modes from about 4 to 40 Hz, the first damped at about 2%, springs and dampers scattered
    by 20% so that no two are alike."""
    n = len(masses)
    k = 16000.0 * rng.uniform(0.8, 1.2, n)
    c = 0.003 * k * rng.uniform(0.8, 1.2, n)
    truth = {f"c{i + 1}": c[i] for i in range(n)}
    truth.update({f"k{i + 1}": k[i] for i in range(n)})
    truth["kt"] = 2000.0
    return truth


def chain_model(masses, truth):
    """The model file of the chain, the masses as constants."""
    n = len(masses)
    lines = [f"model chain{n} \"{n} masses in a chain, the force on the last\"",
             "state " + ", ".join(f"y{i}, v{i}" for i in range(1, n + 1)),
             "input x",
             "param " + ", ".join(f"{name} = {value:.6g}" for name, value in truth.items()),
             "const " + ", ".join(f"m{i + 1} = {m:g}" for i, m in enumerate(masses))]
    lines += [f"y{i}' = v{i}" for i in range(1, n + 1)]
    for i in range(1, n + 1):
        terms = [f"-c{i}*v{i} - k{i}*y{i}" if i == 1 else
                 f"-c{i}*(v{i} - v{i - 1}) - k{i}*(y{i} - y{i - 1})"]
        if i < n:
            terms.append(f"- c{i + 1}*(v{i} - v{i + 1}) - k{i + 1}*(y{i} - y{i + 1})")
        else:
            terms.append(f"- kt*y{i} + x")
        lines.append(f"m{i}*v{i}' = " + " ".join(terms))
    return "\n".join(lines) + "\n"


def chain_matrices(masses, truth, corner, damping):
    """The chain and its force filter as z' = A z + b w, z = (y, v, x, x'), w white."""
    n = len(masses)
    stiffness = np.zeros((n, n))
    dampers = np.zeros((n, n))
    for i in range(n):
        for matrix, value in ((stiffness, truth[f"k{i + 1}"]), (dampers, truth[f"c{i + 1}"])):
            matrix[i, i] += value
            if i > 0:
                matrix[i - 1, i - 1] += value
                matrix[i, i - 1] -= value
                matrix[i - 1, i] -= value
    stiffness[n - 1, n - 1] += truth["kt"]
    inverse_mass = np.diag(1 / np.asarray(masses))
    a = np.zeros((2 * n + 2, 2 * n + 2))
    a[:n, n:2 * n] = np.eye(n)
    a[n:2 * n, :n] = -inverse_mass @ stiffness
    a[n:2 * n, n:2 * n] = -inverse_mass @ dampers
    a[2 * n - 1, 2 * n] = 1 / masses[-1]
    omega = 2 * np.pi * corner
    a[2 * n, 2 * n + 1] = 1.0
    a[2 * n + 1, 2 * n:] = (-omega**2, -2 * damping * omega)
    b = np.zeros(2 * n + 2)
    b[-1] = omega**2
    return a, b


def sample_exactly(rng, a, b, fs, samples):
    """Samples z' = A z + b w (w white, unit intensity) exactly at fs from its stationary
    distribution: the rows of z at 0, 1/fs, ..."""
    m = len(b)
    stationary = solve_continuous_lyapunov(a, -np.outer(b, b))
    # Van Loan: exp([[-A, bb'], [0, A']] dt) holds exp(A dt)' and the noise's covariance.
    block = np.zeros((2 * m, 2 * m))
    block[:m, :m], block[:m, m:], block[m:, m:] = -a, np.outer(b, b), a.T
    g = expm(block / fs)
    step = g[m:, m:].T
    covariance = step @ g[:m, m:]
    w, u = np.linalg.eigh((covariance + covariance.T) / 2)
    root = u * np.sqrt(np.clip(w, 0, None))
    w, u = np.linalg.eigh(stationary)
    start = (u * np.sqrt(np.clip(w, 0, None))) @ rng.standard_normal(m)
    # Diagonalised, the recursion z[j+1] = step z[j] + e[j] is one first-order filter per mode.
    eigenvalues, vectors = np.linalg.eig(step)
    drive = np.empty((samples, m), complex)
    drive[0] = np.linalg.solve(vectors, start)
    drive[1:] = np.linalg.solve(vectors, root @ rng.standard_normal((m, samples - 1))).T
    modes = np.empty_like(drive)
    for j, value in enumerate(eigenvalues):
        modes[:, j] = lfilter([1.0], [1.0, -value], drive[:, j])
    del drive
    return (modes @ vectors.T).real


def chain(rng, masses, truth, fs, samples, rms):
    """The chain sampled exactly at fs from its stationary distribution, driven by a force
    low-passed at 40 Hz (second order, damping 0.7) of RMS `rms`: a dict of y1..yn, their
    velocities v1..vn and accelerations a1..an, x and t."""
    n = len(masses)
    a, b = chain_matrices(masses, truth, 40.0, 0.7)
    stationary = solve_continuous_lyapunov(a, -np.outer(b, b))
    z = sample_exactly(rng, a, b, fs, samples) * (rms / np.sqrt(stationary[2 * n, 2 * n]))
    record = {f"y{i + 1}": z[:, i] for i in range(n)}
    record.update({f"v{i + 1}": z[:, n + i] for i in range(n)})
    # The accelerations are the rows of the velocities in z' = A z (the noise drives x' only).
    record.update({f"a{i + 1}": z @ a[n + i] for i in range(n)})
    record["x"] = z[:, 2 * n]
    record["t"] = np.arange(samples) / fs
    return record


def measured(rng, clean, noise, offset=0.0):
    """The channel as a sensor gives it: white noise of `noise` and an offset of `offset`
    times its standard deviation."""
    sd = np.std(clean)
    return clean + noise * sd * rng.standard_normal(clean.size) + offset * sd


def write_csv(path, columns, time_format="%.17g"):
    """A CSV file of the named columns, `t` first, with no metadata."""
    names = ["t"] + [name for name in columns if name != "t"]
    table = np.column_stack([columns[name] for name in names])
    # np.savetxt's text, formatted in one operation (a third faster than a row at a time).
    row = ",".join([time_format] + ["%.17g"] * (len(names) - 1)) + "\n"
    with open(path, "w") as out:
        out.write(",".join(names) + "\n")
        out.write((row * len(table)) % tuple(table.ravel().tolist()))


def identify(momentid, model, path, *options):
    """momentid identify's JSON report, or its exit status and messages when it failed."""
    result = subprocess.run([momentid, "identify", model, path, "--format", "json", *options],
                            capture_output=True, text=True)
    if result.returncode != 0:
        return {"failed": result.returncode, "stderr": result.stderr.strip()}
    return json.loads(result.stdout)


def describe(report, truth):
    """Prints the status, each estimate against the truth in standard errors, and the
    warnings; returns the largest distance in standard errors (inf when a parameter has none)."""
    if "failed" in report:
        print(f"  exit {report['failed']}: {report['stderr']}")
        return np.inf
    diagnostics = report["diagnostics"]
    method = report.get("method", {"name": "zero-lag"})
    window = ""
    if "lags" in method:
        window = f", lags {method['lags']}, instruments {method['instruments']}"
    print(f"  status {diagnostics['status']}, method {method['name']}{window}")
    worst = 0.0
    for name, value in truth.items():
        p = report["parameters"][name]
        se = p["std_error"]
        z = abs(p["estimate"] - value) / se if se else np.inf
        worst = max(worst, z)
        print(f"  {name}: {p['estimate']:.6g} +- {se:.3g} (truth {value:.6g}, "
              f"{z:.1f} SE, SE {se / abs(value):.2%} of the truth)")
    for warning in diagnostics["warnings"]:
        print(f"  warning: {warning}")
    return worst
