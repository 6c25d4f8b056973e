"""Identify the parameters of ODE models from random vibration data, in Python.

momentid derives the moment equations of a polynomial ODE model (a linear system in its
unknown parameters whose entries are moments of the data), estimates the moments from a record
in one pass, and solves for the parameters with standard errors and diagnostics. This module
runs the C++ library on the arrays you already hold: no files, no parsing.

Example::

    import momentid
    model = momentid.Model.from_file("models/duffing.mom")
    record = momentid.simulate(model, {"c": 0.5, "k": 4, "eps": 1}, samples=200_000,
                               inputs={"x": "ma:K=10,w=0.1,sigma=20"})
    result = momentid.identify(model, record)
    print(result.summary())            # the table, the identified model, the diagnostics
    result.param_names                 # ['c', 'k', 'eps']: the order of the arrays
    result.params, result.bse          # numpy arrays (pandas Series for a DataFrame)
    result.cov_params(), result.conf_int(alpha=0.01)
    result.estimates["k"], result.std_errors["k"], result.ci95["k"]    # by name

The functions mirror the commands of the `momentid` program (docs/cli/index.md): the same
options, spelled as keyword arguments, give the same numbers.
"""

from __future__ import annotations

import copy as _copy
import functools as _functools
import os as _os
import warnings as _warnings
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as _np

__all__ = [
    "Model", "Equations", "Record", "Fit", "IdentifyResult", "SelectResult", "CheckResult",
    "ValidateResult", "identify", "select", "check", "simulate", "validate",
    "Error", "ModelError", "DataError", "UsageError", "MomentidWarning", "__version__",
]


class Error(Exception):
    """Every error momentid reports. Located errors carry `file`, `line`, `column` and
    `source_line` (the text of that line); the message is `file:line:col: what was found and
    what was expected`, as the command line prints it."""

    file: Optional[str] = None
    line: Optional[int] = None
    column: Optional[int] = None
    source_line: Optional[str] = None


class ModelError(Error, ValueError):
    """A model that does not parse, or that parses but means nothing momentid can use."""


class DataError(Error, ValueError):
    """Data that cannot be used: a missing column, a value that is not a finite number, too few
    rows, non-uniform time steps; located at the row (line) and column."""


class UsageError(Error, ValueError):
    """An option out of range, or naming something the model or data do not have. The message
    starts with the keyword argument it concerns: `fix: 'k2' is not a parameter of model ...`."""


class MomentidWarning(UserWarning):
    """A warning of the library's, such as a simulation step too coarse for the dynamics."""


from . import _momentid  # noqa: E402  (the exceptions above must exist before it is used)

__version__: str = _momentid.__version__

from ._options import Monomials, _takes_options  # noqa: E402
from ._results import (CheckResult, Fit, IdentifyResult, SelectResult,  # noqa: E402
                       ValidateResult, _json_text)

PathLike = Union[str, "_os.PathLike[str]"]


def _monomials(values: Monomials) -> Optional[str]:
    # The library reads the command line's list: monomials separated by commas.
    if values is None or isinstance(values, str):
        return values
    return ", ".join(str(v) for v in values)


def _older_keywords(function):
    """Accepts for one more release the keywords as the last release spelled them, each with a
    DeprecationWarning: rename= (now columns=, in the same direction, model variable to data
    column), columns= with a list of a 2-D array's column names (now names=) and
    extrapolate="dt" (now True)."""

    def deprecated(old, new):
        # Pointing at the caller, past this function and the wrapper.
        _warnings.warn(f"{function.__name__}(): {old} is deprecated and will be removed in the "
                       f"next release; use {new}", DeprecationWarning, stacklevel=3)

    def move(kwargs, old, new):
        if kwargs.get(new) is not None:
            raise UsageError(f"{old} and {new} say the same: give {new} only")
        kwargs[new] = kwargs.pop(old)

    @_functools.wraps(function)
    def wrapper(*args, **kwargs):
        columns = kwargs.get("columns")
        if columns is not None and not hasattr(columns, "keys"):
            deprecated("columns= with a list of column names", "names=")
            move(kwargs, "columns", "names")
        if "rename" in kwargs:
            deprecated("rename=", "columns= (model variable: data column, as --columns)")
            move(kwargs, "rename", "columns")
        if kwargs.get("extrapolate") == "dt":
            deprecated('extrapolate="dt"', "extrapolate=True")
            kwargs["extrapolate"] = True
        return function(*args, **kwargs)

    return wrapper


class Model:
    """A model in the momentid language: states, inputs, parameters and polynomial equations.

    `Model(text)` parses a model given as text; `Model.from_file(path)` reads a file. Errors
    raise ModelError with the place (`file`, `line`, `column`).

    Example::

        model = momentid.Model('''
            state y, v
            input x
            param c, k, eps
            y' = v
            v' = -c*v - k*y - eps*y^3 + x
        ''', name="duffing")
    """

    def __init__(self, text: str, name: str = "<string>") -> None:
        self._model = _momentid.Model(text, name)

    @classmethod
    def from_file(cls, path: PathLike) -> "Model":
        """Reads a model file (`models/duffing.mom`)."""
        model = cls.__new__(cls)
        model._model = _momentid.Model._from_file(_os.fspath(path))
        return model

    name = property(lambda self: self._model.name, doc="The model's name.")
    title = property(lambda self: self._model.title, doc="The model's title, or ''.")
    states = property(lambda self: list(self._model.states), doc="State names, in order.")
    inputs = property(lambda self: list(self._model.inputs), doc="Input names, in order.")
    parameters = property(lambda self: list(self._model.parameters),
                          doc="Parameter names, in declaration order.")
    nominal = property(lambda self: dict(self._model.nominal),
                       doc="Each parameter's nominal value (None when the file gives none).")
    fixed = property(lambda self: list(self._model.fixed),
                     doc="Parameters declared `fixed` in the model (known, not estimated).")

    def derive(self, multipliers: Monomials = None, degree: Optional[int] = None,
               lags: Optional[tuple[int, int]] = None, instruments: Monomials = None,
               measured: Optional[Sequence[str]] = None) -> "Equations":
        """The moment equations, as `momentid derive` prints them.

        multipliers: monomials in the states to multiply every equation by (["y", "v", "y^3"],
        or as the command line spells them, "y, v, y^3");
        degree: every monomial in the states of degree 1..degree; neither: the model's own or
        the automatic choice. lags=(first, last): the lagged equations for records that lack
        some states, with `instruments` and the `measured` channels.
        """
        text, latex, value, count = _momentid._derive(
            self._model, _options(multipliers=_monomials(multipliers), degree=degree, lags=lags,
                                  instruments=_monomials(instruments), measured=measured))
        return Equations(text, latex, value, count)

    def __repr__(self) -> str:
        parts = [f"states {', '.join(self.states)}"]
        if self.inputs:
            parts.append(f"inputs {', '.join(self.inputs)}")
        parts.append(f"parameters {', '.join(self.parameters) or '(none)'}")
        return f"<momentid.Model {self.name}: {'; '.join(parts)}>"


class Equations:
    """Moment equations: `.text` (as the command prints them), `.latex`, `.to_dict()` (the JSON
    of `derive --format json` as Python objects), `.json` (that JSON as text) and `len()` the
    number of equations. Shown as LaTeX in a notebook."""

    def __init__(self, text: str, latex: str, value: dict, count: int) -> None:
        self.text, self.latex = text, latex
        self._dict = value
        self._count = count

    @property
    def json(self) -> str:
        return _json_text(self._dict)

    def to_dict(self) -> dict:
        return _copy.deepcopy(self._dict)

    def __len__(self) -> int:
        return self._count

    def __str__(self) -> str:
        return self.text

    __repr__ = __str__

    def _repr_latex_(self) -> str:
        return self.latex


class Record(dict):
    """The columns simulate() returns ({name: array}), with the `metadata` of the file the
    program would write ({"dt": "0.01", "input-hold": "zoh", ...}), which identify(), check()
    and validate() read as they read a file's: a held input is known to be held, a record
    simulated without noise takes the zero-lag equations as its file would."""

    metadata: dict

    def __init__(self, columns: dict, metadata: dict) -> None:
        super().__init__(columns)
        self.metadata = metadata

    def to_frame(self):
        """The columns as a pandas DataFrame whose attrs["momentid"] holds the metadata, which
        identify(), check() and validate() read from it as from the Record."""
        import pandas as pd

        frame = pd.DataFrame(dict(self))
        frame.attrs["momentid"] = dict(self.metadata)
        return frame


@_older_keywords
@_takes_options("identify")
def identify(model: Union[Model, PathLike], data: Any, **options: Any) -> IdentifyResult:
    """Estimates the model's parameters from a record, as `momentid identify MODEL DATA`.

    model: a Model or a model file's path.
    data: a mapping of column name to 1-D array (a dict of numpy arrays, a pandas DataFrame),
      a 2-D array with `names` naming its columns, a data file's path, or a list of paths
      (read one after the other as one record whose files are never joined). A Record's
      metadata, or a DataFrame's attrs["momentid"], are read as a file's `# momentid:` lines:
      arrays without them are taken as measured (see the result's `why`).
      Columns are named as in a file: the model's variables, `t` for the sample times and `run`
      to separate records. float64 arrays are read in place, strided ones too; other real
      dtypes are converted. Without a `t` column give `dt`. A path may name a CSV, binary,
      .npy, .mat or HDF5 file (`names` for a 2-D .npy array's columns too, `dt_from` for the
      interval stored in a .mat or HDF5 file: "Ts", or "1/fs" for a rate).

    The options are the command line's (docs/cli/identify.md), as keyword arguments; None (or
    False) leaves an option at its default. The result is the same to the last bit with any
    number of threads.
    <options>

    Returns an IdentifyResult: params, bse, cov_params(), conf_int(alpha), summary(), the
    least-squares fit as .ls beside an optimally weighted one, and to_frame() for pandas. Raises
    ModelError, DataError or UsageError with the command line's messages, each naming its
    keyword. The GIL is released during the pass over the data.
    """
    model = _model_of(model)
    record = _record_options(options)
    source, name, metadata, keep, options["names"] = _data_of(data, options.get("names"))
    text, value = _momentid._identify(model._model, source, name, metadata, _options(**options))
    del keep
    result = IdentifyResult(text, value, model, _is_frame(data))
    result._record = (data, record)
    return result


@_takes_options("select")
def select(model: Union[Model, PathLike], data: Any, **options: Any) -> SelectResult:
    """Chooses the terms of a library model that the record wants, as `momentid select MODEL
    DATA` (docs/cli/select.md): the model's candidates (`candidate` and `library` statements)
    scored on the lagged equations of one pass, and the chosen model identified.

    `data` as for identify(). The options are identify()'s for the record and the lagged
    equations, and select's own; None leaves an option at its default. validate: a second record
    (a path or a mapping of columns) on which the best three subsets, each identified on
    `data`, are simulated through its inputs and compared with it, as validate() does.
    <options>

    Returns a SelectResult: the chosen model's IdentifyResult (params, bse, jtest(), ...) with
    selected and dropped (candidate names), ranking, tests, windows, selection_warnings,
    model_text (the chosen model as a model file) and write_model(path). Raises ModelError for a
    model without candidates, and what identify() raises.
    """
    model = _model_of(model)
    record = _record_options(options)
    source, name, metadata, keep, options["names"] = _data_of(data, options.get("names"))
    validate = options.pop("validate", None)
    second = (None, "", {}, None) if validate is None else _data_of(validate, None)[:4]
    text, value, model_text = _momentid._select(model._model, source, name, metadata,
                                                _options(**options), *second[:3])
    del keep, second
    result = SelectResult(text, value, model_text, _is_frame(data))
    result._record = (data, record)
    return result


@_older_keywords
def check(data: Any, model: Union[None, Model, PathLike] = None, *,
          columns: Optional[Mapping[str, str]] = None, names: Optional[Sequence[str]] = None,
          dt: Optional[float] = None, lags: Optional[int] = None,
          input_hold: Optional[str] = None, missing: Optional[str] = None,
          skip_rows: Optional[int] = None, decimal: Optional[str] = None,
          dt_from: Optional[str] = None, threads: Optional[int] = None) -> CheckResult:
    """Whether a record suits the method, as `momentid check DATA [MODEL]`: each channel's
    mean, variance and autocorrelations (`lags` of them), warnings, and with a model the sample
    violations of its stationarity identities. `data` and the options as for identify()."""
    model = None if model is None else _model_of(model)
    source, name, metadata, keep, names = _data_of(data, names)
    options = _options(lags=lags, input_hold=input_hold, columns=columns,
                       dt=dt, missing=missing, skip_rows=skip_rows, decimal=decimal,
                       names=names, dt_from=dt_from, threads=threads)
    text, values = _momentid._check(None if model is None else model._model, source, name,
                                    metadata, options)
    del keep
    return CheckResult(text, values)


def simulate(model: Union[Model, PathLike], params: Optional[Mapping[str, float]] = None, *,
             samples: int = 10000, dt: Optional[float] = None, inputs: Any = None,
             seed: int = 1, runs: int = 1, burn_in: int = 10000,
             noise: Optional[Mapping[str, float]] = None,
             observe: Optional[Sequence[str]] = None, path: Optional[PathLike] = None,
             format: Optional[str] = None, interpolation: Optional[str] = None,
             substeps: Optional[int] = None,
             columns: Optional[Mapping[str, str]] = None) -> Optional[Record]:
    """Simulates the model with known parameters, as `momentid simulate`.

    params: {parameter: value}, the rest at the model's nominal values.
    inputs: {input: process} such as "ma:K=10,w=0.1,sigma=20", "ma:T=0.1", "ou:tau=0.5" or
      "multisine:f1=0.5,f2=5,lines=10" (default "ma:K=10,w=0.1"); or a record (a mapping of
      arrays with the model's inputs and `t`, or a data file's path) whose inputs drive the
      model, as `simulate --input-file` does: each run starts from the record's initial state,
      `interpolation` ("zoh", "foh", "cubic", "sinc"), `substeps` and `columns` ({model
      variable: the record's column}) as for validate().
    dt: the step (default 0.01; for a record, its own sample interval).
    noise: {channel: relative level} of white measurement noise. observe: the channels to
      return (default: states, then inputs).

    Returns a Record, {"t": array, channel: array, ..., "run": array (with several runs)},
    the same numbers the program writes, with the file's metadata; or, with `path`, writes that
    file and returns None: `format` "csv", "bin", "npy", "mat", "mat73" or "h5", by default the
    one the path's extension names (.csv, .txt, .bin, .npy, .mat, .h5, .hdf5; CSV without an
    extension; another extension, or a format the name contradicts, is a UsageError). A .npy
    file keeps neither names nor metadata, said in a MomentidWarning with the options that read
    it back; a step too coarse for the dynamics gives one too.
    """
    model = _model_of(model)
    if inputs is not None and (isinstance(inputs, (str, _os.PathLike)) or
                               any(not isinstance(v, str) for v in inputs.values())):
        source, name, metadata, keep, _ = _data_of(inputs, None)
        options = _options(params=_numbers(params), interpolation=interpolation,
                           substeps=substeps, dt=dt, columns=columns,
                           path=None if path is None else _os.fspath(path), format=format)
        columns, metadata, warnings = _momentid._replay(model._model, source, name, metadata,
                                                        options)
        del keep
    else:
        options = _options(params=_numbers(params), samples=samples, dt=dt,
                           inputs=dict(inputs) if inputs else None, seed=seed, runs=runs,
                           burn_in=burn_in, noise=noise, observe=observe,
                           path=None if path is None else _os.fspath(path), format=format)
        columns, metadata, warnings = _momentid._simulate(model._model, options)
    for warning in warnings:
        _warnings.warn(warning, MomentidWarning, stacklevel=2)
    return None if columns is None else Record(columns, metadata)


@_older_keywords
def validate(model: Union[Model, PathLike], data: Any,
             params: Union[None, Mapping[str, float], IdentifyResult] = None, *,
             columns: Optional[Mapping[str, str]] = None, names: Optional[Sequence[str]] = None,
             dt: Optional[float] = None, skip: Optional[int] = None, lags: Optional[int] = None,
             interpolation: Optional[str] = None, substeps: Optional[int] = None,
             plot: Optional[PathLike] = None, missing: Optional[str] = None,
             skip_rows: Optional[int] = None, decimal: Optional[str] = None,
             dt_from: Optional[str] = None,
             center: Union[None, str, Sequence[str]] = None) -> ValidateResult:
    """Simulates the model through the record's inputs and compares its outputs, as
    `momentid validate`: per measured state the RMS error, the fit (100 (1 - |y - ŷ| / |y - ȳ|)
    %), the drift and the residual correlation checks.

    params: {parameter: value} or an IdentifyResult (its estimates); the rest at the nominal
    values. skip: rows left out at the start of each run (default: until the initial state is
    forgotten). interpolation: "zoh", "foh", "cubic" or "sinc". plot: an SVG file to draw.
    center: variables (or "all") whose mean is removed before simulating and comparing.
    `data` and the other options as for identify().

    Returns a ValidateResult: the fit and errors per output, and the series compared (t, the
    simulated and measured outputs, the inputs, and which rows were compared).
    """
    model = _model_of(model)
    origin = "the model's nominal values"
    covariance = None
    if isinstance(params, IdentifyResult):
        # The estimates' covariance widens the noise band, as `--estimates FILE` does.
        covariance = params.diagnostics.get("covariance")
        params, origin = params.estimates, "the estimates of identify()"
    elif params:
        origin += " and params"
    source, name, metadata, keep, names = _data_of(data, names)
    center = _channel_lists(model, center)
    options = _options(params=_numbers(params), parameters_from=origin, skip=skip, lags=lags,
                       interpolation=interpolation, substeps=substeps, columns=columns,
                       dt=dt,
                       plot=None if plot is None else _os.fspath(plot), missing=missing,
                       skip_rows=skip_rows, decimal=decimal, names=names, dt_from=dt_from,
                       center=center, covariance=covariance)
    text, value, series = _momentid._validate(model._model, source, name, metadata, options)
    del keep
    return ValidateResult(text, value, series)


# --- helpers ----------------------------------------------------------------------------------

def _channel_lists(model: Model, center: Union[None, str, Sequence[str]]) -> Optional[list]:
    """`center` as a list of variables: "all" is every state and input."""
    if isinstance(center, str):
        return model.states + model.inputs if center == "all" else [center]
    return None if center is None else list(center)


# The options of identify() and select() that say how the record is read, which validate()
# takes as well: what IdentifyResult.validate() reads the record identified with.
_RECORD_OPTIONS = ("columns", "names", "dt", "missing", "skip_rows", "decimal", "dt_from",
                   "center")


def _record_options(options: dict) -> dict:
    out = {key: options[key] for key in _RECORD_OPTIONS if options.get(key) is not None}
    if options.get("input_hold") == "zoh":
        out["interpolation"] = "zoh"  # held inputs are replayed held
    return out


def _options(**options: Any) -> dict:
    return {key: value for key, value in options.items() if value is not None}


def _numbers(values: Optional[Mapping[str, float]]) -> Optional[dict]:
    # repr() of a float reads back exactly, which is how the library reads the value.
    return None if values is None else {name: repr(float(v)) for name, v in values.items()}


def _model_of(model: Union[Model, PathLike]) -> Model:
    if isinstance(model, Model):
        return model
    if isinstance(model, (str, _os.PathLike)):
        return Model.from_file(model)
    raise TypeError(f"model: expected a momentid.Model or a path, found {type(model).__name__}")


def _column(name: str, values: Any) -> _np.ndarray:
    array = _np.asarray(values)
    if array.dtype.kind not in "fiub":
        raise UsageError(f"column '{name}': expected real numbers, found dtype {array.dtype}")
    if array.ndim != 1:
        raise UsageError(f"column '{name}': expected a one-dimensional array, found shape "
                         f"{array.shape}")
    # Read in place: float64 with a stride of whole values, forwards (or 0, a broadcast).
    if array.dtype != _np.float64 or array.strides[0] % 8 != 0 or array.strides[0] < 0:
        array = _np.ascontiguousarray(array, dtype=_np.float64)
    return array


def _is_frame(data: Any) -> bool:
    """Whether `data` is a pandas DataFrame: the results are then labelled, as statsmodels'."""
    return type(data).__module__.split(".")[0] == "pandas"


def _data_of(data: Any, names: Optional[Sequence[str]]):
    """The record as the compiled part takes it: a path, or [(name, float64 array)] with a name
    for messages and metadata; the last but one item keeps converted arrays alive, the last is
    `names` when they are for the file to read (a 2-D .npy array's columns)."""
    if isinstance(data, (str, _os.PathLike)):
        return _os.fspath(data), "", {}, None, names
    if (isinstance(data, (list, tuple)) and data
            and all(isinstance(d, (str, _os.PathLike)) for d in data)):
        # Several files: one record whose files are never joined.
        return [_os.fspath(d) for d in data], "", {}, None, names
    # A Record's metadata, or a DataFrame's attrs["momentid"] (Record.to_frame()).
    metadata = getattr(data, "metadata", None)
    if metadata is None:
        metadata = getattr(data, "attrs", {}).get("momentid") if hasattr(data, "attrs") else None
    metadata = {str(k): str(v) for k, v in (metadata or {}).items()}
    if isinstance(data, _np.ndarray) and data.ndim == 2:
        if names is None or len(names) != data.shape[1]:
            raise UsageError(f"names: a 2-D array of {data.shape[1]} columns needs as many "
                             f"names, found {0 if names is None else len(names)}")
        pairs = [(str(n), _column(str(n), data[:, k])) for k, n in enumerate(names)]
        return pairs, "<array>", metadata, pairs, None
    if names is not None:
        raise UsageError("names: only for a 2-D array or file; a mapping names its own columns")
    if not hasattr(data, "keys") or not hasattr(data, "__getitem__"):
        raise TypeError("data: expected a mapping of column names to arrays, a 2-D array with "
                        f"names=, or a path, found {type(data).__name__}")
    pairs = [(str(n), _column(str(n), data[n])) for n in data.keys()]
    return pairs, "<arrays>", metadata, pairs, None
