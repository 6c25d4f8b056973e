"""momentid.plots: the figures hold the result's own arrays, one panel per series, statistic
and curve, and a result without what is asked for says so."""

import sys

import numpy as np
import pytest

import momentid
from conftest import INPUT

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from momentid.plots import plot_engineering, plot_validation  # noqa: E402

# A lightly damped hardening oscillator under strong forcing (examples/python/engineering.py),
# validated with a stiffness 1% off: the trajectory fit fails, so validate compares the
# response's statistics too, and some are outside their bands.
HARDENING = momentid.Model("""
    model hardening
    state y, v
    input x
    param c, k, eps
    y' = v
    v' = -c*v - k*y - eps*y^3 + x
""")
HARDENING_TRUE = {"c": 0.2, "k": 4.0, "eps": 2.0}
HARDENING_OFF = {"c": 0.2, "k": 4.04, "eps": 2.0}


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def duffing_check(duffing, record):
    return momentid.validate(duffing, record)


@pytest.fixture(scope="module")
def hardening_check():
    record = momentid.simulate(HARDENING, HARDENING_TRUE, samples=20_000, seed=22,
                               inputs={"x": INPUT})
    return momentid.validate(HARDENING, record, HARDENING_OFF)


@pytest.fixture(scope="module")
def identified(duffing, record):
    return momentid.identify(duffing, record)


def lines(ax):
    return {line.get_label(): line for line in ax.get_lines()}


def band(ax):
    """The lower and upper edges of the one band of a panel, by x."""
    (polygon,) = ax.collections
    if isinstance(polygon, matplotlib.collections.LineCollection):  # one value: a bar
        return tuple(np.array([segment[:, 1] for segment in polygon.get_segments()]).T)
    vertices = polygon.get_paths()[0].vertices
    # fill_between's outline runs along the lower edge, then back along the upper one.
    count = (len(vertices) - 3) // 2
    return vertices[1:count + 1, 1], vertices[count + 2:2 * count + 2, 1][::-1]


def test_validation_draws_the_measured_and_simulated_series_over_the_compared_rows(
        duffing_check):
    assert duffing_check.statistics is None  # the true model's trajectory is reproduced
    fig = plot_validation(duffing_check)
    assert isinstance(fig, matplotlib.figure.Figure)
    assert list(duffing_check.measured) == ["y", "v"]
    assert len(fig.axes) == 2
    compared = duffing_check.compared
    assert 0 < compared.sum() < len(compared)
    for ax, output in zip(fig.axes, duffing_check.measured):
        drawn = lines(ax)
        np.testing.assert_array_equal(drawn["measured"].get_xdata(), duffing_check.t[compared])
        np.testing.assert_array_equal(drawn["measured"].get_ydata(),
                                      duffing_check.measured[output][compared])
        np.testing.assert_array_equal(drawn["simulated"].get_ydata(),
                                      duffing_check.simulated[output][compared])
        assert ax.get_title() == f"{output}: fit {duffing_check.fit[output]:.1f}%"


def test_validation_draws_each_statistic_against_the_band_of_the_runs(hardening_check):
    checks = hardening_check.statistics["checks"]
    assert {c["kind"] for c in checks} == {"psd", "distribution", "crossings", "prediction",
                                           "bias"}
    assert {c["inside"] for c in checks} == {True, False}
    fig = hardening_check.plot()
    outputs = len(hardening_check.measured)
    assert len(fig.axes) == outputs + len(checks)
    # A row per output, a column per kind: the panels are found by their titles.
    panels = {tuple(ax.get_title().split(":")[0].split()): ax for ax in fig.axes[outputs:]}
    for check in checks:
        ax = panels[check["output"], check["kind"]]
        where = ("inside" if check["inside"] else
                 f"outside, {check['distance'] / check['limit']:.2g} times the limit")
        assert ax.get_title() == f"{check['output']} {check['kind']}: {where}"
        drawn = lines(ax)
        np.testing.assert_array_equal(drawn["record"].get_xdata(), check["at"])
        np.testing.assert_array_equal(drawn["record"].get_ydata(), check["measured"])
        np.testing.assert_array_equal(drawn["runs: mean"].get_ydata(), check["mean"])
        low, high = band(ax)
        np.testing.assert_array_equal(low, check["low"])
        np.testing.assert_array_equal(high, check["high"])
    assert len(plot_validation(hardening_check, statistics=False).axes) == outputs


def test_validation_without_statistics_says_why_when_they_are_asked_for(duffing_check):
    with pytest.raises(ValueError, match=r"^plot_validation: the result has no statistics "
                                         r"\(validate compares them for a sensitive model, or "
                                         r"when the trajectory fit fails\)$"):
        plot_validation(duffing_check, statistics=True)


def test_validation_breaks_its_lines_between_runs():
    from momentid.plots import _runs_apart
    got = _runs_apart(np.array([0.0, 1.0, 0.0, 1.0, 2.0]), np.array([1, 1, 2, 2, 2]))
    np.testing.assert_array_equal(got, [0.0, 1.0, np.nan, 0.0, 1.0, 2.0])


def test_engineering_draws_the_restoring_force_and_the_backbone_with_their_bands(identified):
    fig = identified.plot_engineering()
    assert isinstance(fig, matplotlib.figure.Figure)
    assert len(fig.axes) == 2
    # The parameters' 95% intervals are Student's t at df_resid times their errors; so is the band.
    t975 = (identified.conf_int()[0, 1] - identified.params[0]) / identified.bse[0]
    for ax, key, x, y in zip(fig.axes, ("restoring_force", "backbone"),
                             ("displacement", "amplitude"), ("force", "frequency_hz")):
        curve = identified.engineering[key]
        drawn = lines(ax)["identified"]
        np.testing.assert_array_equal(drawn.get_xdata(), curve[x])
        np.testing.assert_array_equal(drawn.get_ydata(), curve[y])
        low, high = band(ax)
        half = t975 * np.asarray(curve["std_error"])
        np.testing.assert_allclose(low, np.asarray(curve[y]) - half, rtol=1e-12)
        np.testing.assert_allclose(high, np.asarray(curve[y]) + half, rtol=1e-12)


def test_engineering_without_curves_says_why(identified):
    value = identified.to_dict()
    del value["engineering"]["restoring_force"], value["engineering"]["backbone"]
    value["engineering"]["unavailable"] = "no equilibrium near the origin"
    with pytest.raises(ValueError, match=r"^plot_engineering: the result has no restoring-force "
                                         r"curve and no backbone \(no equilibrium near the "
                                         r"origin\)$"):
        plot_engineering(momentid.IdentifyResult("", value))


def test_a_figure_to_draw_into_is_used(identified):
    fig = plt.figure()
    assert plot_engineering(identified, fig=fig) is fig
    assert len(fig.axes) == 2


def test_without_matplotlib_the_error_names_the_package(identified, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match=r"^momentid.plots needs matplotlib \(Debian's "
                                          r"python3-matplotlib, or pip install matplotlib\)"):
        plot_engineering(identified)
