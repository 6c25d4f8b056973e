"""Records of oscillators with non-smooth forces, made by numpy and scipy, not momentid.

One mass (m = 1) on a spring and a damper, driven by a shaker force x:

    y' = v,    v' = x - c v - k y - N(y, v)

with one of these forces N (the cases):

    drag       N = c2 |v| v                       quadratic damping
    friction   N = f sign(v)                      Coulomb friction, with sticking (below)
    contact    N = kc (y - g + |y - g|)/2         a one-sided stop of stiffness kc at the gap g
    clearance  N = kc |y| y
    cubic      N = c3 v^3                         smooth: the model a drag record must refuse

The force is a periodic Gaussian signal whose spectrum is flat on a band of Hz, the signal that
lab_records.shaker_force draws from the same generator, in one of two conventions:
  - `continuous`: the band-limited signal itself. Its exact values, slopes and curvatures are
    computed by FFT on a grid 8 times finer than the samples and joined by quintic Hermite
    interpolation, within 1e-12 of its RMS of the exact signal and smooth enough (C^2) not to
    stall the integrator's convergence; the record holds its samples, which momentid reads as
    samples of a continuous signal;
  - `held`: the sample x_n held over [t_n, t_n+1), what `momentid simulate --input-file REC
    --interpolation zoh` replays.
Both conventions of one seed have the same samples x_n.

Each smooth region of N (a sign of v, of y - g or of y) is integrated by scipy's DOP853 with
relative tolerance 1e-10, the switch located as a terminal event (to rounding) and the
integration restarted there in the region that the vector field enters; a held force restarts it
at every sample as well, where the force jumps. Friction sticks when v reaches 0 with
|x - k y| <= f: then v = 0 and y stays put until |x - k y| exceeds f, and the mass slides in the
direction of x - k y (Filippov's solution). With a held force that can only happen at a sample;
with a continuous one the time is found by Brent's method on the interpolated force.

Accuracy (HELD_ACCURACY, CONTINUOUS_ACCURACY below, which nonsmooth_check.py holds the
integration to): y and v within 1e-12 (held) and 1e-8 (continuous) of their standard deviation.
Speed: 10^5 samples after the 10 s burn-in take about 20 s of one core held (one DOP853 run per
sample interval) and 10 s continuous.
"""
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from lab_records import measured, write_csv

# At 1024 Hz a 5 Hz oscillator (k = 1024) with 6% viscous damping, as lab_records.SDOF, driven
# on 1-40 Hz with an RMS of 800, which alone gives std(y) 0.95 and std(v) 31 (y in mm, say).
# Each non-smooth force is a large part of the response (shares measured on 30 s):
#   drag: c2 E|v|^3 dissipates 54% of the power the force puts in (c E[v^2] the rest);
#   friction: f E|v| dissipates 52%; 2.7% of the velocity's reversals stick, each for a few
#     ms, about 0.15% of the time in all (STICK_BOUND is the bound the check holds it to);
#   contact: a stop three times as stiff as the spring at 0.6 std(y), touched 19% of the time,
#     carrying 24% of E[y (k y + N)];
#   clearance: kc |y| y carries 36% of E[y (k y + N)];
#   cubic: c3 v^3 dissipates 47%, as much as the drag: the model a drag record must refuse.
FS = 1024
BAND = (1.0, 40.0)
RMS = 800.0
BURN_IN = 10.0
RTOL = 1e-10
DRAG = {"c": 4.0, "k": 1024.0, "c2": 0.15}
FRICTION = {"c": 4.0, "k": 1024.0, "f": 120.0}
CONTACT = {"c": 4.0, "k": 1024.0, "kc": 3072.0, "g": 0.5}
CLEARANCE = {"c": 4.0, "k": 1024.0, "kc": 500.0}
CUBIC = {"c": 4.0, "k": 1024.0, "c3": 0.003}
STICK_BOUND = 0.02
# Friction that sticks in about a third of the reversals, 1.2% of the time: the stick logic at
# work, and the bias of sticking on the moment equations made visible.
STICKY_FRICTION = {"c": 4.0, "k": 1024.0, "f": 300.0}
# The accuracy that nonsmooth_check.py holds the integration to: the largest difference in y or
# v, relative to its standard deviation, from the same integration at a ten times tighter
# tolerance, measured over 96 records of 2 s (every case, 8 seeds, both conventions). Held,
# DOP853 crosses a sample interval in a step or two with an error near rounding (at most
# 4.4e-14). Continuous, the local errors of the steps add up over the damping's memory to a few
# times the tolerance (1.2e-10 to 1.3e-9; the difference from a tolerance of 1e-12 is the same,
# and that from 1e-11 ten times smaller, so the difference measures the error). The continuous
# force's largest error, relative to its RMS, is that of the quintic interpolation (3e-13).
HELD_ACCURACY = 1e-12
CONTINUOUS_ACCURACY = 1e-8
FORCE_ACCURACY = 1e-9
# The grid of the continuous force, in points per sample interval.
FINE = 8


class ShakerForce:
    """A periodic Gaussian force of period `samples`/fs with a flat spectrum on `band` (Hz) and
    RMS `rms`: random complex amplitudes on the FFT lines of the band.

    `samples` holds x(t_n) at t_n = n/fs; calling the force gives the band-limited signal at any
    time in [0, samples/fs] (quintic Hermite between exact values, slopes and curvatures on a
    grid of 1/(FINE fs));
    `exact(t)` sums the lines, slowly, to check the interpolation."""

    def __init__(self, rng, samples, fs, band, rms):
        n = FINE * samples
        self.step = 1 / (FINE * fs)
        frequency = np.fft.rfftfreq(n, self.step)
        lines = (frequency >= band[0]) & (frequency <= band[1])
        spectrum = np.zeros(frequency.size, complex)
        spectrum[lines] = rng.standard_normal(lines.sum()) + 1j * rng.standard_normal(lines.sum())
        scale = rms / np.std(np.fft.irfft(spectrum, n))
        # Values, slopes and curvatures, periodic: the last point is the first again.
        self.grid = np.stack([
            np.fft.irfft(spectrum * (2j * np.pi * frequency * self.step)**order, n) * scale
            for order in range(3)], axis=1)
        self.grid = np.vstack([self.grid, self.grid[:1]])
        self.samples = self.grid[:-1:FINE, 0]
        self.lines = 2 * np.pi * frequency[lines]
        self.amplitudes = 2 * scale / n * spectrum[lines]

    def __call__(self, t):
        """x(t), the quintic Hermite interpolant of the exact values, slopes and curvatures."""
        i = min(int(t / self.step), self.samples.size * FINE - 1)
        u = t / self.step - i
        # Python floats from one slice: numpy's scalars would double the integration's time.
        x0, d0, a0, x1, d1, a1 = self.grid[i:i + 2].ravel().tolist()
        u2, u3 = u * u, u * u * u
        w = 10 - 15 * u + 6 * u2
        return (x0 + (x1 - x0) * u3 * w + d0 * (u - u3 * (6 - 8 * u + 3 * u2))
                - d1 * u3 * (4 - 7 * u + 3 * u2) + a0 * u2 * (1 - u) ** 3 / 2
                + a1 * u3 * (1 - u) ** 2 / 2)

    def exact(self, t):
        """x at the times `t` (array), summed over the lines."""
        return (np.exp(1j * np.multiply.outer(t, self.lines)) @ self.amplitudes).real


class Oscillator:
    """y' = v, v' = x - c v - k y - N(y, v). A subclass gives N in each region s (-1 or +1) where
    it is smooth, continued smoothly past the switch so that an integrator can step over it;
    the switch: the state (`switch_state`, 0 for y, 1 for v) whose sign about `level` is s; the
    side a trajectory takes from the switch; and N per unit of its parameter as a function of
    the measured channels."""

    switch_state = None
    level = 0.0

    def __init__(self, params):
        self.params = dict(params)
        self.c, self.k = params["c"], params["k"]

    def rates(self, y, v, x, s):
        """(y', v') in region s."""
        return v, x - self.c * v - self.k * y - self.force(y, v, s)

    def switch(self, state):
        """The switch function, whose sign is the region."""
        return state[self.switch_state] - self.level

    def region(self, state, x):
        """The region of a state: the sign of the switch function, or where the field goes from
        the switch."""
        if self.switch_state is None:
            return 1
        sigma = self.switch(state)
        return int(np.sign(sigma)) if sigma != 0 else self.side(*state, x)

    def side(self, y, v, x):
        """The region a trajectory enters from the switch of y: where y moves, or where the
        force pushes it from rest."""
        return _sign(v if v != 0 else x - self.k * y)


def _sign(value):
    return 1 if value > 0 else -1


class Drag(Oscillator):
    """N = c2 |v| v."""
    term, switch_state = "c2", 1

    def force(self, y, v, s):
        return self.params["c2"] * s * v * v

    def side(self, y, v, x):
        return _sign(x - self.k * y)

    @staticmethod
    def basis(y, v):
        return np.abs(v) * v


class Friction(Oscillator):
    """N = f sign(v) while the mass slides; in region 0 it sticks (v = 0, N = x - k y)."""
    term, switch_state = "f", 1

    def force(self, y, v, s):
        return self.params["f"] * s

    def side(self, y, v, x):
        """Slides where x - k y points when it overcomes f, else sticks (0)."""
        drive = x - self.k * y
        return _sign(drive) if abs(drive) > self.params["f"] else 0

    def rates(self, y, v, x, s):
        return super().rates(y, v, x, s) if s else (0.0, 0.0)

    @staticmethod
    def basis(y, v):
        return np.sign(v)


class Contact(Oscillator):
    """N = kc max(y - g, 0), a stop at the gap g."""
    term, switch_state = "kc", 0

    def __init__(self, params):
        super().__init__(params)
        self.level = params["g"]

    def force(self, y, v, s):
        return self.params["kc"] * (y - self.params["g"]) if s > 0 else 0.0

    def basis(self, y, v):
        return np.maximum(y - self.params["g"], 0.0)


class Clearance(Oscillator):
    """N = kc |y| y."""
    term, switch_state = "kc", 0

    def force(self, y, v, s):
        return self.params["kc"] * s * y * y

    @staticmethod
    def basis(y, v):
        return np.abs(y) * y


class Cubic(Oscillator):
    """N = c3 v^3, smooth."""
    term = "c3"

    def force(self, y, v, s):
        return self.params["c3"] * v**3

    @staticmethod
    def basis(y, v):
        return v**3


CASES = {"drag": (Drag, DRAG), "friction": (Friction, FRICTION), "contact": (Contact, CONTACT),
         "clearance": (Clearance, CLEARANCE), "cubic": (Cubic, CUBIC)}


def oscillator(case, params=None):
    """The oscillator of a case ("drag", "friction", "contact", "clearance", "cubic") with the
    case's default parameters, or `params`."""
    kind, defaults = CASES[case]
    return kind(params or defaults)


class Tally:
    """Switches located, sticks and time stuck from `start` on (the record after its burn-in)."""

    def __init__(self, start):
        self.start = start
        self.switches = 0
        self.sticks = 0
        self.stuck = 0.0

    def switch(self, t, region):
        if t >= self.start:
            self.switches += 1
            self.sticks += region == 0

    def stuck_between(self, t0, t1):
        self.stuck += max(t1 - max(t0, self.start), 0.0)


def _leaving(function, region, t0, state):
    """An event function of (t, z) for a run from (t0, state) in `region`, unchanged when it
    starts with the region's sign.

    Otherwise it starts from 0: the switch function on the switch, the rate of the switch
    state at a turning point or where friction stops sticking. A quick return (friction that
    slides for a moment and sticks) would then be a double root within one step, which a sign
    test at the steps' ends misses, and rounding would find the start again. Divided by t - t0
    the function has the sign it takes just after t0 from the start, given as the region's at
    t0, and the return is a simple root."""
    if region * function(t0, state) > 0:
        return function
    return lambda t, z: function(t, z) / (t - t0) if t > t0 else region


def _solve(osc, force, state, region, t0, t1, rtol, t_eval=None):
    """DOP853 from t0 to t1 in one region, stopped where the switch function leaves its sign
    (event 0) or where it turns back towards the switch (event 1). The solution carries its
    switch function as `distance`."""
    def rates(t, z):
        return osc.rates(z[0], z[1], force(t), region)

    events = None
    if osc.switch_state is not None:
        events = [_leaving(lambda t, z: osc.switch(z), region, t0, state),
                  _leaving(lambda t, z: rates(t, z)[osc.switch_state], region, t0, state)]
        for event, direction in zip(events, (-region, region)):
            event.terminal, event.direction = True, direction
    solution = solve_ivp(rates, (t0, t1), state, method="DOP853", t_eval=t_eval, events=events,
                         dense_output=events is not None, rtol=rtol, atol=rtol / 100)
    if not solution.success:
        raise RuntimeError(solution.message)
    solution.distance = events and events[0]
    return solution


def _stop(osc, force, solution, region, tally):
    """The time, state and region from which the integration goes on after `solution` stopped
    at an event: a switch, or a turning point (the same region, unless the switch function
    changed its sign twice within the last step, both times unseen, and the first is found)."""
    crossed = solution.t_events[0].size > 0
    t, state = (solution.t_events[not crossed][0], solution.y_events[not crossed][0].copy())
    if not crossed:
        if region * solution.distance(t, state) > 0:
            return t, state, region
        # The switch function keeps its direction from the last step's start to the turning
        # point, so it has one root there.
        t = brentq(lambda u: solution.distance(u, solution.sol(u)), solution.sol.ts[-2], t,
                   xtol=1e-15)
        state = solution.sol(t)
    # Exactly on the switch, which the next region's integration starts by leaving.
    state[osc.switch_state] = osc.level
    region = osc.side(state[0], state[1], force(t))
    tally.switch(t, region)
    return t, state, region


def _held_interval(osc, state, region, x, t0, dt, rtol, tally):
    """The state and region at t0 + dt, the force held at x from t0."""
    def force(_):
        return x

    t, end = t0, t0 + dt
    for _ in range(100):
        if region == 0:
            region = osc.side(state[0], 0.0, x)
            if region == 0:
                tally.stuck_between(t, end)
                return state, 0
        solution = _solve(osc, force, state, region, t, end, rtol)
        if solution.status == 0:
            return solution.y[:, -1], region
        t, state, region = _stop(osc, force, solution, region, tally)
    raise RuntimeError(f"more than 100 switches in the interval from t = {t0}")


def _held(osc, force, fs, rtol, tally):
    """The states at the samples, the force held over each sample interval."""
    path = np.empty((force.samples.size, 2))
    state, region = np.zeros(2), osc.region(np.zeros(2), force.samples[0])
    for n, x in enumerate(force.samples):
        path[n] = state
        state, region = _held_interval(osc, state, region, x, n / fs, 1 / fs, rtol, tally)
    return path


def _slip_time(osc, force, y, t, end):
    """The first time after t at which the force x - k y on the stuck mass exceeds f, or end."""
    limit, held = osc.params["f"], osc.k * y
    first, last = int(t / force.step) + 1, int(end / force.step) + 1
    # Stretches of the grid, short because sticks are: most end within a few ms.
    for start in range(first, last, 256):
        stretch = force.grid[start:min(start + 256, last + 1), 0]
        over = np.nonzero(np.abs(stretch - held) > limit)[0]
        if over.size:
            right = (start + over[0]) * force.step
            left = max(t, right - force.step)
            return brentq(lambda u: abs(force(u) - held) - limit, left, right, xtol=1e-15)
    return end


def _continuous(osc, force, fs, rtol, tally):
    """The states at the samples, the force the band-limited signal."""
    times = np.arange(force.samples.size) / fs
    path = np.empty((times.size, 2))
    state, region = np.zeros(2), osc.region(np.zeros(2), force(0.0))
    t, done, stops = 0.0, 0, 0
    while done < times.size:
        if stops > 100:
            raise RuntimeError(f"more than 100 events in the interval from t = {times[done]}")
        if region == 0:
            slip = _slip_time(osc, force, state[0], t, times[-1])
            reached = np.searchsorted(times, slip, side="right")
            path[done:reached] = state
            tally.stuck_between(t, slip)
            t, done = slip, reached
            region = _sign(force(t) - osc.k * state[0])
            continue
        solution = _solve(osc, force, state, region, t, times[-1], rtol, times[done:])
        # solve_ivp gives lists, not arrays, when it stopped before the next sample.
        reached = len(solution.t)
        if reached:
            path[done:done + reached] = solution.y.T
        if solution.status == 0:
            break
        t, state, region = _stop(osc, force, solution, region, tally)
        # A switch found behind a turning point leaves the samples after it to the next run.
        reached = min(reached, np.searchsorted(times[done:], t, side="right"))
        done += reached
        stops = 0 if reached else stops + 1
    return path


def record(case, rng, samples, hold="continuous", params=None, fs=FS, rms=RMS, band=BAND,
           burn_in=BURN_IN, rtol=RTOL):
    """A record of `samples` samples of a case's oscillator (see oscillator()) after `burn_in`
    seconds from rest, driven by a shaker force of RMS `rms` on `band` Hz, `hold` "continuous"
    or "held" (see the module's text), integrated with relative tolerance `rtol`.

    Returns a dict of arrays t (from 0), y, v and x, `stuck` (the samples where the mass sticks)
    and the counts of the record: `switches` located, `sticks` and `stick_fraction` (of the
    record's time)."""
    osc = oscillator(case, params)
    burn = int(round(burn_in * fs))
    force = ShakerForce(rng, burn + samples, fs, band, rms)
    tally = Tally(burn / fs)
    integrate = {"held": _held, "continuous": _continuous}[hold]
    path = integrate(osc, force, fs, rtol, tally)[burn:]
    return {"t": np.arange(samples) / fs, "y": path[:, 0], "v": path[:, 1],
            "x": force.samples[burn:], "stuck": path[:, 1] == 0.0, "switches": tally.switches,
            "sticks": tally.sticks, "stick_fraction": tally.stuck * fs / samples}


def write(path, record, channels=("y", "v", "x"), noise=0.0, rng=None):
    """Writes the record's `channels` as a lab does: a CSV file with `t` first and no metadata
    (lab_records.write_csv), each channel with white noise of `noise` times its standard
    deviation drawn from `rng` (lab_records.measured). momentid then reads the force as samples
    of a continuous signal; the force of a held record is held over each sample interval, which
    `momentid simulate --input-file PATH --interpolation zoh` replays from the first sample's
    y and v."""
    columns = {"t": record["t"]}
    for name in channels:
        columns[name] = measured(rng, record[name], noise) if noise else record[name]
    write_csv(path, columns)


# The multipliers m of the zero-lag moment equations E[m (v' + c v + k y + N - x)] = 0, each with
# I and M such that m v' = dM/dt - I. A stationary record has E[dM/dt] = 0, so the stationarity
# identity replaces E[m v'] by -E[I] (E[y v'] = -E[v^2], E[y^2 v v'] = -E[y v^3], ...); over a
# stretch of time T the exact mean is (M(T) - M(0))/T - E[I].
MULTIPLIERS = {
    "y": lambda y, v: (y, v * v, y * v),
    "v": lambda y, v: (v, np.zeros_like(v), v * v / 2),
    "y^3": lambda y, v: (y**3, 3 * y * y * v * v, y**3 * v),
    "y^2 v": lambda y, v: (y * y * v, y * v**3, y * y * v * v / 2),
    "y v^2": lambda y, v: (y * v * v, v**4 / 3, y * v**3 / 3),
    "v^3": lambda y, v: (v**3, np.zeros_like(v), v**4 / 4),
}


def _batch_means(series, batches, size):
    """Trapezoid means of `series` (last axis: samples) over [b size, (b + 1) size] / fs."""
    whole = series[..., :batches * size].reshape(*series.shape[:-1], batches, size).sum(axis=-1)
    ends = series[..., size:batches * size + 1:size] - series[..., :batches * size:size]
    return (whole + ends / 2) / size


def _batch_equations(record, osc, multipliers, batches, ends, slip_only):
    """The equations' terms in c, k and N's parameter (B x M x 3) and their right-hand sides
    E[m x] + E[I] (B x M), means over each of B equal batches of the record, with the batch's
    end terms -(M(T) - M(0))/T when `ends`; each equation scaled to a unit row."""
    y, v, x = record["y"], record["v"], record["x"]
    size = (y.size - 1) // batches
    span = size / FS if "t" not in record else record["t"][size] - record["t"][0]
    # Stuck samples obey k y + N - x = 0 for any k when N is the true x - k y, so leaving them
    # out of the terms (their I vanish with v) gives the equations with the true N.
    keep = ~record["stuck"] if slip_only else np.ones(y.size, bool)
    regressors = np.stack([v, y, osc.basis(y, v)]) * keep
    terms, sides = [], []
    for name in multipliers:
        m, identity, antiderivative = MULTIPLIERS[name](y, v)
        row = _batch_means(m * regressors, batches, size)
        side = _batch_means(m * x * keep + identity, batches, size)
        if ends:
            side -= np.diff(antiderivative[:batches * size + 1:size]) / span
        scale = np.linalg.norm(row.mean(axis=1))
        terms.append(row.T / scale)
        sides.append(side / scale)
    return np.stack(terms, axis=1), np.stack(sides, axis=1)


def moment_estimates(record, case, params=None, multipliers=tuple(MULTIPLIERS), batches=25,
                     ends=False, slip_only=False):
    """c, k and the non-smooth force's parameter by least squares on the zero-lag moment
    equations of `multipliers` (names in MULTIPLIERS), from a noise-free record with t, y, v
    and x, N taken from the case (`params` gives a contact's gap g).

    Without `ends` the equations are those an estimator uses, with the stationarity identities;
    their error is then the record's end terms, of order 1/T, which the nearly parallel terms
    c v and c2 |v| v (or f sign(v)) can magnify: an inconsistency in k between the equations of
    y and y^3 and the others moves c and c2 along it (tens of percent on some drag records of
    10^5 samples, while the four multipliers with a factor v stay within 0.5%). With `ends` each
    batch's equations carry its own end terms and hold to the accuracy of the record and of the
    trapezoid rule, except that sign(v) jumps between samples: in the equations of y and y^3,
    whose multipliers do not vanish with v, each reversal adds an error of order f |y| / fs
    (0.8% of c and f at 10^5 samples of the default friction). With `slip_only` the friction
    equations leave the stuck samples out, which gives them the true force while stuck.

    The standard errors come from the spread of the equations' residuals over `batches` equal
    batches (batch means), through the least-squares solution. Without `ends` each batch's
    residuals hold its own end terms, so they overstate the error of the whole record's
    estimate, by up to sqrt(batches). Returns {name: (estimate, std_error)}."""
    osc = oscillator(case, params)
    terms, sides = _batch_equations(record, osc, multipliers, batches, ends, slip_only)
    a, b = terms.mean(axis=0), sides.mean(axis=0)
    solution = np.linalg.lstsq(a, b, rcond=None)[0]
    gain = np.linalg.pinv(a)
    residuals = terms @ solution - sides
    covariance = gain @ np.cov(residuals, rowvar=False) @ gain.T / batches
    names = ("c", "k", osc.term)
    return {name: (solution[i], np.sqrt(covariance[i, i])) for i, name in enumerate(names)}
