"""Plots of the results of validate() and identify(), drawn with matplotlib.

    import momentid.plots
    fig = momentid.plots.plot_validation(momentid.validate(model, record, result))
    fig.savefig("validate.png")

Each function draws from the result's own arrays (nothing is recomputed) and returns the
matplotlib Figure without showing it: a script saves it, a notebook displays it, plt.show()
shows it. matplotlib is imported when a plot is asked for, so the rest of the module works
without it.
"""

from __future__ import annotations

from typing import Optional

import numpy as _np

from ._results import IdentifyResult, ValidateResult, _t_quantile

# How each kind of statistic is drawn: its horizontal axis, its vertical axis and whether the
# values span decades (a spectrum does; its peak would flatten everything else on a linear
# axis).
_KINDS = {
    "psd": ("frequency [Hz]", "power spectral density", True),
    "distribution": ("probability", "quantile", False),
    "crossings": ("level", "up-crossing rate", False),
    "prediction": ("time ahead [s]", "prediction error", False),
    "bias": ("state predicted (index)", "slope of the prediction error", False),
}


def _figure(fig, rows: int, columns: int, size: tuple):
    """The figure (a new one unless given) and a grid of rows x columns to place panels on."""
    try:
        import matplotlib.pyplot as pyplot
    except ImportError as error:
        raise ImportError("momentid.plots needs matplotlib (Debian's python3-matplotlib, or "
                          "pip install matplotlib); the results need only numpy") from error
    if fig is None:
        fig = pyplot.figure(figsize=size, layout="constrained")
    return fig, fig.add_gridspec(rows, columns)


def _runs_apart(values: _np.ndarray, run: Optional[_np.ndarray]) -> _np.ndarray:
    # A NaN between runs keeps the line from joining the end of one run to the next's start.
    if run is None or len(run) == 0:
        return values
    starts = _np.flatnonzero(_np.diff(run) != 0) + 1
    return _np.insert(values.astype(float), starts, _np.nan)


def plot_validation(result: ValidateResult, fig=None, statistics: Optional[bool] = None):
    """Draws what validate() compared: one panel per output with the measured and the
    simulated series over the compared rows (runs apart), then one panel per statistic (a row
    per output, a column per kind) with the record's values against the runs' band (smallest
    to largest) and mean, titled inside or outside.

    statistics: None draws them when validate compared them (a sensitive model, or a
    trajectory fit that failed); True requires them (ValueError without);
    False leaves them out. fig: a matplotlib Figure to draw into (empty); by default a new
    one. Returns the Figure.
    """
    compared = result.statistics or {}
    checks = compared.get("checks", []) if statistics is not False else []
    if statistics and not checks:
        reason = compared.get("not_compared") or (
            "validate compares them for a sensitive model, or when the trajectory fit fails")
        raise ValueError(f"plot_validation: the result has no statistics ({reason})")
    outputs = list(result.measured)
    kinds = [kind for kind in _KINDS if any(c["kind"] == kind for c in checks)]
    checked = [o for o in outputs if any(c["output"] == o for c in checks)]
    columns = max(1, len(kinds))
    rows = len(outputs) + len(checked)
    fig, grid = _figure(fig, rows, columns, (4.2 * max(2, columns), 2.6 * rows))
    # A series spans the width; the statistics of an output share a row, a kind a column.
    for row, output in enumerate(outputs):
        _draw_series(fig.add_subplot(grid[row, :]), result, output)
    for row, output in enumerate(checked, start=len(outputs)):
        for column, kind in enumerate(kinds):
            check = next((c for c in checks if c["output"] == output and c["kind"] == kind),
                         None)
            if check is not None:
                _draw_statistic(fig.add_subplot(grid[row, column]), check)
    return fig


def _draw_series(ax, result: ValidateResult, output: str) -> None:
    compared = _np.asarray(result.compared, bool)
    run = None if result.run is None else _np.asarray(result.run)[compared]
    t = _runs_apart(_np.asarray(result.t)[compared], run)
    ax.plot(t, _runs_apart(_np.asarray(result.measured[output])[compared], run),
            color="k", lw=0.8, label="measured")
    ax.plot(t, _runs_apart(_np.asarray(result.simulated[output])[compared], run),
            color="C0", lw=0.8, label="simulated")
    ax.set(xlabel="t", ylabel=output, title=f"{output}: fit {result.fit[output]:.1f}%")
    ax.legend(fontsize=8, loc="upper right")


def _draw_statistic(ax, check: dict) -> None:
    xlabel, ylabel, logarithmic = _KINDS[check["kind"]]
    at = _np.asarray(check["at"], float)
    band = {"color": "C0", "alpha": 0.3, "label": "runs: smallest to largest"}
    if len(at) == 1:
        # A prediction error is one number at one time ahead: a bar and marks, not areas.
        ax.vlines(at, check["low"], check["high"], lw=8, **band)
        style = {"marker": "o", "ls": "none"}
    else:
        ax.fill_between(at, check["low"], check["high"], lw=0, **band)
        style = {"lw": 0.8}
    ax.plot(at, check["mean"], color="C0", label="runs: mean", **style)
    ax.plot(at, check["measured"], color="k", label="record", **style)
    if logarithmic:
        ax.set_yscale("log")
    where = ("inside" if check["inside"] else
             f"outside, {check['distance'] / check['limit']:.2g} times the limit")
    ax.set(xlabel=xlabel, ylabel=f"{ylabel} of {check['output']}",
           title=f"{check['output']} {check['kind']}: {where}")
    ax.title.set_color("k" if check["inside"] else "C3")
    ax.legend(fontsize=7)


def plot_engineering(result: IdentifyResult, fig=None):
    """Draws the engineering curves of identify(): the restoring force against displacement
    and the backbone (the frequency of free oscillation against amplitude), each with its
    95% band (Student's t at df_resid times the standard errors, as the parameters'
    intervals), one panel for each the result has.

    Raises ValueError when it has neither (a model that is not a single-degree oscillator with
    a constant mass; engineering["unavailable"] says why when there is no linearisation
    either). fig: a matplotlib Figure to draw into (empty); by default a new one. Returns it.
    """
    curves = [key for key in ("restoring_force", "backbone") if key in result.engineering]
    if not curves:
        reason = result.engineering.get("unavailable") or (
            "the model is not an oscillator y' = v, m*v' = ... with a constant mass")
        raise ValueError(f"plot_engineering: the result has no restoring-force curve and no "
                         f"backbone ({reason})")
    fig, grid = _figure(fig, 1, len(curves), (4.8 * len(curves), 3.6))
    t975 = _t_quantile(0.975, result.df_resid)
    for column, key in enumerate(curves):
        ax = fig.add_subplot(grid[0, column])
        curve = result.engineering[key]
        if key == "restoring_force":
            x, y = curve["displacement"], curve["force"]
            labels = {"xlabel": f"displacement {curve['state']}", "ylabel": "restoring force",
                      "title": "restoring force"}
        else:
            x, y = curve["amplitude"], curve["frequency_hz"]
            labels = {"xlabel": "amplitude", "ylabel": "frequency [Hz]",
                      "title": "backbone (harmonic balance)"}
        x, y = _np.asarray(x, float), _np.asarray(y, float)
        band = t975 * _np.asarray(curve["std_error"], float)
        ax.fill_between(x, y - band, y + band, color="C0", alpha=0.3, lw=0, label="95% band")
        ax.plot(x, y, color="C0", label="identified")
        ax.set(**labels)
        ax.legend(fontsize=8)
    return fig
