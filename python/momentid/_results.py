"""The results of identify(), check() and validate(), as values to compute with.

An identification is read from its JSON value (what `momentid identify --format json` prints),
which the binding converts into Python objects without writing or parsing text, never from the
text report, so that the numbers are the program's to the last bit. The arrays follow
statsmodels' results (params, bse, cov_params(), conf_int(), tvalues, pvalues, summary()): as
statsmodels does, they are numpy arrays in the order of `param_names`, and pandas Series and
DataFrames indexed by the parameters' names when the record was a pandas DataFrame. The module
needs numpy only; pandas, when installed, gives the tables of to_frame().
"""

from __future__ import annotations

import copy as _copy
import json as _json
import os as _os
from typing import Optional, Union

import numpy as _np

from . import _momentid


def _number(value) -> float:
    # The JSON writes what is not a finite number as null.
    return _np.nan if value is None else float(value)


def _json_text(value: dict) -> str:
    # Laid out as the program prints it: two spaces of indentation, a final newline.
    return _json.dumps(value, indent=2, ensure_ascii=False) + "\n"


def _read_only(values) -> _np.ndarray:
    array = _np.array(values, dtype=float)
    array.flags.writeable = False
    return array


def _t_dof(dof: float) -> float:
    # The library's rule (long_run.hpp, t975): below one degree of freedom the t law has no
    # variance and its quantiles overflow, so at least one is taken. Unknown stays unknown.
    return dof if _np.isnan(dof) else max(1.0, dof)


def _t_quantile(q: float, dof: float) -> float:
    return _np.nan if _np.isnan(dof) else _momentid._t_quantile(q, _t_dof(dof))


def _pandas():
    try:
        import pandas
    except ImportError as error:
        raise ImportError("to_frame() needs pandas (pip install pandas, or Debian's "
                          "python3-pandas); the arrays need only numpy") from error
    return pandas


class Fit:
    """One estimate of the model's parameters with its errors: the least-squares one or the
    optimally weighted (GMM) one. Every array is in the order of `param_names` (the
    model's parameters in declaration order) and read-only.

    params, bse: the estimates and their standard errors. A parameter taken as known (`fix=`, or
      `fixed` in the model) has its value and error 0; one the data do not identify (only
      combinations of it with others) has the minimum-norm estimate and error NaN.
    df_resid: the degrees of freedom of the standard errors: the effective degrees of freedom of
      their long-run covariance over the batches, not samples minus parameters. Student's t at
      df_resid (at least 1) gives the intervals and p-values, as the program's 95% intervals.
    tvalues, pvalues: params / bse and the two-sided p-value of the t test of "the parameter is
      0"; NaN for a parameter that is fixed or not identifiable.
    identifiable: a boolean array; fixed: the names of the fixed parameters.
    With `labels` (a record given as a pandas DataFrame), params, bse, tvalues and pvalues are
    pandas Series indexed by the parameters' names, cov_params() and conf_int() DataFrames.
    objective: what the fit minimised, at its estimate (docs/json.md, "identify"): fits of the
      same moments compare by it; NaN when nothing is identifiable.
    cov_params(), conf_int(alpha), to_frame(alpha): below.
    estimates, std_errors: {parameter: float}; ci95: {parameter: (low, high)}.
    """

    def __init__(self, section: dict, labels: bool = False) -> None:
        """section: {"parameters": the JSON's parameter entries, "error_dof": their degrees of
        freedom, "covariance": their covariance matrix (rows of numbers or null), and optionally
        "objective" and "correlation"}. Without "covariance" (a result saved by an older
        release), cov_params() is NaN."""
        parameters = section["parameters"]
        self.param_names = list(parameters)
        self._labels = labels
        self._params = _read_only([_number(p["estimate"]) for p in parameters.values()])
        self._bse = _read_only([_number(p["std_error"]) for p in parameters.values()])
        self.identifiable = _np.array([p["identifiable"] for p in parameters.values()], bool)
        self.identifiable.flags.writeable = False
        self._fixed = _np.array([p["fixed"] for p in parameters.values()], bool)
        self.df_resid = _number(section["error_dof"])
        self.objective = _number(section.get("objective"))
        count = len(self.param_names)
        self._covariance = _read_only(
            [[_number(c) for c in row] for row in section["covariance"]]
            if section.get("covariance") else _np.full((count, count), _np.nan))
        self.estimates = {name: p["estimate"] for name, p in parameters.items()}
        self.std_errors = {name: p["std_error"] for name, p in parameters.items()}
        self.ci95 = {name: tuple(p["ci95"]) if p["ci95"] is not None else None
                     for name, p in parameters.items()}
        self.fixed = [name for name, p in parameters.items() if p["fixed"]]

    def _series(self, values: _np.ndarray, name: str):
        if not self._labels:
            return values
        return _pandas().Series(values, index=self.param_names, name=name)

    def _frame(self, values: _np.ndarray, columns):
        if not self._labels:
            return values
        return _pandas().DataFrame(values, index=self.param_names, columns=columns)

    @property
    def params(self):
        return self._series(self._params, "params")

    @property
    def bse(self):
        return self._series(self._bse, "bse")

    def _tvalues(self) -> _np.ndarray:
        with _np.errstate(divide="ignore", invalid="ignore"):
            t = self._params / self._bse
        t[self._fixed] = _np.nan
        return t

    def _pvalues(self) -> _np.ndarray:
        dof = _t_dof(self.df_resid)
        return _np.array([2 * _momentid._t_upper_tail(abs(t), dof)
                          if _np.isfinite(t) and not _np.isnan(dof) else _np.nan
                          for t in self._tvalues()])

    @property
    def tvalues(self):
        return self._series(self._tvalues(), "tvalues")

    @property
    def pvalues(self):
        return self._series(self._pvalues(), "pvalues")

    def cov_params(self):
        """The covariance matrix of the estimates, as the program computes it from their
        standard errors and correlation: the squared errors on the diagonal, rows and columns of
        a fixed parameter 0, NaN where an error or a correlation is unknown."""
        return self._frame(self._covariance.copy(), self.param_names)

    def _conf_int(self, alpha: float) -> _np.ndarray:
        if not 0 < alpha < 1:
            from . import UsageError
            raise UsageError(f"alpha: expected a number between 0 and 1, found {alpha!r}")
        t = _t_quantile(1 - alpha / 2, self.df_resid)
        return _np.column_stack([self._params - t * self._bse, self._params + t * self._bse])

    def conf_int(self, alpha: float = 0.05):
        """The (1 - alpha) confidence intervals, one row (low, high) per parameter: Student's t
        at df_resid times the standard error either side. At alpha=0.05 these are `ci95`."""
        return self._frame(self._conf_int(alpha), [0, 1])

    def to_frame(self, alpha: float = 0.05):
        """A pandas DataFrame, one row per parameter (the index): estimate, std_error, t,
        p_value, ci_low and ci_high (the (1 - alpha) interval), identifiable, fixed."""
        pandas = _pandas()
        interval = self._conf_int(alpha)
        return pandas.DataFrame(
            {"estimate": self._params, "std_error": self._bse, "t": self._tvalues(),
             "p_value": self._pvalues(), "ci_low": interval[:, 0], "ci_high": interval[:, 1],
             "identifiable": self.identifiable, "fixed": self._fixed},
            index=pandas.Index(self.param_names, name="parameter"))

    def __repr__(self) -> str:
        values = ", ".join(f"{name}={value:.6g}±{error:.2g}" for name, value, error in
                           zip(self.param_names, self._params, self._bse))
        return f"<momentid.Fit {values}>"


class Summary(str):
    """The text report, as summary() returns it: a str that prints as the report, also at the
    interactive prompt (where a plain str shows its escapes); as_text() gives it as a plain
    str, and `tables` the parameter tables as pandas DataFrames (the main fit's, then, when
    optimally weighted, the least-squares one's)."""

    def __new__(cls, text: str, result: "IdentifyResult"):
        out = super().__new__(cls, text)
        out._result = result
        return out

    def as_text(self) -> str:
        return str.__str__(self)

    @property
    def tables(self) -> list:
        fits = [self._result] + ([self._result.ls] if self._result.weighting == "gmm" else [])
        return [fit.to_frame() for fit in fits]

    def __repr__(self) -> str:
        return self.as_text()


class IdentifyResult(Fit):
    """What identify() found: the main estimate (a Fit: params, bse, cov_params(), conf_int(),
    ...; the optimally weighted one when it was computed, otherwise least squares), and:

    weighting: "gmm" or "ls", which estimate is the main one; ls: the least-squares Fit (the
      first step of the optimally weighted one, or the main estimate itself).
    jval, jtest(): Hansen's J statistic of the optimally weighted estimate, and (J, p-value,
      degrees of freedom); None without it.
    nobs: the samples the moments are averaged over; status: "ok", "doubtful", "rank-deficient"
      or "nothing-identifiable"; warnings: what to distrust, the most serious first; equations:
      the identified model; diagnostics: the whole diagnostics section of the JSON.
    natural_frequencies, damping_ratios: the model linearised at its equilibrium under the
      inputs' means, one entry per oscillating mode by frequency (Hz), each an array of
      (estimate, standard error) rows; empty when there is none (engineering["unavailable"]
      says why); engineering: that section of the JSON, with the equilibrium.
    summary(): the text report of `momentid identify` (a Summary: it prints as the report, and
      gives its tables), str() the same; to_dict(): the JSON of
      `momentid identify --format json` as Python objects, `json` as text.
    model: the Model identified (None for a result read from its JSON); simulate(**options) and
      predict(data, **options): the model with the estimates simulated, as momentid.simulate()
      does, under random inputs or through a record's inputs (its response to them).
    validate(data=None, **options): the model with the estimates simulated through the inputs
      of a record (by default the one identified, with its record options) and compared with
      it, as momentid.validate() does; fittedvalues and resid: on the record identified, per
      state the record shows, the model's response to its inputs and the record minus that
      response (NaN on the rows before each run's skip, where the response still carries the
      initial state), arrays in a dict, or a DataFrame when the record was one.
    plot_engineering(): the restoring force and the backbone drawn (momentid.plots).
    latent: for a model with states the record does not show (docs/latent-states.md), the
      `latent` section of the JSON: the states, the equations without them, their coefficients'
      estimates and the minimum distance's test; None otherwise.
    refinement: with refine=True (docs/refine.md), the `refinement` section of the JSON: each
      parameter's start and refined value with their intervals, the simulation error before and
      after, the inputs' noise and its bias removed; None otherwise.

    IdentifyResult(text, value) reads a saved result of the program as well: `value` is its
    JSON text or the dict json.load() made of it (text may be ""); `model` the Model it is of,
    for simulate() and predict(); `labels` True for pandas Series and DataFrames (see Fit).
    """

    def __init__(self, text: str, value: Union[str, dict], model=None,
                 labels: bool = False) -> None:
        self.text = text
        self.model = model
        # The record identified and its record options (identify() and select() set them): what
        # validate(), fittedvalues and resid compare the model with.
        self._record = None
        self._validation = None
        # A JSON text is a result saved by the user; the binding hands over the value itself.
        self._dict = _json.loads(value) if isinstance(value, str) else value
        self.diagnostics = self._dict["diagnostics"]
        main = {"parameters": self._dict["parameters"], **self.diagnostics}
        super().__init__(main, labels)
        self.weighting = "gmm" if "least_squares" in self._dict else "ls"
        if self.weighting == "gmm":
            # A result saved by an older release lacks the least-squares errors: their intervals
            # and covariances are NaN, not guessed.
            errors = self.diagnostics.get("least_squares", {"error_dof": None})
            self.ls = Fit({"parameters": self._dict["least_squares"], **errors}, labels)
        else:
            self.ls = Fit(main, labels)
        self.status = self.diagnostics["status"]
        self.warnings = list(self.diagnostics["warnings"])
        self.equations = list(self._dict.get("equations", []))
        self.nobs = self.diagnostics["samples"]
        self.jval = self.diagnostics["j_statistic"]
        self.engineering = self._dict.get("engineering", {})
        self.latent = self._dict.get("latent")
        self.refinement = self._dict.get("refinement")
        self.natural_frequencies, self.damping_ratios = (
            _read_only(_np.reshape([[_number(m["estimate"]), _number(m["std_error"])]
                                    for m in self.engineering.get(key, [])], (-1, 2)))
            for key in ("natural_frequencies_hz", "damping_ratios"))

    @property
    def json(self) -> str:
        """The JSON of `momentid identify --format json`, as text."""
        return _json_text(self._dict)

    def jtest(self) -> Optional[tuple]:
        """(J, p-value, degrees of freedom) of Hansen's test that the moment equations hold at
        the estimate; None when it was not computed (least squares, or no more equations than
        parameters)."""
        if self.jval is None:
            return None
        return self.jval, self.diagnostics["j_pvalue"], self.diagnostics["j_dof"]

    def summary(self) -> Summary:
        """The text report: the estimates (both, when optimally weighted), the identified
        model and the diagnostics, as a Summary (a str that prints as the report)."""
        return Summary(self.text, self)

    def _identified_model(self):
        if self.model is None:
            from . import UsageError
            raise UsageError("model: a result read from its JSON does not hold its model: give "
                             "IdentifyResult(text, value, model) the Model")
        return self.model

    def simulate(self, **options):
        """momentid.simulate(model, the estimates, **options): the identified model under
        random inputs (samples=, inputs=, seed=, noise=, ...); a Record."""
        from . import simulate
        return simulate(self._identified_model(), self.estimates, **options)

    def predict(self, data, **options):
        """The identified model's response to the inputs of `data` (a record: a mapping of
        arrays with `t` and the model's inputs, or a data file's path), from its initial state,
        as momentid.simulate(model, the estimates, inputs=data, **options); a Record."""
        return self.simulate(inputs=data, **options)

    def validate(self, data=None, **options):
        """momentid.validate(model, data, the estimates, **options): the identified model
        simulated through the record's inputs and compared with it, a ValidateResult. Without
        `data`, the record identified, read with the record options it was identified with
        (columns, names, dt, center, ...); `options` add to them."""
        from . import validate
        if data is None:
            data, record_options = self._identified_record()
            options = {**record_options, **options}
        return validate(self._identified_model(), data, self, **options)

    def _identified_record(self):
        if self._record is None:
            from . import UsageError
            raise UsageError("data: a result read from its JSON does not hold its record: give "
                             "validate(data) the record")
        return self._record

    def _validated(self):
        if self._validation is None:
            self._validation = self.validate()
        return self._validation

    def _per_state(self, values: dict):
        if not self._labels:
            return values
        index = getattr(self._identified_record()[0], "index", None)
        rows = len(next(iter(values.values()))) if values else 0
        return _pandas().DataFrame(values, index=index if index is not None and
                                   len(index) == rows else None)

    @property
    def fittedvalues(self):
        """Per state the record shows, the identified model's response to the inputs of the
        record identified, from its initial state (validate()'s `simulated`)."""
        validation = self._validated()
        return self._per_state({name: validation.simulated[name] for name in validation.measured})

    @property
    def resid(self):
        """Per state the record shows, the record identified minus fittedvalues; NaN on the rows
        before each run's skip (validate()'s `compared` false)."""
        validation = self._validated()
        return self._per_state({
            name: _np.where(validation.compared, measured - validation.simulated[name], _np.nan)
            for name, measured in validation.measured.items()})

    def to_dict(self) -> dict:
        return _copy.deepcopy(self._dict)

    def plot_engineering(self, fig=None):
        """momentid.plots.plot_engineering(self, fig): the restoring force and the backbone
        with their 95% bands, as a matplotlib Figure."""
        from .plots import plot_engineering
        return plot_engineering(self, fig)

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        values = ", ".join(f"{name}={value:.6g}±{self.std_errors[name]:.2g}"
                           for name, value in self.estimates.items())
        return f"<momentid.IdentifyResult {self.status}: {values}>"


class SelectResult(IdentifyResult):
    """What select() found: the chosen model's IdentifyResult (its params, bse, jtest(), ...,
    and summary(), the whole text report of `momentid select`), and:

    selected, dropped: the candidates' names; ranking: the best subsets, each a dict with
      "selected", "criterion", "j", "dof" and "pvalue"; tests: per candidate, "candidate",
      "terms", "kept", "j_change" and "pvalue" (the difference-in-J test at the chosen subset);
      windows: the chosen candidates on narrower lag windows; selection_warnings;
      status: the selection's, "doubtful" when the chosen model's fit is ok but the structure
      is uncertain; uncertain: why (the library rejected, a close runner-up, terms that change
      with the lag window); runner_up: then the runner-up subset's
      "selected", "status" and "parameters" (as to_dict()'s), else None;
      validation: with select(validate=...), the best subsets on the second record, each a dict
      with "rank", "selected", "outputs" ({state: {"fit", "rms"}}) and "consistent" (else []).
    model_text: the chosen model as a model file; write_model(path) writes it.
    """

    def __init__(self, text: str, value: Union[str, dict], model_text: str = "",
                 labels: bool = False) -> None:
        from . import Model
        super().__init__(text, value, Model(model_text, "<selected>") if model_text else None,
                         labels)
        selection = self._dict["selection"]
        self.selected = list(self._dict["selected"])
        self.dropped = list(self._dict["dropped"])
        self.ranking = selection["ranking"]
        self.tests = selection["tests"]
        self.windows = selection["windows"]
        self.selection_warnings = selection["warnings"]
        self.uncertain = list(selection["uncertain"])
        self.runner_up = selection["runner_up"]
        self.validation = selection.get("validation", {}).get("subsets", [])
        self.model_text = model_text

    def write_model(self, path: Union[str, _os.PathLike]) -> None:
        """Writes the chosen model as a model file, for identify(), validate() and simulate()."""
        with open(path, "w", encoding="utf-8") as out:
            out.write(self.model_text)


class CheckResult:
    """What check() found: `channels` {name: statistics}, `identities` (with a model),
    `warnings`, `to_dict()` (the JSON of `momentid check --format json` as Python objects,
    `json` as text), and str() the report of `momentid check`."""

    def __init__(self, text: str, values: dict) -> None:
        self.text = text
        self._dict = values
        self.channels = values["channels"]
        self.identities = values["identities"]
        self.warnings = values["warnings"]

    @property
    def json(self) -> str:
        """The JSON of `momentid check --format json`, as text."""
        return _json_text(self._dict)

    def to_dict(self) -> dict:
        return _copy.deepcopy(self._dict)

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        return (f"<momentid.CheckResult {self._dict['rows']} rows, "
                f"{len(self.warnings)} warnings>")


class ValidateResult:
    """What validate() found: `fit` {output: percent}, `rms` {output: error}, `warnings`,
    `centered` {variable: the mean removed} (validate(center=...)),
    `to_dict()` (the JSON of `momentid validate --format json`) and str() its report; and the
    series compared, every run's rows one run after the other (numpy arrays):

    t: the sample times; run: each row's run (None for a record of one run);
    simulated: {state: the model's response}, every state; measured: {output: the record's
      values}, the states the record has; inputs: {input: the record's values that drove it};
    compared: True for the rows the fit and the errors are over (those past each run's skip).

    sensitive: whether nearby trajectories separate to the spread within the record (then the
    trajectory cannot be reproduced and the statistics judge the model); `sensitivity` its
    figures (dict: time_to_spread, lyapunov, ...); noise_band: for a trajectory that can be
    reproduced, whether each output's error is what the inputs' noise and the estimates'
    errors leave (dict: compared, input_noise, with_errors, outputs {name: error, simulations,
    estimates, limit, inside}); consistent: the overall verdict as a boolean, `verdict` in words; `statistics`: None, or the statistics compared (dict with
    `checks`, each with output, kind (psd, distribution, crossings, prediction, bias), distance,
    limit, inside and the arrays at, measured, mean, low, high).

    The fit of output y is 100 (1 - |e| / |m - mean(m)|) over the compared rows, with
    m = measured[y][compared] and e = m - simulated[y][compared]. plot() draws the series and
    the statistics (momentid.plots).
    """

    def __init__(self, text: str, value: dict, series: dict) -> None:
        self.text = text
        self._dict = value
        outputs = self._dict["outputs"]
        self.fit = {name: o["fit_percent"] for name, o in outputs.items()}
        self.rms = {name: o["rms"] for name, o in outputs.items()}
        self.warnings = list(self._dict["warnings"])
        self.centered = dict(self._dict.get("centered", {}))
        self.sensitive = bool(self._dict["sensitive"])
        self.consistent = bool(self._dict["consistent"])
        self.verdict = self._dict["verdict"]
        self.sensitivity = dict(self._dict["sensitivity"])
        self.noise_band = self._dict["noise_band"]
        self.statistics = self._dict["statistics"]
        self.t = series["t"]
        self.run = series["run"]
        self.simulated = dict(series["simulated"])
        self.measured = dict(series["measured"])
        self.inputs = dict(series["inputs"])
        self.compared = series["compared"]

    @property
    def json(self) -> str:
        """The JSON of `momentid validate --format json`, as text."""
        return _json_text(self._dict)

    def to_dict(self) -> dict:
        return _copy.deepcopy(self._dict)

    def plot(self, fig=None, statistics: Optional[bool] = None):
        """momentid.plots.plot_validation(self, fig, statistics): the series compared and the
        statistics, as a matplotlib Figure."""
        from .plots import plot_validation
        return plot_validation(self, fig, statistics)

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        fits = ", ".join(f"{name} {value:.2f}%" for name, value in self.fit.items())
        return f"<momentid.ValidateResult fit {fits}>"
