"""Tests of the Python module `momentid` against the `momentid` program.

What they cover:
- identify, simulate, derive and validate give the same numbers (JSON, text, files byte for
  byte) as the command line with the same options;
- records given as arrays in any layout (2-D with names=, strided, reversed, float32, int,
  a pandas DataFrame) give the estimates of contiguous float64 copies, and bad ones (complex,
  2-D without names, unequal lengths) raise UsageError naming what is wrong;
- errors are the module's exceptions with the command line's messages and places;
- simulate's Record (columns, runs, metadata) and its MomentidWarning for a coarse step;
- check and validate on a clean simulation;
- no memory leak over 1000 calls, and the GIL released while identify works.

Run from the repository root:
    PYTHONPATH=build/python MOMENTID=build/momentid python3 -m pytest -q python/tests
"""

import gc
import json
import os
import pydoc
import subprocess
import sys
import textwrap
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import momentid

from conftest import DUFFING, INPUT, ROOT, TRUE, read_csv, read_metadata, without


def assert_same_estimates(result, expected, rel=1e-12):
    """Estimates and standard errors of an IdentifyResult equal those of another result or of
    the CLI's JSON dict, to `rel` relative."""
    if isinstance(expected, dict):
        estimates = {n: p["estimate"] for n, p in expected["parameters"].items()}
        errors = {n: p["std_error"] for n, p in expected["parameters"].items()}
    else:
        estimates, errors = expected.estimates, expected.std_errors
    assert result.estimates == pytest.approx(estimates, rel=rel, abs=0)
    assert result.std_errors == pytest.approx(errors, rel=rel, abs=0)


def rss_bytes():
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS in /proc/self/status")


# --- 1. round trip against the command line ----------------------------------------------------

def test_identify_file_equals_cli(duffing, cli_csv, cli_json):
    result = momentid.identify(duffing, str(cli_csv))
    assert result.to_dict() == cli_json
    assert_same_estimates(result, cli_json)
    # A model path and a pathlib.Path work as well.
    assert momentid.identify(DUFFING, cli_csv).to_dict() == cli_json


def test_identify_arrays_equal_cli(duffing, cli_csv, cli_json):
    columns = read_csv(cli_csv)
    assert list(columns) == ["t", "y", "v", "x"]
    # The arrays lose the file's metadata, so the hold of the input is given, and the equations
    # its noise-free records take.
    with_t = momentid.identify(duffing, columns, input_hold="zoh", method="zero-lag")
    assert_same_estimates(with_t, cli_json)
    with_dt = momentid.identify(duffing, without(columns, "t"), dt=0.01, input_hold="zoh",
                                method="zero-lag")
    assert_same_estimates(with_dt, cli_json)
    # The same report but for why the equations were chosen.
    assert with_t.to_dict()["method"] == {"name": "zero-lag", "why": "asked for"}
    assert without(with_t.to_dict(), "data", "method") == without(cli_json, "data", "method")


def test_simulate_equals_cli_file(duffing, cli_csv, cli_json):
    simulated = momentid.simulate(duffing, seed=3, samples=100000, inputs={"x": INPUT})
    columns = read_csv(cli_csv)
    assert list(simulated) == list(columns)
    for name in columns:
        assert simulated[name].dtype == np.float64
        np.testing.assert_array_equal(simulated[name], columns[name], err_msg=name)
    assert simulated.metadata == read_metadata(cli_csv)
    # The Record carries the metadata (input-hold=zoh), so no option is needed.
    result = momentid.identify(duffing, simulated)
    assert without(result.to_dict(), "data") == without(cli_json, "data")


def test_data_frame_carries_the_metadata_and_arrays_say_why_they_are_measured(duffing, cli_json):
    simulated = momentid.simulate(duffing, seed=3, samples=100000, inputs={"x": INPUT})
    # A DataFrame made by Record.to_frame() keeps the metadata in attrs["momentid"]: the same
    # equations, estimates and report as the file.
    frame = simulated.to_frame()
    assert frame.attrs["momentid"] == simulated.metadata
    from_frame = momentid.identify(duffing, frame)
    assert without(from_frame.to_dict(), "data") == without(cli_json, "data")
    # Plain arrays carry nothing: the lagged equations, and the report says why and how a record
    # known to be free of noise takes the faster ones.
    plain = {name: np.asarray(values) for name, values in simulated.items()}
    method = momentid.identify(duffing, plain).to_dict()["method"]
    assert method["name"] == "lagged"
    assert method["why"].startswith("a record without metadata is taken as measured")
    assert "--method zero-lag" in method["why"]


# --- 2. array layouts ----------------------------------------------------------------------------

def test_2d_array_columns_are_views(duffing, record):
    names = ["t", "y", "v", "x"]
    table = np.column_stack([record[n] for n in names])
    assert table.flags.c_contiguous and table[:, 1].strides == (32,)
    copies = {n: np.ascontiguousarray(table[:, k]) for k, n in enumerate(names)}
    expected = momentid.identify(duffing, copies, input_hold="zoh")
    result = momentid.identify(duffing, table, names=names, input_hold="zoh")
    assert_same_estimates(result, expected, rel=0)


def test_strided_and_reversed_views(duffing, record):
    expected = momentid.identify(duffing, dict(record), input_hold="zoh")
    strided = {}
    for name, values in record.items():
        big = np.full(2 * len(values), 1e300)  # every other value garbage
        big[::2] = values
        strided[name] = big[::2]
        assert not strided[name].flags.c_contiguous
    assert_same_estimates(momentid.identify(duffing, strided, input_hold="zoh"), expected, rel=0)
    # A negative stride: a time-reversed record, against its contiguous copy.
    reversed_view = {n: v[::-1] for n, v in record.items() if n != "t"}
    reversed_copy = {n: v.copy() for n, v in reversed_view.items()}
    assert_same_estimates(
        momentid.identify(duffing, reversed_view, dt=0.01, input_hold="zoh"),
        momentid.identify(duffing, reversed_copy, dt=0.01, input_hold="zoh"), rel=0)


def test_float32_arrays_are_converted(duffing, record):
    data = {n: record[n] for n in ("y", "v", "x")}
    expected = momentid.identify(duffing, data, dt=0.01, input_hold="zoh")
    single = momentid.identify(duffing, {n: v.astype(np.float32) for n, v in data.items()},
                               dt=0.01, input_hold="zoh")
    assert single.estimates == pytest.approx(expected.estimates, rel=1e-4)
    assert single.estimates != expected.estimates  # it did read the rounded values


def test_int_arrays_are_converted(duffing, record):
    scaled = {n: np.round(record[n] * 1000) for n in ("y", "v", "x")}
    as_float = momentid.identify(duffing, scaled, dt=0.01, input_hold="zoh")
    as_int = momentid.identify(duffing, {n: v.astype(np.int64) for n, v in scaled.items()},
                               dt=0.01, input_hold="zoh")
    assert_same_estimates(as_int, as_float, rel=0)


def test_complex_array_is_a_usage_error(duffing, record):
    data = {"y": record["y"].astype(complex), "v": record["v"], "x": record["x"]}
    with pytest.raises(momentid.UsageError, match="column 'y'.*complex"):
        momentid.identify(duffing, data, dt=0.01)


def test_2d_array_needs_column_names(duffing, record):
    table = np.column_stack([record[n] for n in ("y", "v", "x")])
    with pytest.raises(momentid.UsageError, match="^names: a 2-D array of 3 columns needs"):
        momentid.identify(duffing, table, dt=0.01)
    with pytest.raises(momentid.UsageError, match="^names: .* found 2$"):
        momentid.identify(duffing, table, names=["y", "v"], dt=0.01)


def test_columns_of_different_lengths(duffing, record):
    data = {"y": record["y"], "v": record["v"][:-5], "x": record["x"]}
    with pytest.raises(momentid.UsageError) as raised:
        momentid.identify(duffing, data, dt=0.01)
    message = str(raised.value)
    assert "'v' has 19995" in message and "'y' has 20000" in message


def test_path_that_is_not_a_file(duffing, tmp_path):
    with pytest.raises(momentid.Error, match="cannot open"):
        momentid.identify(duffing, str(tmp_path / "no such file.csv"))


# --- 3. pandas -----------------------------------------------------------------------------------

def test_pandas_dataframe(duffing, record):
    pandas = pytest.importorskip("pandas")
    frame = pandas.DataFrame({n: record[n] for n in ("t", "y", "v", "x")})
    expected = momentid.identify(duffing, dict(record), input_hold="zoh")
    assert_same_estimates(momentid.identify(duffing, frame, input_hold="zoh"), expected, rel=0)
    # A frame with more columns than the model needs, in another order.
    frame["extra"] = 1.0
    shuffled = frame[["x", "extra", "v", "t", "y"]]
    assert_same_estimates(momentid.identify(duffing, shuffled, input_hold="zoh"), expected,
                          rel=0)


def test_a_dataframe_gives_results_labelled_by_parameter_as_statsmodels_does(duffing, record):
    pandas = pytest.importorskip("pandas")
    frame = pandas.DataFrame({n: record[n] for n in ("t", "y", "v", "x")})
    arrays = momentid.identify(duffing, dict(record), input_hold="zoh")
    labelled = momentid.identify(duffing, frame, input_hold="zoh")
    names = ["c", "k", "eps"]
    assert isinstance(arrays.params, np.ndarray) and isinstance(arrays.bse, np.ndarray)
    for fit, plain in ((labelled, arrays), (labelled.ls, arrays.ls)):
        for name in ("params", "bse", "tvalues", "pvalues"):
            series = getattr(fit, name)
            assert isinstance(series, pandas.Series) and list(series.index) == names
            assert series.name == name
            np.testing.assert_array_equal(series.to_numpy(), getattr(plain, name))
        assert fit.params["k"] == plain.estimates["k"]
        covariance, interval = fit.cov_params(), fit.conf_int(0.1)
        assert list(covariance.index) == names and list(covariance.columns) == names
        np.testing.assert_array_equal(covariance.to_numpy(), plain.cov_params())
        assert list(interval.index) == names and list(interval.columns) == [0, 1]
        np.testing.assert_array_equal(interval.to_numpy(), plain.conf_int(0.1))
    # The summary prints as the report, at the prompt too, and holds the tables.
    summary = labelled.summary()
    assert summary == labelled.text and repr(summary) == labelled.text
    assert summary.as_text() == labelled.text and type(summary.as_text()) is str
    assert [list(t.index) for t in summary.tables] == [names, names]
    np.testing.assert_array_equal(summary.tables[1]["estimate"].to_numpy(), arrays.ls.params)


def test_a_result_simulates_and_predicts_with_its_estimates(duffing, record):
    result = momentid.identify(duffing, record, input_hold="zoh")
    simulated = result.simulate(samples=500, seed=2, inputs={"x": INPUT})
    expected = momentid.simulate(duffing, result.estimates, samples=500, seed=2,
                                 inputs={"x": INPUT})
    np.testing.assert_array_equal(simulated["y"], expected["y"])
    # The response to a record's inputs, from its initial state.
    predicted = result.predict(record)
    replayed = momentid.simulate(duffing, result.estimates, inputs=record)
    np.testing.assert_array_equal(predicted["y"], replayed["y"])
    assert abs(np.corrcoef(predicted["y"], record["y"])[0, 1]) > 0.9
    # A result read from its JSON knows no model until it is given one.
    saved = momentid.IdentifyResult("", result.json)
    with pytest.raises(momentid.UsageError, match=r"^model: a result read from its JSON"):
        saved.predict(record)
    given = momentid.IdentifyResult("", result.json, duffing)
    np.testing.assert_array_equal(given.predict(record)["y"], predicted["y"])


def test_resid_and_fittedvalues_are_the_response_to_the_record_identified(duffing, record):
    # 2% noise on both states, in a DataFrame with its own index, a renamed column and the
    # force's hold in its attrs: the residuals are the noise (2% of each state's spread) and
    # the estimates' small error, on the rows the response has forgotten its initial state.
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(11)
    frame = pd.DataFrame({name: record[name] + 0.02 * np.std(record[name])
                          * rng.standard_normal(len(record[name])) for name in ("y", "v")},
                         index=np.arange(len(record["t"])) + 500)
    frame["t"], frame["x"] = record["t"], record["x"]
    frame = frame.rename(columns={"y": "disp"})
    frame.attrs["momentid"] = {"input-hold": "zoh"}
    result = momentid.identify(duffing, frame, columns={"y": "disp"})
    resid, fitted = result.resid, result.fittedvalues
    assert list(resid.columns) == ["y", "v"] and list(fitted.columns) == ["y", "v"]
    assert resid.index.equals(frame.index) and fitted.index.equals(frame.index)
    validation = result.validate()
    # The estimates' covariance widens the noise band, and the model is consistent with its record.
    assert validation.noise_band["with_errors"] and validation.consistent
    np.testing.assert_array_equal(fitted["y"].to_numpy(), validation.simulated["y"])
    assert np.array_equal(np.isnan(resid["y"].to_numpy()), ~validation.compared)
    assert 0 < (~validation.compared).sum() < len(frame) // 4
    for name, column in (("y", "disp"), ("v", "v")):
        spread = np.nanstd(resid[name]) / np.std(frame[column])
        assert 0.0195 < spread < 0.0215, (name, spread)
    # Plain arrays give plain arrays; a result read from its JSON holds no record.
    plain = momentid.identify(duffing, {k: np.asarray(frame[k]) for k in frame},
                              columns={"y": "disp"}, input_hold="zoh")
    np.testing.assert_array_equal(plain.resid["y"], resid["y"].to_numpy())
    saved = momentid.IdentifyResult("", result.json, duffing)
    with pytest.raises(momentid.UsageError, match=r"^data: a result read from its JSON"):
        saved.resid
    assert saved.validate(frame, columns={"y": "disp"}).fit == validation.fit


# --- 4. exceptions -------------------------------------------------------------------------------

def test_model_error_is_located():
    with pytest.raises(momentid.ModelError) as raised:
        momentid.Model("state y\ny' = -q*y\n")
    error = raised.value
    assert str(error) == "<string>:2:7: 'q' is not declared (declared: states y)"
    assert (error.file, error.line, error.column) == ("<string>", 2, 7)
    assert error.source_line == "y' = -q*y"
    assert isinstance(error, ValueError) and isinstance(error, momentid.Error)


def test_model_errors_name_keywords_not_flags():
    with pytest.raises(momentid.ModelError) as raised:
        momentid.simulate(momentid.Model("state y\nparam a\ny' = -a*y\n"), samples=10)
    assert str(raised.value) == ("<string>:2:7: parameter 'a' has no value: give a nominal value "
                                 "in the model or params a=VALUE")


def test_data_errors_name_keywords_not_flags(duffing, tmp_path):
    path = tmp_path / "a.npy"
    np.save(path, np.zeros((10, 4)))
    with pytest.raises(momentid.DataError) as raised:
        momentid.identify(duffing, str(path), names=["t", "y", "v"])
    assert str(raised.value) == f"{path}:1:1: names gives 3 names for 4 columns"
    units = tmp_path / "units.csv"
    units.write_text("t,y,v,x\ns,m,m/s,N\nclock,laser,laser,load cell\n0,1,2,3\n")
    with pytest.raises(momentid.DataError, match=r"\(a units row\? give skip_rows 1\)"):
        momentid.identify(duffing, str(units))


def test_nan_is_a_data_error_at_its_row(duffing, record):
    y = record["y"].copy()
    y[100] = np.nan
    data = {"t": record["t"], "y": y, "v": record["v"], "x": record["x"]}
    with pytest.raises(momentid.DataError, match="column 'y'") as raised:
        momentid.identify(duffing, data, input_hold="zoh")
    # Row 100 counted from 0 is line 101; y is the second column.
    assert (raised.value.line, raised.value.column) == (101, 2)
    # The hint names the keyword that passes over the row, as the command line names its flag.
    assert "(a missing value? missing drop-row or split-run passes over it)" in str(raised.value)
    assert isinstance(raised.value, ValueError)

    result = momentid.identify(duffing, data, input_hold="zoh", missing="split-run")
    assert result.diagnostics["runs"] == 2
    assert result.diagnostics["samples"] == len(y) - 1
    assert any("dropped 1 row" in w for w in result.warnings)
    assert result.estimates == pytest.approx(TRUE, rel=0.05)


def test_unknown_fixed_parameter_is_a_usage_error(duffing, record):
    with pytest.raises(momentid.UsageError, match="'zz' is not a parameter"):
        momentid.identify(duffing, record, fix={"zz": 1.0})
    # A known one is fixed.
    result = momentid.identify(duffing, record, fix={"c": 0.5})
    assert result.fixed == ["c"] and result.estimates["c"] == 0.5


def test_messages_name_the_keywords_not_the_command_line_options(duffing, record):
    with pytest.raises(momentid.UsageError, match=r"^fix: 'zz' is not a parameter"):
        momentid.identify(duffing, record, fix={"zz": 1.0})
    with pytest.raises(momentid.UsageError, match=r"^columns: 'zz' is not a state or input"):
        momentid.identify(duffing, record, columns={"zz": "y"})
    with pytest.raises(momentid.UsageError,
                       match=r"^noise: channel 'v' is not observed \(observe y,x\)"):
        momentid.simulate(duffing, samples=100, observe=["y", "x"], noise={"v": 0.1})


def test_a_bad_name_lists_the_accepted_names_under_the_keyword(duffing, record):
    with pytest.raises(momentid.UsageError,
                       match=r"^input_hold: expected sample or zoh, found 'held'$"):
        momentid.identify(duffing, record, input_hold="held")
    with pytest.raises(momentid.UsageError,
                       match=r"^weighting: expected auto, ls or gmm, found 'GMM'$"):
        momentid.identify(duffing, record, weighting="GMM")
    with pytest.raises(momentid.UsageError,
                       match=r"^params: 'zz' is not a parameter of model duffing"):
        momentid.simulate(duffing, {"zz": 1.0}, samples=100)


def test_option_of_the_wrong_type_is_a_usage_error(duffing, record):
    with pytest.raises(momentid.UsageError, match=r"^seed: expected a whole number, 0 or more, "
                                                  r"found -1$"):
        momentid.simulate(duffing, seed=-1)
    with pytest.raises(momentid.UsageError, match=r"^batches: expected a whole number, 0 or "
                                                  r"more, found 'ten'$"):
        momentid.identify(duffing, record, batches="ten")


def test_bad_dt_is_the_same_error_for_arrays_and_files(duffing, record, cli_csv):
    for data in (record, cli_csv):
        with pytest.raises(momentid.UsageError, match="^dt: expected a positive number$"):
            momentid.identify(duffing, data, dt=-1.0)
        # A denormal interval used to end in a RuntimeError from the symbolic stage.
        with pytest.raises(momentid.UsageError,
                           match=r"^dt: expected a sample interval from 1e-12 to 1e\+12, "
                                 r"found 1e-320$"):
            momentid.identify(duffing, data, dt=1e-320)
    # The record's own interval, from its time column, likewise (after the pass).
    tiny = {**{n: record[n] for n in ("y", "v", "x")}, "t": record["t"] * 1e-13}
    message = (r"^<arrays>:1:1: the sample interval 1e-15 \(the record's own: its time column, "
               r"metadata or stored interval\) is outside 1e-12 to 1e\+12: give the times in "
               r"other units, or the interval with dt$")
    for run in (momentid.identify, momentid.validate):
        with pytest.raises(momentid.DataError, match=message):
            run(duffing, tiny)


def test_model_from_missing_file(tmp_path):
    with pytest.raises(momentid.Error, match="cannot open the model file"):
        momentid.Model.from_file(tmp_path / "missing.mom")


def test_bad_calls_do_not_crash_the_interpreter():
    """Bad arguments of every kind raise Python exceptions; the interpreter lives on."""
    script = textwrap.dedent(f"""
        import numpy as np, momentid
        m = momentid.Model.from_file({str(DUFFING)!r})
        rec = momentid.simulate(m, samples=2000)
        calls = [
            lambda: momentid.Model(""),
            lambda: momentid.Model("state y\\x00\\ny' = -y\\n"),
            lambda: momentid.Model.from_file("/"),
            lambda: momentid.identify(m, {{}}),
            lambda: momentid.identify(m, {{k: v[:0] for k, v in rec.items()}}),
            lambda: momentid.identify(m, {{k: v[:1] for k, v in rec.items()}}),
            lambda: momentid.identify(m, {{"y": 1.0, "v": rec["v"], "x": rec["x"]}}, dt=0.01),
            lambda: momentid.identify(m, {{"y": np.array(["a"] * 2000), "v": rec["v"],
                                          "x": rec["x"]}}, dt=0.01),
            lambda: momentid.identify(m, rec, dt=-1),
            lambda: momentid.identify(m, rec, degree=-1),
            lambda: momentid.identify(m, rec, batches=-1),
            lambda: momentid.identify(m, rec, lags=(50, 3)),
            lambda: momentid.identify(m, rec, columns={{"y": "zz"}}),
            lambda: momentid.identify(m, rec, input_shift=10**12),
            lambda: momentid.identify(42, rec),
            lambda: momentid.identify(m, 42),
            lambda: momentid.simulate(m, samples=0),
            lambda: momentid.simulate(m, samples=10, seed=-1),
            lambda: momentid.simulate(m, samples=10, observe=["zz"]),
            lambda: momentid.simulate(m, samples=10, inputs={{"zz": "white"}}),
            lambda: momentid.simulate(m, {{"c": float("nan")}}, samples=10),
            lambda: momentid.check(rec, lags=-1),
            lambda: momentid.validate(m, rec, skip=10**9),
            lambda: momentid.validate(m, rec, substeps=0),
            lambda: m.derive(lags=(3, 50), measured=["zz"]),
        ]
        for n, call in enumerate(calls):
            try:
                call()
            except Exception:
                pass
            else:
                raise SystemExit(f"call {{n}} raised nothing")
        print("alive")
    """)
    env = dict(os.environ, PYTHONPATH=str(Path(momentid.__file__).resolve().parents[1]))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=60, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "alive"


def test_ctrl_c_stops_a_pass():
    """Ctrl-C while a pass reads (2*10^7 rows on one thread, about 3 s whole) raises
    KeyboardInterrupt within a second, not when the pass is over."""
    script = textwrap.dedent(f"""
        import os, signal, threading, time
        import numpy as np
        import momentid
        n = 20_000_000
        rng = np.random.default_rng(1)
        rec = {{"t": np.arange(n) * 0.01, "y": rng.standard_normal(n),
               "v": rng.standard_normal(n), "x": rng.standard_normal(n)}}
        model = momentid.Model.from_file({str(DUFFING)!r})
        sent = []
        def interrupt():
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)
        threading.Timer(0.3, interrupt).start()
        try:
            momentid.identify(model, rec, method="zero-lag", threads=1)
            print("finished")
        except KeyboardInterrupt:
            print(f"interrupted {{time.monotonic() - sent[0]:.2f}}")
    """)
    env = dict(os.environ, PYTHONPATH=str(Path(momentid.__file__).resolve().parents[1]))
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, env=env)
    assert done.returncode == 0, done.stderr
    word, took = done.stdout.split()
    assert word == "interrupted"
    assert float(took) < 1.0


# --- 5. derive -----------------------------------------------------------------------------------

def test_derive_equals_cli(duffing, cli):
    equations = duffing.derive(degree=2)
    assert equations.text == cli("derive", DUFFING, "--degree", 2)
    latex = cli("derive", DUFFING, "--degree", 2, "--format", "latex")
    assert equations.latex == latex
    assert equations._repr_latex_() == latex
    as_dict = json.loads(cli("derive", DUFFING, "--degree", 2, "--format", "json"))
    assert equations.to_dict() == as_dict
    assert json.loads(equations.json) == as_dict
    assert len(equations) == len(as_dict["equations"]) > 0


# --- 6. simulate ---------------------------------------------------------------------------------

def test_simulate_record_with_runs(duffing):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a fine step draws no warning
        simulated = momentid.simulate(duffing, samples=500, runs=2, seed=5)
    assert isinstance(simulated, momentid.Record)
    assert list(simulated) == ["t", "y", "v", "x", "run"]
    for name, values in simulated.items():
        assert values.shape == (1000,), name
    np.testing.assert_array_equal(simulated["run"], np.repeat([1.0, 2.0], 500))
    assert simulated["t"][0] == simulated["t"][500] == 0  # t restarts with each run
    assert simulated.metadata["runs"] == "2" and simulated.metadata["seed"] == "5"


@pytest.mark.parametrize("fmt", ["csv", "bin"])
def test_simulate_path_equals_cli_bytes(duffing, cli, tmp_path, fmt):
    ours, theirs = tmp_path / f"ours.{fmt}", tmp_path / f"cli.{fmt}"
    assert momentid.simulate(duffing, {"c": 0.7}, samples=3000, runs=2, seed=11,
                             inputs={"x": "ou:tau=0.5"}, path=ours, format=fmt) is None
    cli("simulate", DUFFING, "--set", "c=0.7", "--samples", 3000, "--runs", 2, "--seed", 11,
        "--input", "x=ou:tau=0.5", "--format", fmt, "-o", theirs)
    assert ours.read_bytes() == theirs.read_bytes()


def test_simulate_path_name_chooses_the_format(duffing, tmp_path):
    # Without `format`, a .bin path is written in binary, as `simulate -o FILE.bin` does.
    momentid.simulate(duffing, samples=10, path=tmp_path / "named.bin")
    assert (tmp_path / "named.bin").read_bytes()[:8] == b"MOMNTID1"
    # A name no format has, or one `format` contradicts: refused, and no file is written.
    with pytest.raises(momentid.UsageError,
                       match=r"^path: cannot tell the format of '.*x\.xyz' from its name .*: "
                             r"give format$"):
        momentid.simulate(duffing, samples=10, path=tmp_path / "x.xyz")
    with pytest.raises(momentid.UsageError, match="^format: csv contradicts the output file's name"):
        momentid.simulate(duffing, samples=10, path=tmp_path / "y.bin", format="csv")
    with pytest.raises(momentid.UsageError, match=r"^format: bin contradicts .*'.*z\.mat' \(mat\)"):
        momentid.simulate(duffing, samples=10, path=tmp_path / "z.mat", format="bin")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["named.bin"]
    # `format` names the format of a name that does not.
    momentid.simulate(duffing, samples=10, path=tmp_path / "x.xyz", format="csv")
    assert (tmp_path / "x.xyz").read_text().startswith("# momentid: model=duffing")


def test_simulate_path_h5_holds_the_csv_values(duffing, tmp_path):
    """An .h5 path is written as HDF5, which h5py reads: the same values as the CSV of the same
    seed, bit for bit (CSV numbers read back exactly), and the metadata as attributes."""
    h5py = pytest.importorskip("h5py")
    options = dict(samples=2000, runs=2, seed=9, inputs={"x": INPUT}, noise={"y": 0.05})
    momentid.simulate(duffing, path=tmp_path / "r.csv", **options)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # HDF5 keeps the names and metadata: nothing to warn of
        assert momentid.simulate(duffing, path=tmp_path / "r.h5", **options) is None
    csv, metadata = read_csv(tmp_path / "r.csv"), read_metadata(tmp_path / "r.csv")
    assert list(csv) == ["t", "y", "v", "x", "run"]
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert sorted(f.keys()) == sorted(csv)
        for name, column in csv.items():
            values = f[name][()]
            assert values.dtype == np.float64 and values.shape == (4000,), name
            assert np.array_equal(values.view(np.uint64), column.view(np.uint64)), name
        # Every key=value of the CSV's metadata, `dt` as a number, the others as text.
        assert "noise-sd.y" in metadata
        for key, value in metadata.items():
            assert f.attrs[key] == (float(value) if key == "dt" else value.encode()), key
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.h5"]


def test_simulate_path_npy_warns_how_to_read_it_back(duffing, tmp_path):
    path = tmp_path / "r.npy"
    with pytest.warns(momentid.MomentidWarning,
                      match=r"^a \.npy file keeps neither column names nor metadata: read "
                            r".*r\.npy with --names t,y,v,x --input-hold zoh$"):
        momentid.simulate(duffing, samples=500, seed=2, path=path)
    np.testing.assert_array_equal(
        np.load(path), np.column_stack(list(momentid.simulate(duffing, samples=500, seed=2).values())))


def test_simulate_driven_by_a_record_writes_its_path_as_the_cli(duffing, cli, tmp_path):
    record = tmp_path / "record.csv"
    momentid.simulate(duffing, samples=500, seed=4, inputs={"x": INPUT}, path=record)
    ours, theirs = tmp_path / "ours.bin", tmp_path / "cli.bin"
    # The response to the record's inputs, written where `path` says (it used to be returned
    # and `path` ignored), in the format its name says.
    assert momentid.simulate(duffing, {"c": 0.7}, inputs=record, path=ours) is None
    cli("simulate", DUFFING, "--set", "c=0.7", "--input-file", record, "-o", theirs)
    assert ours.read_bytes()[:8] == b"MOMNTID1"
    assert ours.read_bytes() == theirs.read_bytes()


def test_simulate_coarse_step_warns(duffing):
    with pytest.warns(momentid.MomentidWarning, match="coarse"):
        simulated = momentid.simulate(duffing, dt=0.3, inputs={"x": "ma:K=1,sigma=3"},
                                      samples=2000)
    assert len(simulated["y"]) == 2000  # the record is still returned


# --- 7. check and validate -----------------------------------------------------------------------

def test_check_clean_record(duffing, record):
    result = momentid.check(record, duffing)
    assert list(result.channels) == ["y", "v", "x"]
    assert result.channels["x"]["input"] and not result.channels["y"]["input"]
    assert result.warnings == []
    assert result.identities and all(abs(i["z"]) < 4 for i in result.identities)
    assert result.to_dict()["rows"] == 20000


def test_validate_true_parameters(duffing, record):
    result = momentid.validate(duffing, record, params=TRUE)
    assert result.fit["y"] > 99.9
    assert result.warnings == []


def test_validate_reports_sensitivity_and_the_verdict(duffing, record):
    result = momentid.validate(duffing, record, params=TRUE)
    assert not result.sensitive and result.consistent and result.statistics is None
    assert result.sensitivity["lyapunov"] < 0 and result.sensitivity["time_to_spread"] is None
    assert result.verdict.startswith("the trajectory can be reproduced")


def test_validate_judges_a_sensitive_model_by_its_statistics(duffing):
    # A lightly damped, strongly hardening oscillator under a strong force.
    stiff = {"c": 0.2, "k": 100.0, "eps": 1e4}
    record = momentid.simulate(duffing, stiff, samples=40000, dt=0.001, seed=5,
                               inputs={"x": "ou:tau=0.01,sigma=50"}, substeps=4)
    result = momentid.validate(duffing, record, params=stiff)
    assert result.sensitive and result.sensitivity["time_to_spread"] > 0
    assert result.consistent and result.warnings == []
    checks = result.statistics["checks"]
    # Both states are in the record: the prediction errors are compared too.
    assert [c["kind"] for c in checks] == ["psd", "distribution", "crossings"] * 2 + \
        ["prediction", "bias"] * 2
    assert all(c["inside"] for c in checks)
    assert len(checks[0]["at"]) == result.statistics["segment"] // 2 + 1


def test_validate_center_removes_an_offset(duffing, record):
    shifted = momentid.Record({**record, "y": record["y"] + 0.3}, record.metadata)
    result = momentid.validate(duffing, shifted, params=TRUE, center="y")
    assert result.centered == {"y": pytest.approx(0.3 + np.mean(record["y"]), rel=1e-12)}
    assert "means removed (--center): y " in str(result)
    # Centering removes any constant: the shifted record compares as the record does.
    unshifted = momentid.validate(duffing, record, params=TRUE, center="y")
    assert result.fit["y"] == pytest.approx(unshifted.fit["y"], rel=1e-9)
    offset = momentid.validate(duffing, shifted, params=TRUE)
    assert offset.centered == {}
    assert offset.fit["y"] < result.fit["y"] - 10


def test_irregular_time_stamps_suggest_the_dt_keyword(duffing, record):
    t = np.round(np.arange(len(record["t"])) / 1024, 6)
    data = {**record, "t": t}
    assert momentid.check(data).to_dict() is not None  # six decimals at 1024 Hz: accepted
    t[20] += 3e-6
    with pytest.raises(momentid.DataError, match=r"give the sample interval with dt 0.000976\d* if "
                       r"the samples are equally spaced") as raised:
        momentid.check(data)
    assert raised.value.line == 21


def test_validate_identify_result_as_params(duffing, record):
    estimated = momentid.identify(duffing, record)
    result = momentid.validate(duffing, record, params=estimated)
    assert result.to_dict()["parameters"] == pytest.approx(estimated.estimates, rel=1e-15)
    assert result.fit["y"] > 99


def test_validate_json_equals_cli(duffing, cli, tmp_path):
    path = tmp_path / "validate.csv"
    momentid.simulate(duffing, samples=20000, seed=3, inputs={"x": INPUT}, path=path)
    theirs = json.loads(cli("validate", DUFFING, path, "--set", "c=0.5,k=4,eps=1",
                            "--format", "json"))
    # The file, and the same record in memory (a Record, with the file's metadata).
    in_memory = momentid.simulate(duffing, samples=20000, seed=3, inputs={"x": INPUT})
    for data in (path, in_memory):
        ours = momentid.validate(duffing, data, params=TRUE).to_dict()
        # "parameters_from" says where the values came from; see the next test.
        assert without(ours, "data", "parameters_from") == \
            without(theirs, "data", "parameters_from")


def test_validate_says_where_the_parameters_came_from(duffing, cli, tmp_path):
    path = tmp_path / "validate.csv"
    momentid.simulate(duffing, samples=5000, seed=3, inputs={"x": INPUT}, path=path)
    theirs = json.loads(cli("validate", DUFFING, path, "--format", "json"))
    result = momentid.validate(duffing, path)
    assert "parameters ()" not in str(result)
    assert without(result.to_dict(), "data") == without(theirs, "data")


# --- 8. memory -----------------------------------------------------------------------------------

def test_no_leak_over_1000_calls(duffing):
    small = momentid.simulate(duffing, samples=2000, seed=1, inputs={"x": INPUT})
    for call in range(1000):
        momentid.identify(duffing, small)
        if call == 99:
            gc.collect()
            before = rss_bytes()
    gc.collect()
    grown = rss_bytes() - before
    assert grown < 10e6, f"resident memory grew by {grown / 1e6:.1f} MB over 900 calls"


# --- 9. the GIL ----------------------------------------------------------------------------------

def test_gil_released_during_identify(duffing):
    large = momentid.simulate(duffing, samples=4_000_000, seed=1, inputs={"x": INPUT})
    started, times, results = threading.Event(), {}, []

    def work():
        times["start"] = time.perf_counter()
        started.set()
        results.append(momentid.identify(duffing, large))
        times["end"] = time.perf_counter()

    thread = threading.Thread(target=work)
    thread.start()
    started.wait()
    # Count, and note the longest stretch in which this thread could not run: with the GIL
    # held, that is the whole call (however many increments one switch interval allows).
    counter, last, longest = 0, times["start"], 0.0
    while thread.is_alive():
        counter += 1
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
    thread.join()
    duration = times["end"] - times["start"]
    assert results and results[0].status == "ok"
    assert duration > 0.1, f"identify took only {duration:.3f} s: the test needs a longer call"
    assert counter > 1000
    assert longest < duration / 3, (
        f"the main thread stood still for {longest:.3f} s of a {duration:.3f} s call")


def test_threads_calling_at_once_get_the_serial_results(duffing):
    """Several Python threads calling identify and check at once, on records with a held input
    (what simulate writes) and on one array they share: no crash, and every result is the one a
    serial call gives."""
    records = [momentid.simulate(duffing, samples=20_000, seed=seed, inputs={"x": INPUT})
               for seed in range(1, 9)]
    serial = [str(momentid.identify(duffing, record)) for record in records]
    checked = str(momentid.check(records[0], model=duffing))
    for count in (2, 8):
        for _ in range(5):
            results, errors = {}, []

            def work(k):
                try:
                    results[k] = str(momentid.identify(duffing, records[k % len(records)]))
                    results[-1 - k] = str(momentid.check(records[0], model=duffing))
                except Exception as error:  # reported below, with the thread
                    errors.append((k, error))

            threads = [threading.Thread(target=work, args=(k,)) for k in range(count)]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
            assert not errors
            for k in range(count):
                assert results[k] == serial[k % len(records)]
                assert results[-1 - k] == checked


def test_threads_calling_validate_and_select_beside_identify_get_the_serial_results(duffing):
    """validate and select (which keep the GIL but for select's passes) on threads beside
    identify (which lets go of it while it reads): every result is the serial one."""
    library = momentid.Model.from_file(ROOT / "examples" / "select" / "library.mom")
    record = momentid.simulate(duffing, samples=20_000, seed=3, inputs={"x": INPUT})
    calls = {"identify": lambda: momentid.identify(duffing, record),
             "validate": lambda: momentid.validate(duffing, record),
             "select": lambda: momentid.select(library, record)}
    serial = {name: str(call()) for name, call in calls.items()}
    for _ in range(3):
        results, errors = {}, []

        def work(k, name):
            try:
                results[(k, name)] = str(calls[name]())
            except Exception as error:  # reported below, with the thread
                errors.append((k, name, error))

        threads = [threading.Thread(target=work, args=(k, name))
                   for k in range(2) for name in calls]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        assert not errors
        for (k, name), text in results.items():
            assert text == serial[name], (k, name)
        assert len(results) == 2 * len(calls)


# --- 10. documentation ---------------------------------------------------------------------------

def test_identify_has_help():
    text = pydoc.render_doc(momentid.identify, renderer=pydoc.plaintext)
    assert "data" in text and "Returns" in text
    assert "data" in momentid.identify.__doc__ and "Returns" in momentid.identify.__doc__


# --- 11. several files ----------------------------------------------------------------------------

def test_threads_change_nothing(duffing):
    """Arrays of 16 MB or more are read in shards on the threads asked for: any number gives the
    one-thread result to the last bit."""
    record = momentid.simulate(duffing, samples=800_000, seed=2, inputs={"x": INPUT})
    one = momentid.identify(duffing, record, threads=1)
    for threads in (2, 3):
        other = momentid.identify(duffing, record, threads=threads)
        assert other.estimates == one.estimates
        assert other.std_errors == one.std_errors
    assert momentid.check(record, threads=2).to_dict() == momentid.check(record, threads=1).to_dict()


def test_list_of_files_is_one_record_of_their_runs(duffing, tmp_path):
    """Two files give the estimates of the same two runs in one file."""
    both = tmp_path / "both.csv"
    momentid.simulate(duffing, samples=3000, seed=5, runs=2, inputs={"x": INPUT}, path=both)
    lines = both.read_text().splitlines()
    metadata = [line for line in lines if line.startswith("#")]
    header, *rows = [line for line in lines if not line.startswith("#")]
    paths = []
    for run in ("1", "2"):
        path = tmp_path / f"run{run}.csv"
        kept = [row.rsplit(",", 1)[0] for row in rows if row.rsplit(",", 1)[1] == run]
        path.write_text("\n".join(metadata + [header.rsplit(",", 1)[0]] + kept) + "\n")
        paths.append(path)
    # Least squares: the optimal weighting, like the standard errors, comes from the batches,
    # and the batches of two files are cut elsewhere than those of one.
    whole = momentid.identify(duffing, both, weighting="ls")
    split = momentid.identify(duffing, paths, weighting="ls")
    assert split.diagnostics["runs"] == 2
    for name, value in whole.estimates.items():
        assert split.estimates[name] == pytest.approx(value, rel=1e-12)


def test_identify_extrapolate(duffing, cli_csv):
    # The sampling bias from every other sample: reported for inputs read as samples, refused
    # for a held input (the record's metadata), and only 'dt' is a valid value.
    columns = read_csv(cli_csv)
    result = momentid.identify(duffing, columns, input_hold="sample", degree=3, extrapolate=True)
    bias = result.diagnostics["sampling_bias"]
    assert bias["order"] == 2
    assert set(bias["parameters"]) == {"c", "k", "eps"}
    assert all(p["difference_error"] > 0 for p in bias["parameters"].values())
    with pytest.raises(momentid.UsageError, match=r"^extrapolate: the input is held"):
        momentid.identify(duffing, str(cli_csv), degree=3, extrapolate=True)
    # A held input's kinks are corrected instead, and the shift is reported.
    held = momentid.identify(duffing, str(cli_csv), degree=3)
    correction = held.diagnostics["held_input_correction"]
    assert correction["applied"] is True
    assert set(correction["shift"]) == {"c", "k", "eps"}
    assert "held_input_correction" not in result.diagnostics
    # The errors that the record's ends leave come from the states' variances there.
    assert held.diagnostics["end_values"] == {"applied": True}
    with pytest.raises(momentid.UsageError, match=r"^extrapolate: expected True or False, found 't'"):
        momentid.identify(duffing, str(cli_csv), extrapolate="t")


def test_simulate_and_replay_friction():
    # sign(v): the record holds the states and the input, not the sign, and the mass sticks
    # (v exactly 0, y held) while the force stays within the friction.
    friction = ROOT / "tests" / "data" / "friction.mom"
    simulated = momentid.simulate(friction, samples=2000, burn_in=50)
    assert list(simulated) == ["t", "y", "v", "x"]
    stuck = simulated["v"] == 0
    assert 0 < stuck.sum() < 2000
    held = np.flatnonzero(stuck[:-1] & stuck[1:])
    np.testing.assert_array_equal(simulated["y"][held], simulated["y"][held + 1])
    replayed = momentid.validate(friction, simulated)
    assert replayed.fit["y"] > 99.999 and replayed.fit["v"] > 99.999


def test_linearised_modes(duffing, cli, cli_csv):
    # The Duffing oscillator at y = 0: one mode near sqrt(k) / (2 pi) Hz, damping ratio near
    # c / (2 sqrt(k)); the arrays hold the CLI's JSON values.
    result = momentid.identify(duffing, cli_csv)
    engineering = json.loads(cli("identify", DUFFING, cli_csv, "--format", "json"))["engineering"]
    assert result.natural_frequencies.shape == (1, 2)
    frequency, error = result.natural_frequencies[0]
    assert frequency == engineering["natural_frequencies_hz"][0]["estimate"]
    assert abs(frequency - 1 / np.pi) < 3 * error
    ratio, error = result.damping_ratios[0]
    assert abs(ratio - 0.125) < 3 * error
