"""Tests of the results as values to compute with, against the `momentid` program.

What they cover:
- IdentifyResult's params, bse, cov_params(), objective, conf_int(), tvalues, pvalues,
  summary(), to_frame(), nobs, df_resid and J test equal the JSON (and text) of `momentid
  identify` on the same file, for the least-squares and the optimally weighted estimate and its
  `.ls` beside it;
- the keywords renamed in this release (rename=, columns= as a list, extrapolate="dt") still
  work and warn; monomial lists are lists or strings alike;
- validate's series: their lengths, the rows compared, and the fit and errors recomputed from
  them equal those of `momentid validate`;
- check's values equal the JSON (and text) of `momentid check` on the same file, with and
  without a model.
"""

import json
import math

import numpy as np
import pytest

import momentid

from conftest import DUFFING, INPUT, ROOT, TRUE, read_csv, sines

# The arrays are the JSON's numbers, or computed from them by a few operations.
REL = 1e-12


def entry(value, error):
    """A parameter's entry in the JSON."""
    return {"estimate": value, "std_error": error, "ci95": None, "identifiable": True,
            "fixed": False}


def parameters_of(section):
    """(names, estimates, errors, intervals) of a JSON parameters section."""
    names = list(section)
    values = np.array([section[n]["estimate"] for n in names])
    errors = np.array([section[n]["std_error"] for n in names])
    intervals = np.array([section[n]["ci95"] for n in names])
    return names, values, errors, intervals


def covariance_of(section, correlation):
    """The covariance from the errors and the correlation of the program's JSON."""
    _, _, errors, _ = parameters_of(section)
    return np.array(correlation, dtype=float) * np.outer(errors, errors)


def matrix(rows):
    """A matrix of the JSON, null as NaN."""
    return np.array([[np.nan if x is None else x for x in row] for row in rows], dtype=float)


@pytest.fixture(scope="session")
def gmm_json(cli, cli_csv):
    return json.loads(cli("identify", DUFFING, cli_csv, "--weighting", "gmm", "--format", "json"))


@pytest.fixture(scope="session")
def gmm_result(duffing, cli_csv):
    return momentid.identify(duffing, cli_csv, weighting="gmm")


@pytest.fixture(scope="session")
def ls_result(duffing, cli_csv):
    return momentid.identify(duffing, cli_csv, weighting="ls")


# --- 1. the main estimate against the program's JSON ---------------------------------------------

@pytest.mark.parametrize("weighting", ["ls", "gmm"])
def test_params_bse_cov_and_intervals_equal_cli_json(request, weighting, ls_json, gmm_json):
    result = request.getfixturevalue(f"{weighting}_result")
    expected = ls_json if weighting == "ls" else gmm_json
    names, values, errors, intervals = parameters_of(expected["parameters"])
    assert result.weighting == weighting
    assert result.param_names == names == ["c", "k", "eps"]
    np.testing.assert_allclose(result.params, values, rtol=REL, atol=0)
    np.testing.assert_allclose(result.bse, errors, rtol=REL, atol=0)
    # The program's covariance, to the last bit, and what its errors and correlation make.
    diagnostics = expected["diagnostics"]
    np.testing.assert_array_equal(result.cov_params(), matrix(diagnostics["covariance"]))
    covariance = covariance_of(expected["parameters"], diagnostics["correlation"])
    np.testing.assert_allclose(result.cov_params(), covariance, rtol=REL, atol=0)
    # Symmetric to rounding: the program forms entry (i, j) as (r_ij s_i) s_j and (j, i) as
    # (r_ji s_j) s_i, which may differ in the last bit (Fit::covariance).
    np.testing.assert_allclose(result.cov_params(), result.cov_params().T,
                               rtol=2 * np.finfo(float).eps, atol=0)
    assert result.objective == diagnostics["objective"] > 0
    # At alpha = 0.05, Student's t at the result's degrees of freedom: the program's interval.
    np.testing.assert_allclose(result.conf_int(), intervals, rtol=REL, atol=0)
    assert result.df_resid == expected["diagnostics"]["error_dof"]
    assert result.nobs == expected["diagnostics"]["samples"] == 100000


def test_arrays_are_read_only(ls_result):
    with pytest.raises(ValueError):
        ls_result.params[0] = 1.0
    with pytest.raises(ValueError):
        ls_result.bse[0] = 1.0


def test_summary_is_the_cli_report(cli, cli_csv, gmm_result):
    assert gmm_result.summary() == cli("identify", DUFFING, cli_csv, "--weighting", "gmm")
    assert str(gmm_result) == gmm_result.summary()


def test_least_squares_beside_the_optimally_weighted_estimate(gmm_result, gmm_json):
    names, values, errors, intervals = parameters_of(gmm_json["least_squares"])
    ls = gmm_result.ls
    assert isinstance(ls, momentid.Fit) and ls.param_names == names
    np.testing.assert_allclose(ls.params, values, rtol=REL, atol=0)
    np.testing.assert_allclose(ls.bse, errors, rtol=REL, atol=0)
    # The degrees of freedom the binding hands over are those of the program's intervals.
    np.testing.assert_allclose(ls.conf_int(), intervals, rtol=REL, atol=0)
    assert ls.df_resid != gmm_result.df_resid
    # Its objective and covariance: the program's, the squared errors on the diagonal, a
    # correlation within [-1, 1].
    errors_json = gmm_json["diagnostics"]["least_squares"]
    assert ls.objective == errors_json["objective"] > 0
    assert ls.objective != gmm_result.objective
    assert ls.df_resid == errors_json["error_dof"]
    covariance = ls.cov_params()
    np.testing.assert_array_equal(covariance, matrix(errors_json["covariance"]))
    np.testing.assert_allclose(covariance, covariance_of(gmm_json["least_squares"],
                                                         errors_json["correlation"]), rtol=REL)
    np.testing.assert_allclose(np.diag(covariance), errors ** 2, rtol=REL, atol=0)
    correlation = covariance / np.outer(errors, errors)
    assert np.all(np.abs(correlation) <= 1 + 1e-12)
    assert np.all(np.linalg.eigvalsh(covariance) > 0)


def test_least_squares_result_is_its_own_ls(ls_result):
    np.testing.assert_array_equal(ls_result.ls.params, ls_result.params)
    np.testing.assert_array_equal(ls_result.ls.cov_params(), ls_result.cov_params())
    assert ls_result.ls.objective == ls_result.objective
    assert ls_result.jval is None and ls_result.jtest() is None


def test_j_test_equals_cli_json(gmm_result, gmm_json):
    diagnostics = gmm_json["diagnostics"]
    assert gmm_result.jval == diagnostics["j_statistic"]
    assert gmm_result.jtest() == (diagnostics["j_statistic"], diagnostics["j_pvalue"],
                                  diagnostics["j_dof"])


# --- 2. other levels, t values and p-values -----------------------------------------------------

def test_conf_int_at_other_levels_is_student_t(gmm_result):
    stats = pytest.importorskip("scipy.stats")
    for alpha in (0.01, 0.1, 0.5):
        t = stats.t.ppf(1 - alpha / 2, gmm_result.df_resid)
        expected = np.column_stack([gmm_result.params - t * gmm_result.bse,
                                    gmm_result.params + t * gmm_result.bse])
        np.testing.assert_allclose(gmm_result.conf_int(alpha), expected, rtol=1e-10)
    narrow, wide = gmm_result.conf_int(0.5), gmm_result.conf_int(0.01)
    assert np.all(wide[:, 0] < narrow[:, 0]) and np.all(narrow[:, 1] < wide[:, 1])
    with pytest.raises(momentid.UsageError, match="^alpha: expected a number between 0 and 1"):
        gmm_result.conf_int(1.5)


def test_tvalues_and_pvalues(ls_result):
    stats = pytest.importorskip("scipy.stats")
    t = ls_result.params / ls_result.bse
    np.testing.assert_allclose(ls_result.tvalues, t, rtol=REL)
    # Hundreds of errors from 0: p-values that underflow. A fit of few degrees of freedom with
    # estimates near 0 shows the t law's tails.
    assert np.all(ls_result.pvalues < 1e-100)
    for dof in (12.5, 0.4):
        fit = momentid.Fit({"parameters": {"a": entry(1.0, 0.8), "b": entry(-0.1, 0.05)},
                            "error_dof": dof,
                            "covariance": [[0.64, 0.3 * 0.8 * 0.05], [0.3 * 0.8 * 0.05, 0.0025]]})
        law = stats.t(max(1.0, dof))  # at least one degree of freedom, as the program's
        np.testing.assert_allclose(fit.pvalues, 2 * law.sf([1.25, 2.0]), rtol=1e-10)
        np.testing.assert_allclose(fit.conf_int(0.1)[:, 1] - fit.params,
                                   law.ppf(0.95) * fit.bse, rtol=1e-10)
        assert fit.cov_params()[0, 1] == pytest.approx(0.3 * 0.8 * 0.05, rel=REL)


def test_fixed_parameter(duffing, cli, cli_csv):
    result = momentid.identify(duffing, cli_csv, fix={"c": 0.5})
    expected = json.loads(cli("identify", DUFFING, cli_csv, "--fix", "c=0.5", "--format", "json"))
    np.testing.assert_allclose(result.params, parameters_of(expected["parameters"])[1], rtol=REL)
    assert result.fixed == ["c"] and result.bse[0] == 0
    covariance = result.cov_params()
    assert np.all(covariance[0, :] == 0) and np.all(covariance[:, 0] == 0)
    np.testing.assert_allclose(covariance[1:, 1:], covariance_of(
        expected["parameters"], expected["diagnostics"]["correlation"])[1:, 1:], rtol=REL)
    assert np.isnan(result.tvalues[0]) and np.isnan(result.pvalues[0])
    np.testing.assert_array_equal(result.conf_int()[0], [0.5, 0.5])


# --- 3. the table --------------------------------------------------------------------------------

def test_to_frame(gmm_result, gmm_json):
    pytest.importorskip("pandas")
    frame = gmm_result.to_frame()
    names, values, errors, intervals = parameters_of(gmm_json["parameters"])
    assert list(frame.index) == names and frame.index.name == "parameter"
    assert list(frame.columns) == ["estimate", "std_error", "t", "p_value", "ci_low", "ci_high",
                                   "identifiable", "fixed"]
    np.testing.assert_allclose(frame["estimate"], values, rtol=REL, atol=0)
    np.testing.assert_allclose(frame["std_error"], errors, rtol=REL, atol=0)
    np.testing.assert_allclose(frame[["ci_low", "ci_high"]], intervals, rtol=REL, atol=0)
    assert frame["identifiable"].all() and not frame["fixed"].any()
    np.testing.assert_array_equal(gmm_result.to_frame(alpha=0.01)[["ci_low", "ci_high"]],
                                  gmm_result.conf_int(0.01))
    assert list(gmm_result.ls.to_frame()["estimate"]) == list(gmm_result.ls.params)


def test_old_attributes_still_work(ls_result, ls_json):
    names, values, errors, intervals = parameters_of(ls_json["parameters"])
    assert ls_result.estimates == dict(zip(names, values))
    assert ls_result.std_errors == dict(zip(names, errors))
    assert ls_result.ci95 == {n: tuple(i) for n, i in zip(names, intervals)}
    assert ls_result.to_dict() == ls_json
    assert ls_result.status == ls_json["diagnostics"]["status"]


# --- 4. keywords: one name and direction, the old ones for one release --------------------------

def test_columns_map_model_variables_to_data_columns(duffing, record):
    renamed = {"disp": record["y"], "vel": record["v"], "x": record["x"], "t": record["t"]}
    # The renamed arrays lose the record's metadata, which chose the zero-lag equations.
    expected = momentid.identify(duffing, record, input_hold="zoh")
    result = momentid.identify(duffing, renamed, columns={"y": "disp", "v": "vel"},
                               input_hold="zoh", method="zero-lag")
    np.testing.assert_array_equal(result.params, expected.params)
    with pytest.warns(DeprecationWarning, match=r"identify\(\): rename= is deprecated.*columns="):
        old = momentid.identify(duffing, renamed, rename={"y": "disp", "v": "vel"},
                                input_hold="zoh", method="zero-lag")
    np.testing.assert_array_equal(old.params, expected.params)
    with pytest.warns(DeprecationWarning, match=r"check\(\): rename="):
        momentid.check(renamed, rename={"y": "disp", "v": "vel"})
    with pytest.warns(DeprecationWarning, match=r"validate\(\): rename="):
        momentid.validate(duffing, renamed, TRUE, rename={"y": "disp", "v": "vel"})
    with pytest.warns(DeprecationWarning), pytest.raises(momentid.UsageError,
                                                         match="^rename and columns"):
        momentid.identify(duffing, renamed, rename={"y": "disp"}, columns={"v": "vel"})


def test_a_variable_maps_to_a_sum_of_columns(duffing, record):
    # y and v each split into two columns, as two accelerometers on a shaker give the motion
    # relative to the table: the sums give back the record's channels exactly.
    half = record["y"] / 4
    split = {"t": record["t"], "x": record["x"], "y_mass": record["y"] + half, "y_table": half,
             "v 2": 2 * record["v"]}
    expected = momentid.identify(duffing, record, input_hold="zoh", method="zero-lag")
    result = momentid.identify(duffing, split, columns={"y": "y_mass - y_table",
                                                        "v": "0.5*'v 2'"},
                               input_hold="zoh", method="zero-lag")
    np.testing.assert_allclose(result.params, expected.params, rtol=1e-9)
    with pytest.raises(momentid.UsageError, match=r"^columns: y=y_mass - y_tab: <arrays> has no "
                                                  r"column 'y_tab'$"):
        momentid.identify(duffing, split, columns={"y": "y_mass - y_tab", "v": "0.5*'v 2'"})


def test_deprecation_points_at_the_caller(duffing, record):
    with pytest.warns(DeprecationWarning) as caught:
        momentid.check(record, rename={"y": "y"})
    assert caught[0].filename == __file__


def test_list_of_column_names_is_names(duffing, record):
    names = ["t", "y", "v", "x"]
    table = np.column_stack([record[n] for n in names])
    expected = momentid.identify(duffing, table, names=names, input_hold="zoh")
    with pytest.warns(DeprecationWarning, match=r"columns= with a list of column names.*names="):
        old = momentid.identify(duffing, table, columns=names, input_hold="zoh")
    np.testing.assert_array_equal(old.params, expected.params)


def test_extrapolate_is_a_flag(duffing, cli_csv):
    columns = read_csv(cli_csv)
    expected = momentid.identify(duffing, columns, input_hold="sample", degree=3,
                                 extrapolate=True)
    assert "sampling_bias" in expected.diagnostics
    with pytest.warns(DeprecationWarning, match=r'extrapolate="dt" is deprecated.*True'):
        old = momentid.identify(duffing, columns, input_hold="sample", degree=3,
                                extrapolate="dt")
    np.testing.assert_array_equal(old.params, expected.params)
    off = momentid.identify(duffing, columns, input_hold="sample", degree=3, extrapolate=False)
    assert "sampling_bias" not in off.diagnostics


def test_monomials_as_a_list_or_a_string(duffing, record, cli):
    as_text = momentid.identify(duffing, record, multipliers="y, v, y^3, y*v^2")
    as_list = momentid.identify(duffing, record, multipliers=["y", "v", "y^3", "y*v^2"])
    np.testing.assert_array_equal(as_list.params, as_text.params)
    assert duffing.derive(multipliers=["y", "y*v^2"]).text == \
        cli("derive", DUFFING, "--multipliers", "y,y*v^2")
    lagged = dict(lags=(3, 50), measured=["y", "x"])
    assert duffing.derive(instruments=["y", "y^3"], **lagged).text == \
        duffing.derive(instruments="y, y^3", **lagged).text


# --- 5. validate's series -----------------------------------------------------------------------

@pytest.fixture(scope="session")
def two_runs(cli, tmp_path_factory):
    """A record of two runs of 6000 samples, simulated by the program."""
    path = tmp_path_factory.mktemp("validate") / "runs.csv"
    cli("simulate", DUFFING, "--samples", 6000, "--runs", 2, "--seed", 7, "--input", INPUT,
        "-o", path)
    return path


def test_validate_series_match_the_cli_report(duffing, cli, two_runs):
    params = {"c": 0.55, "k": 3.9, "eps": 1.1}  # off, so that the errors are not only noise
    expected = json.loads(cli("validate", DUFFING, two_runs, "--set", "c=0.55,k=3.9,eps=1.1",
                              "--format", "json"))
    result = momentid.validate(duffing, two_runs, params)
    assert list(result.simulated) == ["y", "v"] and list(result.inputs) == ["x"]
    assert list(result.measured) == list(expected["outputs"]) == ["y", "v"]
    rows = 12000
    for series in (result.t, result.run, result.compared, *result.simulated.values(),
                   *result.measured.values(), *result.inputs.values()):
        assert series.shape == (rows,)
    np.testing.assert_array_equal(result.run, np.repeat([1.0, 2.0], 6000))
    skip = expected["skip"]
    within = np.concatenate([np.arange(6000)] * 2)
    np.testing.assert_array_equal(result.compared, within >= np.repeat(skip, 6000))
    for name, output in expected["outputs"].items():
        measured = result.measured[name][result.compared]
        error = measured - result.simulated[name][result.compared]
        assert len(error) == output["samples"]
        rms = math.sqrt(np.mean(error ** 2))
        fit = 100 * (1 - np.linalg.norm(error) / np.linalg.norm(measured - measured.mean()))
        assert rms == pytest.approx(output["rms"], rel=REL)
        assert fit == pytest.approx(output["fit_percent"], rel=REL)


def test_validate_series_are_the_record_and_the_replay(duffing, two_runs):
    result = momentid.validate(duffing, two_runs, TRUE)
    recorded = read_csv(two_runs)
    np.testing.assert_array_equal(result.t, recorded["t"])
    np.testing.assert_array_equal(result.measured["y"], recorded["y"])
    np.testing.assert_array_equal(result.inputs["x"], recorded["x"])
    replayed = momentid.simulate(duffing, TRUE, inputs=str(two_runs))
    np.testing.assert_array_equal(result.simulated["y"], replayed["y"])
    one_run = momentid.validate(duffing, {n: v[:6000] for n, v in recorded.items()
                                          if n != "run"}, TRUE)
    assert one_run.run is None and one_run.t.shape == (6000,)


def test_result_from_the_programs_json_alone(cli, cli_csv, gmm_json, gmm_result):
    """A saved `momentid identify --format json` is a result too, the same to the last bit; one
    saved by an older release, without the covariances and the least-squares errors, has NaN
    there rather than guessed numbers."""
    text = cli("identify", DUFFING, cli_csv, "--weighting", "gmm")
    for value in (cli("identify", DUFFING, cli_csv, "--weighting", "gmm", "--format", "json"),
                  gmm_json):
        saved = momentid.IdentifyResult(text, value)
        for fit, expected in ((saved, gmm_result), (saved.ls, gmm_result.ls)):
            np.testing.assert_array_equal(fit.conf_int(), expected.conf_int())
            np.testing.assert_array_equal(fit.cov_params(), expected.cov_params())
            assert fit.objective == expected.objective and fit.df_resid == expected.df_resid
        assert saved.to_dict() == gmm_result.to_dict()
    older = json.loads(json.dumps(gmm_json))
    for key in ("objective", "covariance", "least_squares"):
        del older["diagnostics"][key]
    saved = momentid.IdentifyResult(text, json.dumps(older))
    np.testing.assert_array_equal(saved.conf_int(), gmm_result.conf_int())
    np.testing.assert_array_equal(saved.ls.params, gmm_result.ls.params)
    assert np.isnan(saved.cov_params()).all() and np.isnan(saved.objective)
    assert np.isnan(saved.ls.conf_int()).all() and np.isnan(saved.ls.df_resid)


def test_json_text_is_the_programs_value(cli, cli_csv, gmm_json, gmm_result):
    """`.json` is the value as text: it reads back as the program's JSON, in the same order."""
    assert json.loads(gmm_result.json) == gmm_json
    assert list(json.loads(gmm_result.json)) == list(gmm_json)
    assert list(gmm_result.to_dict()["diagnostics"]) == list(gmm_json["diagnostics"])
    # to_dict() is a copy: changing it leaves the result as it was.
    gmm_result.to_dict()["parameters"].clear()
    assert gmm_result.to_dict()["parameters"] == gmm_json["parameters"]


def test_a_column_of_a_derivative_is_named_as_the_command_line_names_it():
    """A linear oscillator's force and acceleration alone: the force a smooth sum of 400 sines at
    random frequencies (a force held over each sample would put kinks into the acceleration),
    the acceleration its steady-state response, line by line through the oscillator's frequency
    response (exact: a start from rest differs by a transient that decays as exp(-1.5 t)), 2%
    noise on the acceleration."""
    model = momentid.Model("state y, v\ninput F\nparam c, k\ny' = v\nv' = -c*v - k*y + F\n",
                           name="oscillator")
    c, k, fs, seconds = 3.0, 900.0, 256.0, 380.0
    rng = np.random.default_rng(7)
    force = sines(rng, 400, (0.5, 20.0), 4.0)

    t = np.arange(int(seconds * fs)) / fs
    frequencies, amplitudes, phases = force.lines
    omega = 2 * np.pi * frequencies
    # The acceleration per unit of force, -omega^2 / (k - omega^2 + i c omega).
    gain = -omega**2 / (k - omega**2 + 1j * c * omega)
    accel = sum(np.imag(a * g * np.exp(1j * (w * t + p)))
                for w, a, p, g in zip(omega, amplitudes, phases, gain))
    data = {"time": t, "shaker": force(t),
            "acc": accel + 0.02 * np.std(accel) * rng.standard_normal(t.size)}
    result = momentid.identify(model, data, columns={"v'": "acc", "F": "shaker", "t": "time"})
    assert "acc" in result.text and "not measured: y'' = acc, v' = acc" in result.text
    for name, truth in (("c", c), ("k", k)):
        assert abs(result.estimates[name] - truth) < 3 * result.std_errors[name], result.text
    with pytest.raises(momentid.UsageError, match=r"^columns: x'=acc: x is not a state"):
        momentid.identify(model, data, columns={"x'": "acc", "F": "shaker", "t": "time"})


# --- 6. check against the program's JSON ---------------------------------------------------------

# (the record, with the model, check()'s keywords, the program's options)
CHECKS = {
    "model": ("simulated", True, {}, []),
    "no-model": ("simulated", False, {"lags": 4}, ["--lags", 4]),
    "runs": (ROOT / "tests" / "data" / "two_runs.csv", True, {"lags": 4}, ["--lags", 4]),
    "gaps": (ROOT / "tests" / "data" / "gaps.csv", False, {"lags": 2, "missing": "split-run"},
             ["--lags", 2, "--missing", "split-run"]),
}


@pytest.mark.parametrize("case", list(CHECKS))
def test_check_values_are_the_programs_json(case, cli, cli_csv, duffing):
    """check() gives the value `momentid check --format json` prints: every number the same
    double, every key in its place; and the same text report."""
    path, with_model, keywords, options = CHECKS[case]
    path = str(cli_csv if path == "simulated" else path)
    files = [path, DUFFING] if with_model else [path]
    expected = json.loads(cli("check", *files, *options, "--format", "json"))
    result = momentid.check(path, duffing if with_model else None, **keywords)
    assert result.to_dict() == expected
    assert list(json.loads(result.json)) == list(expected)
    assert result.channels == expected["channels"]
    assert result.identities == expected["identities"]
    assert result.warnings == expected["warnings"]
    assert bool(result.identities) == with_model
    assert str(result) == cli("check", *files, *options)


def test_latent_states_from_arrays():
    """The filter's output z has no array: identify eliminates it and says so in `latent`."""
    model = momentid.Model.from_file(str(ROOT / "models" / "filtered_duffing.mom"))
    record = momentid.simulate(model, samples=100_000, inputs={"x": INPUT}, noise={"y": 0.02})
    result = momentid.identify(model, {"y": record["y"], "x": record["x"]}, dt=0.01,
                               input_hold="zoh")
    assert result.latent["states"] == ["z"]
    assert result.latent["dof"] == 1 and result.latent["converged"]
    assert result.status == "ok"
    truth = {"c": 0.5, "k": 4.0, "eps": 1.0, "a": 2.0, "g": 1.0}
    for name, value in truth.items():
        assert abs(result.estimates[name] - value) < 4 * result.std_errors[name], name
    assert result.to_dict()["latent"]["coefficients"].keys() == {
        "-c - a", "-c*a - k", "-k*a", "-eps", "-eps*a", "2*g"}
