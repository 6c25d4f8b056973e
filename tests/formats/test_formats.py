"""The array-file readers (.npy, .mat levels 5 and 7.3, HDF5) and `momentid convert`.

One simulated Duffing record, written as CSV by `simulate`, is written again independently by
numpy, scipy.io and h5py and by `momentid convert`; every copy must give the same estimates to
1e-12 relative. Bad, truncated and odd files must each draw a message and exit status 2, never a
crash or a hang; the HDF5 reader's memory must not grow with the file.

Run as: MOMENTID=build/momentid python3 -m pytest -q -p no:cacheprovider tests/formats
"""

import json
import os
import shutil
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io

ROOT = Path(__file__).resolve().parents[2]
MOMENTID = Path(os.environ.get("MOMENTID", ROOT / "build" / "momentid")).resolve()
MODEL = ROOT / "models" / "duffing.mom"
# A guard against a hang, not a measure of speed: under the sanitizers, identify on the 4e6-row
# file of test_hdf5_memory_stays_flat took 83 s on a busy 2-core machine (7 s without them).
TIMEOUT = 600
SAMPLES = 50000
NAMES = ["t", "y", "v", "x"]
TIME = shutil.which("time", path="/usr/bin")


def run(*args, cwd=None, timeout=TIMEOUT):
    """Runs the program; a hang fails the test through TimeoutExpired."""
    if args and args[0] == "identify":
        # Most copies lose simulate's metadata, which takes the reference (noise-free) record to
        # the zero-lag equations: every identification here asks for them.
        args = (*args, "--method", "zero-lag")
    return subprocess.run(
        [str(MOMENTID), *map(str, args)],
        cwd=cwd,
        capture_output=True,
        text=True,
        errors="replace",
        timeout=timeout,
        env={**os.environ, "LC_ALL": "C"},
    )


def first_line(text):
    return text.splitlines()[0] if text else ""


def not_a_crash(proc):
    assert proc.returncode >= 0, f"killed by signal {-proc.returncode}: {proc.stderr[-2000:]}"


def identify(data, *options, cwd=None):
    proc = run("identify", MODEL, data, "--format", "json", *options, cwd=cwd)
    not_a_crash(proc)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def estimates(report):
    return {
        name: (p["estimate"], p["std_error"]) for name, p in report["parameters"].items()
    }


def assert_same_estimates(got, reference):
    assert set(got) == set(reference)
    for name, (estimate, error) in reference.items():
        assert got[name][0] == pytest.approx(estimate, rel=1e-12, abs=0), name
        assert got[name][1] == pytest.approx(error, rel=1e-12, abs=0), name


def read_csv(path):
    """The `# momentid:` lines and the columns by name, every number parsed with float()."""
    metadata, header, rows = [], None, []
    with open(path) as f:
        for line in f:
            line = line.rstrip("\n")
            if header is None:
                if line.startswith("#"):
                    if line.startswith("# momentid:"):
                        metadata.append(line)
                    continue
                header = line.split(",")
                continue
            rows.append([float(field) for field in line.split(",")])
    values = np.array(rows, dtype=np.float64)
    return metadata, {name: values[:, k].copy() for k, name in enumerate(header)}, header


def metadata_pairs(lines):
    return sorted(pair for line in lines for pair in line[len("# momentid:"):].split())


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """rec.csv from `simulate`, its columns and metadata, and the reference estimates."""
    d = tmp_path_factory.mktemp("record")
    proc = run(
        "simulate", MODEL, "--samples", SAMPLES, "--seed", 4,
        "--input", "ma:K=10,w=0.1,sigma=20", "-o", d / "rec.csv",
    )
    assert proc.returncode == 0, proc.stderr
    metadata, columns, header = read_csv(d / "rec.csv")
    assert header == NAMES
    assert len(columns["t"]) == SAMPLES
    assert any("input-hold=zoh" in line for line in metadata)
    report = identify(d / "rec.csv")
    assert report["diagnostics"]["samples"] == SAMPLES
    assert report["diagnostics"]["input_hold"] == "zoh"
    return {
        "dir": d,
        "csv": d / "rec.csv",
        "metadata": metadata,
        "columns": columns,
        "reference": estimates(report),
    }


def matrix(columns, names=NAMES):
    return np.column_stack([columns[n] for n in names])


# --- 1. The same estimates through every reader ------------------------------------------------
# Each builder writes its files into `d` and returns the arguments that read them (run in `d`).
# Files without momentid's metadata get --input-hold zoh, which the CSV file's metadata says.


def npy_c_order(d, c, csv):
    array = np.ascontiguousarray(matrix(c), dtype="<f8")
    np.save(d / "rec.npy", array)
    return ["rec.npy", "--names", "t,y,v,x", "--input-hold", "zoh"]


def npy_fortran_big_endian(d, c, csv):
    array = np.asfortranarray(matrix(c).astype(">f8"))
    np.save(d / "rec.npy", array)
    with open(d / "rec.npy", "rb") as f:
        version = np.lib.format.read_magic(f)
        assert version == (1, 0)
        shape, fortran, dtype = np.lib.format.read_array_header_1_0(f)
    assert (shape, fortran, dtype.str) == ((SAMPLES, 4), True, ">f8")
    return ["rec.npy", "--names", "t,y,v,x", "--input-hold", "zoh"]


def npy_one_file_per_channel(d, c, csv):
    for name in NAMES:
        np.save(d / f"{name}.npy", c[name])
    return ["y.npy", "--columns", "v=v.npy,x=x.npy", "--dt", "0.01", "--input-hold", "zoh"]


def npy_one_file_per_channel_with_t(d, c, csv):
    for name in NAMES:
        np.save(d / f"{name}.npy", c[name])
    return ["y.npy", "--columns", "v=v.npy,x=x.npy,t=t.npy", "--input-hold", "zoh"]


def mat5_vectors(d, c, csv):
    scipy.io.savemat(d / "rec.mat", {n: c[n] for n in NAMES})
    return ["rec.mat", "--input-hold", "zoh"]


def mat5_compressed_matrix_with_ts(d, c, csv):
    scipy.io.savemat(
        d / "rec.mat", {"V": matrix(c, ["y", "v", "x"]), "Ts": 0.01}, do_compression=True
    )
    return [
        "rec.mat", "--columns", "y=V[:, 0],v=V[:, 1],x=V[:, 2]", "--dt-from", "Ts",
        "--input-hold", "zoh",
    ]


def mat5_rate_without_t(d, c, csv):
    scipy.io.savemat(d / "rec.mat", {"y": c["y"], "v": c["v"], "x": c["x"], "fs": 100.0})
    return ["rec.mat", "--dt-from", "1/fs", "--input-hold", "zoh"]


def hdf5_group_by_h5py(d, c, csv):
    with h5py.File(d / "rec.h5", "w") as f:
        group = f.create_group("run1")
        for name in ("y", "v", "x"):
            group.create_dataset(name, data=c[name])
        f.attrs["dt"] = 0.01
    return ["rec.h5", "--columns", "y=/run1/y,v=/run1/v,x=/run1/x", "--input-hold", "zoh"]


def hdf5_rate_attribute(d, c, csv):
    with h5py.File(d / "rec.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[name] = c[name]
        f.attrs["Fs"] = np.int32(100)
    return ["rec.h5", "--input-hold", "zoh"]


def hdf5_wf_increment_on_datasets(d, c, csv):
    with h5py.File(d / "rec.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[name] = c[name]
            f[name].attrs["wf_increment"] = 0.01
    return ["rec.h5", "--input-hold", "zoh"]


def mat5_integer_rate(d, c, csv):
    scipy.io.savemat(d / "rec.mat", {"y": c["y"], "v": c["v"], "x": c["x"],
                                     "sample_rate": np.int32(100), "fs": 100.0})
    return ["rec.mat", "--input-hold", "zoh"]


def converted(name, extra_convert=(), extra_read=()):
    def build(d, c, csv):
        proc = run("convert", csv, name, *extra_convert, cwd=d)
        assert proc.returncode == 0, proc.stderr
        if name.endswith(".npy"):
            assert proc.stderr == (
                f"momentid: note: a .npy file keeps neither column names nor metadata: "
                f"read {name} with --names t,y,v,x --input-hold zoh\n"
            )
        else:
            assert proc.stderr == ""
        return [name, *extra_read]

    return build


VARIANTS = {
    "npy-2d-c-order": npy_c_order,
    "npy-2d-fortran-big-endian": npy_fortran_big_endian,
    "npy-1d-per-channel": npy_one_file_per_channel,
    "npy-1d-per-channel-with-t": npy_one_file_per_channel_with_t,
    "mat5-vectors": mat5_vectors,
    "mat5-compressed-matrix-dt-from-Ts": mat5_compressed_matrix_with_ts,
    "mat5-dt-from-rate": mat5_rate_without_t,
    "hdf5-h5py-group": hdf5_group_by_h5py,
    "hdf5-rate-attribute": hdf5_rate_attribute,
    "hdf5-wf-increment-on-datasets": hdf5_wf_increment_on_datasets,
    "mat5-integer-rate-without-t": mat5_integer_rate,
    "convert-bin": converted("out.bin"),
    "convert-npy": converted("out.npy", extra_read=("--names", "t,y,v,x", "--input-hold", "zoh")),
    "convert-mat": converted("out.mat"),
    "convert-mat73": converted("out.mat", extra_convert=("--format", "mat73")),
    "convert-h5": converted("out.h5"),
}


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_same_estimates_through_every_reader(record, tmp_path, variant):
    args = VARIANTS[variant](tmp_path, record["columns"], record["csv"])
    report = identify(*args, cwd=tmp_path)
    assert report["diagnostics"]["samples"] == SAMPLES
    assert report["diagnostics"]["input_hold"] == "zoh"
    assert_same_estimates(estimates(report), record["reference"])


def test_convert_writes_the_exact_values(record, tmp_path):
    """The files `convert` writes, read by numpy, scipy and h5py, hold the CSV's values bit for
    bit (and the level 7.3 file is HDF5 under a MATLAB header)."""
    c, csv = record["columns"], record["csv"]
    for args in (["out.npy"], ["out.mat"], ["out.h5"], ["out73.mat", "--format", "mat73"]):
        proc = run("convert", csv, *args, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
    assert np.array_equal(np.load(tmp_path / "out.npy"), matrix(c))
    mat = scipy.io.loadmat(tmp_path / "out.mat")
    for name in NAMES:
        assert np.array_equal(mat[name].ravel(), c[name]), name
    assert mat["dt"].item() == 0.01
    with h5py.File(tmp_path / "out.h5", "r") as f:
        for name in NAMES:
            assert np.array_equal(f[name][()], c[name]), name
        assert f.attrs["dt"] == 0.01
        assert f.attrs["input-hold"] == b"zoh"
    assert (tmp_path / "out73.mat").read_bytes().startswith(b"MATLAB 7.3 MAT-file")
    with h5py.File(tmp_path / "out73.mat", "r") as f:
        for name in NAMES:
            assert np.array_equal(f[name][()].ravel(), c[name]), name
    assert not list(tmp_path.glob("*.partial-*"))


@pytest.mark.parametrize("target", ["out.mat", "out73.mat", "out.h5"])
def test_convert_carries_metadata_and_values_back_to_csv(record, tmp_path, target):
    extra = ["--format", "mat73"] if target == "out73.mat" else []
    proc = run("convert", record["csv"], target, *extra, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    proc = run("convert", target, "back.csv", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    metadata, columns, header = read_csv(tmp_path / "back.csv")
    if target == "out.mat":
        assert header == NAMES
    assert sorted(header) == sorted(NAMES)
    for name in NAMES:
        assert np.array_equal(columns[name], record["columns"][name]), name
    # The same key=value pairs (HDF5 keeps each as an attribute too; the lines are tested below).
    assert metadata_pairs(metadata) == metadata_pairs(record["metadata"])
    if target != "out.h5":
        assert metadata == record["metadata"]


def test_hdf5_round_trip_keeps_metadata_lines(record, tmp_path):
    assert run("convert", record["csv"], "out.h5", cwd=tmp_path).returncode == 0
    assert run("convert", "out.h5", "back.csv", cwd=tmp_path).returncode == 0
    metadata, _, _ = read_csv(tmp_path / "back.csv")
    assert metadata == record["metadata"]


# --- 2. Bad files -------------------------------------------------------------------------------
# Each builder writes into `d` and returns the arguments of `identify` (run in `d`) and the exact
# first line of standard error. The files are the first ROWS samples of the record.

ROWS = 5000
ANY_FLOAT = "expected a real double or single vector or matrix"
NPY_TYPES = "expected float64 or float32 ('<f8', '>f8', '<f4', '>f4')"
ONE_VALUE = "every channel needs one value per sample"
MISSING = "expected a number (a missing value? --missing drop-row or split-run passes over it)"


def cut(c, n=ROWS):
    return {name: c[name][:n].copy() for name in NAMES}


def with_nan(c):
    c = cut(c)
    c["y"][99] = np.nan  # sample 100
    return c


def save_mat(path, c, **changes):
    scipy.io.savemat(path, {**c, **changes})


def save_h5(path, c, **changes):
    with h5py.File(path, "w") as f:
        for name, values in {**c, **changes}.items():
            f[name] = values


def bad_mat_missing_variable(d, c):
    save_mat(d / "a.mat", cut(c))
    return (["a.mat", "--columns", "y=z"],
            "a.mat:1:1: missing variable 'z' for 'y' (the file has the variables: t, y, v, x)")


def bad_h5_missing_dataset(d, c):
    c = cut(c)
    with h5py.File(d / "a.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[f"run1/{name}"] = c[name]
        f.attrs["dt"] = 0.01
    return (["a.h5", "--columns", "y=/run1/z,v=/run1/v,x=/run1/x"],
            "a.h5:1:1: missing dataset 'run1/z' for 'y' "
            "(the file has the datasets: run1/v, run1/x, run1/y)")


def bad_h5_no_datasets(d, c):
    # What a writer that died before its first dataset leaves.
    with h5py.File(d / "a.h5", "w") as f:
        f.attrs["dt"] = 0.01
    return (["a.h5"], "a.h5:1:1: missing dataset 'y' (the file has no datasets)")


def bad_npy_missing_column(d, c):
    np.save(d / "a.npy", matrix(cut(c)))
    return (["a.npy", "--names", "t,y,v,q"],
            "a.npy:1:1: missing column 'x' (the file has the columns: t, y, v, q)")


def bad_mat_complex(d, c):
    save_mat(d / "a.mat", cut(c), y=cut(c)["y"] * (1 + 1j))
    return ["a.mat"], f"a.mat:1:1: variable 'y' holds complex double values: {ANY_FLOAT}"


def bad_mat_integer(d, c):
    save_mat(d / "a.mat", cut(c), y=(cut(c)["y"] * 1000).astype(np.int32))
    return ["a.mat"], f"a.mat:1:1: variable 'y' holds int32 values: {ANY_FLOAT}"


def bad_mat_text(d, c):
    save_mat(d / "a.mat", cut(c), y="displacement")
    return ["a.mat"], f"a.mat:1:1: variable 'y' holds char (text) values: {ANY_FLOAT}"


def bad_h5_integer(d, c):
    save_h5(d / "a.h5", cut(c), y=(cut(c)["y"] * 1000).astype(np.int32))
    return ["a.h5"], ("a.h5:1:1: dataset 'y' holds integer values: "
                      "expected floating-point values")


def bad_h5_complex(d, c):
    save_h5(d / "a.h5", cut(c), y=cut(c)["y"] * (1 + 1j))
    return ["a.h5"], ("a.h5:1:1: dataset 'y' holds compound (complex?) values: "
                      "expected floating-point values")


def bad_npy_integer(d, c):
    np.save(d / "a.npy", (matrix(cut(c)) * 1000).astype("<i8"))
    return ["a.npy", "--names", "t,y,v,x"], f"a.npy:1:1: the array holds '<i8' values: {NPY_TYPES}"


def bad_npy_complex(d, c):
    np.save(d / "a.npy", matrix(cut(c)).astype("<c16"))
    return (["a.npy", "--names", "t,y,v,x"],
            f"a.npy:1:1: the array holds '<c16' values: {NPY_TYPES}")


def bad_mat_lengths(d, c):
    save_mat(d / "a.mat", cut(c), v=cut(c)["v"][:-1])
    return ["a.mat"], (f"a.mat:1:1: variable 'v' has {ROWS - 1} values but 't' has {ROWS}: "
                       f"{ONE_VALUE}")


def bad_h5_lengths(d, c):
    save_h5(d / "a.h5", cut(c), v=cut(c)["v"][:-5])
    return ["a.h5"], (f"a.h5:1:1: dataset 'v' has {ROWS - 5} values but 't' has {ROWS}: "
                      f"{ONE_VALUE}")


def bad_npy_lengths(d, c):
    c = cut(c)
    np.save(d / "y.npy", c["y"])
    np.save(d / "v.npy", c["v"][:-1])
    np.save(d / "x.npy", c["x"])
    return (["y.npy", "--columns", "v=v.npy,x=x.npy", "--dt", "0.01"],
            f"y.npy:1:1: column 'v.npy' has {ROWS - 1} values but 'y' has {ROWS}: {ONE_VALUE}")


def bad_npy_nan(d, c):
    np.save(d / "a.npy", matrix(with_nan(c)))
    return (["a.npy", "--names", "t,y,v,x"], f"a.npy:100:2: column 'y': {MISSING}, found 'nan'")


def bad_mat_nan(d, c):
    save_mat(d / "a.mat", with_nan(c))
    return ["a.mat"], f"a.mat:100:2: variable 'y': {MISSING}, found 'nan'"


def bad_h5_nan(d, c):
    save_h5(d / "a.h5", with_nan(c))
    # HDF5 lists the datasets by name: t, v, x, y.
    return ["a.h5"], f"a.h5:100:4: dataset 'y': {MISSING}, found 'nan'"


def bad_h5_infinity(d, c):
    c = cut(c)
    c["x"][6] = np.inf
    save_h5(d / "a.h5", c)
    return ["a.h5"], "a.h5:7:3: dataset 'x': expected a finite number, found 'inf'"


def bad_directory(d, c):
    (d / "dir").mkdir()
    return ["dir"], "momentid: dir: cannot read the data file: Is a directory"


def bad_dt_from_mat(d, c):
    c = cut(c)
    save_mat(d / "a.mat", {"V": matrix(c, ["y", "v", "x"]), "Ts": 0.01})
    return (["a.mat", "--columns", "y=V[:, 0],v=V[:, 1],x=V[:, 2]", "--dt-from", "Tz"],
            "a.mat:1:1: --dt-from: no scalar named 'Tz' in the file")


def bad_dt_from_rate_h5(d, c):
    c = cut(c)
    save_h5(d / "a.h5", {n: c[n] for n in ("y", "v", "x")}, fs=np.float64(100.0))
    return (["a.h5", "--dt-from", "1/rate"],
            "a.h5:1:1: --dt-from: no scalar named 'rate' in the file")


def bad_dt_from_zero(d, c):
    save_mat(d / "a.mat", {n: cut(c)[n] for n in ("y", "v", "x")}, Ts=0.0)
    return (["a.mat", "--dt-from", "Ts"],
            "a.mat:1:1: --dt-from: 'Ts' is 0, which gives no positive sample interval")


NO_INTERVAL = "and the file has no time channel: give the sample interval with --dt"


def bad_rate_text_h5(d, c):
    save_h5(d / "a.h5", {n: cut(c)[n] for n in ("y", "v", "x")})
    with h5py.File(d / "a.h5", "a") as f:
        f.attrs["fs"] = "2 kHz"
    return ["a.h5"], f"a.h5:1:1: attribute 'fs' of the file holds the text '2 kHz', not a number, {NO_INTERVAL}"


def bad_rate_text_mat(d, c):
    save_mat(d / "a.mat", {n: cut(c)[n] for n in ("y", "v", "x")}, Fs="2 kHz")
    return ["a.mat"], f"a.mat:1:1: variable 'Fs' holds char (text) values, not one real number, {NO_INTERVAL}"


def bad_rate_zero_mat(d, c):
    save_mat(d / "a.mat", {n: cut(c)[n] for n in ("y", "v", "x")}, fs=0.0)
    return ["a.mat"], f"a.mat:1:1: variable 'fs' is 0, not a positive number, {NO_INTERVAL}"


def bad_rates_disagree_h5(d, c):
    save_h5(d / "a.h5", {n: cut(c)[n] for n in ("y", "v", "x")})
    with h5py.File(d / "a.h5", "a") as f:
        f.attrs["fs"] = 100.0
        f["y"].attrs["fs"] = 1000.0
    return ["a.h5"], ("a.h5:1:1: attribute 'fs' of dataset 'y' = 1000 disagrees with attribute "
                      "'fs' of the file = 100 (sample intervals 0.001 and 0.01)")


def bad_rate_disagrees_with_t_mat(d, c):
    save_mat(d / "a.mat", cut(c), wf_increment=0.001)
    return ["a.mat"], ("a.mat:2:1: time step 0.01 of column 't' disagrees with variable "
                       "'wf_increment' = 0.001")


def bad_float32_time_gap_h5(d, c):
    c = cut(c)
    keep = np.arange(ROWS) != 1234  # one sample lost
    save_h5(d / "a.h5", {n: c[n][keep] for n in ("y", "v", "x")}, t=c["t"][keep].astype(np.float32))
    # The float32 stamps are shown as they read, exactly.
    return ["a.h5"], ("a.h5:1235:1: non-uniform time step: 0.0200005 after 0.01 at "
                      "t = 12.350000381469727 (the steps before it average 0.01): give the sample "
                      "interval with --dt 0.01 if the samples are equally spaced")


def bad_names_too_few(d, c):
    np.save(d / "a.npy", matrix(cut(c)))
    return ["a.npy", "--names", "t,y,v"], "a.npy:1:1: --names gives 3 names for 4 columns"


def bad_names_too_many(d, c):
    np.save(d / "a.npy", matrix(cut(c)))
    return (["a.npy", "--names", "t,y,v,x,z"],
            "a.npy:1:1: --names gives 5 names for 4 columns")


BAD = {
    "mat-missing-variable": bad_mat_missing_variable,
    "hdf5-missing-dataset": bad_h5_missing_dataset,
    "hdf5-no-datasets": bad_h5_no_datasets,
    "npy-missing-column": bad_npy_missing_column,
    "mat-complex": bad_mat_complex,
    "mat-integer": bad_mat_integer,
    "mat-text": bad_mat_text,
    "hdf5-integer": bad_h5_integer,
    "hdf5-complex": bad_h5_complex,
    "npy-integer": bad_npy_integer,
    "npy-complex": bad_npy_complex,
    "mat-lengths": bad_mat_lengths,
    "hdf5-lengths": bad_h5_lengths,
    "npy-lengths": bad_npy_lengths,
    "npy-nan": bad_npy_nan,
    "mat-nan": bad_mat_nan,
    "hdf5-nan": bad_h5_nan,
    "hdf5-infinity": bad_h5_infinity,
    "directory": bad_directory,
    "dt-from-missing-mat": bad_dt_from_mat,
    "dt-from-missing-rate-hdf5": bad_dt_from_rate_h5,
    "dt-from-zero": bad_dt_from_zero,
    "hdf5-rate-text": bad_rate_text_h5,
    "mat-rate-text": bad_rate_text_mat,
    "mat-rate-zero": bad_rate_zero_mat,
    "hdf5-rates-disagree": bad_rates_disagree_h5,
    "mat-rate-disagrees-with-t": bad_rate_disagrees_with_t_mat,
    "hdf5-float32-time-gap": bad_float32_time_gap_h5,
    "npy-names-too-few": bad_names_too_few,
    "npy-names-too-many": bad_names_too_many,
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_file_is_a_located_error(record, tmp_path, case):
    args, expected = BAD[case](tmp_path, record["columns"])
    proc = run("identify", MODEL, *args, "--input-hold", "zoh", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout == ""
    assert first_line(proc.stderr) == expected
    # A column store has no source line to show: the message is the whole of standard error.
    assert proc.stderr == expected + "\n"


@pytest.mark.parametrize("case", ["npy-nan", "mat-nan", "hdf5-nan"])
def test_nan_is_accepted_with_missing_split_run(record, tmp_path, case):
    args, expected = BAD[case](tmp_path, record["columns"])
    first = expected.split(": ")[0]  # FILE:ROW:COLUMN of the NaN
    report = identify(*args, "--input-hold", "zoh", "--missing", "split-run", cwd=tmp_path)
    assert report["diagnostics"]["samples"] == ROWS - 1
    assert report["diagnostics"]["runs"] == 2
    assert (f"dropped 1 row with missing values (the first at {first}) and began a new run "
            f"at 1 place") in report["diagnostics"]["warnings"]
    proc = run("identify", MODEL, *args, "--input-hold", "zoh", "--missing", "split-run",
               cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert f"warning: dropped 1 row with missing values (the first at {first})" in proc.stdout


def test_convert_to_unknown_extension_is_a_usage_error(record, tmp_path):
    for name in ("out.xyz", "out"):
        proc = run("convert", record["csv"], name, cwd=tmp_path)
        assert proc.returncode == 1
        assert proc.stderr == (
            f"momentid: cannot tell the format of '{name}' from its name "
            "(.csv, .bin, .npy, .mat, .h5): give --format\n"
        )
        assert not (tmp_path / name).exists()
    assert list(tmp_path.iterdir()) == []


# --- Time stamps as acquisition systems write them ----------------------------------------------


def test_float32_time_vectors_are_read_with_their_mean_step(record, tmp_path):
    """A float32 t (500 s at 100 Hz: each stamp off by up to 1.5e-5 s) in HDF5 and .mat: the
    interval is the mean step, within 1e-7 of 0.01, so the estimates move by far less than their
    standard errors."""
    c = record["columns"]
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[name] = c[name]
        f["t"] = c["t"].astype(np.float32)
    scipy.io.savemat(tmp_path / "rec.mat", {**{n: c[n] for n in ("y", "v", "x")},
                                            "t": c["t"].astype(np.float32)})
    for name in ("rec.h5", "rec.mat"):
        report = identify(name, "--input-hold", "zoh", cwd=tmp_path)
        assert report["diagnostics"]["samples"] == SAMPLES
        for p, (estimate, error) in estimates(report).items():
            reference = record["reference"][p]
            assert abs(estimate - reference[0]) < 0.01 * reference[1], (name, p)


def test_csv_times_printed_to_six_decimals_at_1024_hz_are_read(tmp_path):
    """Steps of 0.000976 and 0.000977 agree within the sixth decimal printed."""
    rows = ["t,y,v,x"] + [f"{n / 1024:.6f},{np.sin(n / 50):.6f},0,0" for n in range(4096)]
    (tmp_path / "lab.csv").write_text("\n".join(rows) + "\n")
    proc = run("check", "lab.csv", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "dt = 0.000976562" in proc.stdout or "dt = 0.0009765" in proc.stdout, proc.stdout


# --- Truncated files ------------------------------------------------------------------------------


def small_record(d, csv):
    """The first ROWS rows of the record as CSV, with its metadata."""
    lines = Path(csv).read_text().splitlines(keepends=True)
    comments = [line for line in lines if line.startswith("#")]
    table = [line for line in lines if not line.startswith("#")]  # the header row, then rows
    path = d / "small.csv"
    path.write_text("".join(comments + table[:ROWS + 1]))
    return path


def whole_file(fmt, d, c, csv):
    """Writes the whole file of format `fmt`; returns its name and the options that read it."""
    small = small_record(d, csv)
    c = cut(c)
    if fmt in ("bin", "convert-npy", "convert-mat", "convert-mat73", "convert-h5"):
        target, extra = {
            "bin": ("whole.bin", []), "convert-npy": ("whole.npy", []),
            "convert-mat": ("whole.mat", []), "convert-mat73": ("whole.mat", ["--format", "mat73"]),
            "convert-h5": ("whole.h5", []),
        }[fmt]
        assert run("convert", small, target, *extra, cwd=d).returncode == 0
        return target, (["--names", "t,y,v,x"] if target.endswith(".npy") else [])
    if fmt == "npy-fortran":
        np.save(d / "whole.npy", np.asfortranarray(matrix(c).astype(">f8")))
        return "whole.npy", ["--names", "t,y,v,x"]
    if fmt == "npy-1d":
        for name in ("v", "x"):
            np.save(d / f"{name}.npy", c[name])
        np.save(d / "whole.npy", c["y"])
        return "whole.npy", ["--columns", "v=v.npy,x=x.npy", "--dt", "0.01"]
    if fmt == "mat5":
        scipy.io.savemat(d / "whole.mat", c)
        return "whole.mat", []
    if fmt == "mat5-compressed":
        scipy.io.savemat(d / "whole.mat", c, do_compression=True)
        return "whole.mat", []
    if fmt == "h5py":
        with h5py.File(d / "whole.h5", "w") as f:
            for name in NAMES:
                f.create_dataset(f"run1/{name}", data=c[name], chunks=(512,))
        return "whole.h5", ["--columns", "t=run1/t,y=run1/y,v=run1/v,x=run1/x"]
    raise ValueError(fmt)


TRUNCATED_MESSAGE = {
    # format: (message after FILE:LINE:COL: when cut in half, when cut to 100 bytes)
    "bin": ("the file ends inside row ", "the file ends inside its header: expected "),
    "convert-npy": ("the file ends inside the array: ", "the file ends inside its NumPy header"),
    "npy-fortran": ("the file ends inside the array: ", "the file ends inside its NumPy header"),
    "npy-1d": ("the file ends inside the array: ", "the file ends inside its NumPy header"),
    "mat5": ("cannot read the MATLAB file", "cannot read the MATLAB file"),
    "mat5-compressed": ("cannot read the MATLAB file", "cannot read the MATLAB file"),
    "convert-mat": ("cannot read the MATLAB file", "cannot read the MATLAB file"),
    "convert-mat73": ("cannot read the MATLAB file", "cannot read the MATLAB file"),
    "h5py": ("cannot read the HDF5 file (damaged or truncated?)",) * 2,
    "convert-h5": ("cannot read the HDF5 file (damaged or truncated?)",) * 2,
}


@pytest.mark.parametrize("size", ["half", "100-bytes"])
@pytest.mark.parametrize("fmt", list(TRUNCATED_MESSAGE))
def test_truncated_file_is_an_error_not_a_crash(record, tmp_path, fmt, size):
    name, options = whole_file(fmt, tmp_path, record["columns"], record["csv"])
    whole = (tmp_path / name).read_bytes()
    length = len(whole) // 2 if size == "half" else 100
    if fmt == "bin" and size == "half":
        # A binary file cut between rows is a shorter record: cut inside a row.
        start = 12 + struct.unpack("<I", whole[8:12])[0]
        if (length - start) % 32 == 0:
            length -= 3
    suffix = Path(name).suffix
    truncated = tmp_path / f"cut{suffix}"
    truncated.write_bytes(whole[:length])
    proc = run("identify", MODEL, truncated.name, *options, "--input-hold", "zoh", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2, proc.stderr
    line = first_line(proc.stderr)
    location, _, message = line.partition(": ")
    assert location.startswith(f"cut{suffix}:"), line
    expected = TRUNCATED_MESSAGE[fmt][0 if size == "half" else 1]
    assert message.startswith(expected), line


def test_truncated_csv_header_is_an_error(record, tmp_path):
    (tmp_path / "cut.csv").write_bytes(record["csv"].read_bytes()[:100])
    proc = run("identify", MODEL, "cut.csv", cwd=tmp_path)
    assert proc.returncode == 2
    assert first_line(proc.stderr) == "cut.csv:1:1: expected a header row naming the columns"


@pytest.mark.parametrize("fmt", ["convert-npy", "mat5", "h5py", "convert-mat73", "bin"])
def test_empty_file_is_an_error(record, tmp_path, fmt):
    name, _ = whole_file(fmt, tmp_path, record["columns"], record["csv"])
    empty = tmp_path / f"empty{Path(name).suffix}"
    empty.write_bytes(b"")
    proc = run("identify", MODEL, empty.name, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr == (
        f"{empty.name}:1:1: the file is empty: expected a header row naming the columns\n"
    )


def test_truncated_mat73_message_is_one_line(record, tmp_path):
    name, _ = whole_file("convert-mat73", tmp_path, record["columns"], record["csv"])
    whole = (tmp_path / name).read_bytes()
    (tmp_path / "cut.mat").write_bytes(whole[: len(whole) // 2])
    proc = run("identify", MODEL, "cut.mat", cwd=tmp_path)
    assert proc.returncode == 2
    assert len(proc.stderr.splitlines()) == 1, proc.stderr
    assert "H5F.c" not in proc.stderr


# --- Bugs found: crashes and wrong results --------------------------------------------------------


def test_hdf5_array_attribute_is_not_a_crash(record, tmp_path):
    c = record["columns"]
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        for name in NAMES:
            f[name] = c[name]
        f.attrs["calib"] = np.arange(1000.0)
    proc = run("identify", MODEL, "rec.h5", "--input-hold", "zoh", "--format", "json",
               cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 0, proc.stderr
    assert_same_estimates(estimates(json.loads(proc.stdout)), record["reference"])


def npy_with_header(path, header, data=b"\0" * 800):
    header = header + " " * (118 - len(header)) + "\n"
    path.write_bytes(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode()
                     + data)


def test_npy_shape_overflow_is_an_error(tmp_path):
    npy_with_header(tmp_path / "huge.npy",
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (4611686018427387904, 4), }")
    proc = run("identify", MODEL, "huge.npy", "--names", "t,y,v,x", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2
    assert "the file ends inside the array" in first_line(proc.stderr)


def test_npy_shape_within_range_but_missing_data_is_an_error(tmp_path):
    npy_with_header(tmp_path / "long.npy",
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000, 4), }")
    proc = run("identify", MODEL, "long.npy", "--names", "t,y,v,x", cwd=tmp_path)
    assert proc.returncode == 2
    assert first_line(proc.stderr) == (
        "long.npy:26:1: the file ends inside the array: 800 bytes of data for an array of shape "
        "(1000000, 4) of 8-byte values"
    )


def mat_claiming(path, values, compress):
    """A level-5 .mat file of y, v, x and t, 100 values each, whose headers claim `values`."""
    scipy.io.savemat(path, {name: np.arange(100.0) for name in NAMES},
                     do_compression=compress)
    whole = bytearray(path.read_bytes())
    out, at = whole[:128], 128
    dims = struct.pack("<iiii", 5, 8, 1, 100)  # the miINT32 dimensions element: 1 x 100
    while at < len(whole):
        kind, size = struct.unpack("<ii", whole[at:at + 8])
        body = whole[at + 8:at + 8 + size]
        plain = bytearray(zlib.decompress(bytes(body)) if compress else body)
        where = plain.find(dims)
        plain[where + 8:where + 16] = struct.pack("<ii", 1, values)
        body = zlib.compress(bytes(plain)) if compress else plain
        out += struct.pack("<ii", kind, len(body)) + body
        at += 8 + size
    path.write_bytes(bytes(out))


@pytest.mark.parametrize("compress", [False, True], ids=["plain", "compressed"])
def test_mat_header_claiming_more_than_the_file_holds_is_an_error(tmp_path, compress):
    """matio reads what a header claims: values never written would be read as data."""
    mat_claiming(tmp_path / "claims.mat", 2**28, compress)
    size = (tmp_path / "claims.mat").stat().st_size
    proc = run("identify", MODEL, "claims.mat", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2
    assert first_line(proc.stderr) == (
        f"claims.mat:1:1: variable 'y' claims 1 x 268435456 values, more than a file of {size} "
        "bytes holds (a damaged header?)")


@pytest.mark.parametrize("written", ["never", "only partly"])
def test_hdf5_dataset_not_written_is_an_error(tmp_path, written):
    """Acquisition that stops early leaves datasets whose unwritten values read as the fill
    value."""
    with h5py.File(tmp_path / "early.h5", "w") as f:
        for name in NAMES:
            f.create_dataset(name, data=np.arange(2**16, dtype=float))
        del f["v"]
        v = f.create_dataset("v", shape=(2**16,), dtype="f8", chunks=(1024,))
        if written == "only partly":
            v[:5000] = 1.0
    proc = run("identify", MODEL, "early.h5", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2
    assert first_line(proc.stderr) == (
        f"early.h5:1:1: dataset 'v' was {written} written: its unwritten values would read as "
        "the fill value")


def test_unusable_state_is_an_error_not_an_unmeasured_state(tmp_path):
    """A state the file holds in a form momentid cannot read is not taken as unmeasured (which
    would choose the lagged equations): its reading fails and says why."""
    with h5py.File(tmp_path / "ints.h5", "w") as f:
        for name in NAMES:
            f.create_dataset(name, data=np.arange(1000, dtype=np.int16 if name == "v" else float))
    proc = run("identify", MODEL, "ints.h5", cwd=tmp_path)
    not_a_crash(proc)
    assert proc.returncode == 2
    assert first_line(proc.stderr) == (
        "ints.h5:1:1: dataset 'v' holds integer values: expected floating-point values")


def test_check_without_a_model_names_the_arrays_it_cannot_read(tmp_path):
    with h5py.File(tmp_path / "mixed.h5", "w") as f:
        f.create_dataset("y", data=np.sin(np.arange(1000) / 10))
        f.create_dataset("counts", data=np.arange(1000, dtype=np.int32))
        f.create_dataset("v", shape=(1000,), dtype="f8", chunks=(100,))
    proc = run("check", "mixed.h5", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert ("warning: not checked: dataset 'counts' holds integer values: expected "
            "floating-point values") in proc.stdout.splitlines()
    assert ("warning: not checked: dataset 'v' was never written: its unwritten values would "
            "read as the fill value") in proc.stdout.splitlines()


def test_hdf5_variable_length_string_attribute_is_metadata(record, tmp_path):
    c = record["columns"]
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[name] = c[name]
        f.attrs["dt"] = 0.01
        f.attrs["input-hold"] = "zoh"  # h5py stores str as a variable-length string
    report = identify("rec.h5", cwd=tmp_path)
    assert report["diagnostics"]["input_hold"] == "zoh"
    assert_same_estimates(estimates(report), record["reference"])


def test_hdf5_fixed_length_string_attribute_is_metadata(record, tmp_path):
    c = record["columns"]
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        for name in ("y", "v", "x"):
            f[name] = c[name]
        f.attrs["dt"] = 0.01
        f.attrs["input-hold"] = np.bytes_("zoh")
    report = identify("rec.h5", cwd=tmp_path)
    assert report["diagnostics"]["input_hold"] == "zoh"
    assert_same_estimates(estimates(report), record["reference"])


def test_structured_npy_message_names_the_dtype(tmp_path):
    array = np.zeros(100, dtype=[(n, "<f8") for n in NAMES])
    np.save(tmp_path / "s.npy", array)
    proc = run("identify", MODEL, "s.npy", cwd=tmp_path)
    assert proc.returncode == 2
    line = first_line(proc.stderr)
    assert "structured" in line or "('x', '<f8')" in line, line


def test_convert_matrix_columns_to_csv_reads_back(record, tmp_path):
    np.save(tmp_path / "a.npy", matrix(record["columns"]))
    proc = run("convert", "a.npy", "out.csv", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    report = identify("out.csv", "--columns", "t=a[:, 0],y=a[:, 1],v=a[:, 2],x=a[:, 3]",
                      "--input-hold", "zoh", cwd=tmp_path)
    assert_same_estimates(estimates(report), record["reference"])


# --- 3. Memory stays flat for HDF5 --------------------------------------------------------------


def peak_rss_kb(args, cwd):
    """Peak resident set of the program, in kB, and its run. Under AddressSanitizer, freed
    memory is held back (its quarantine, up to 256 MB) and would count as the program's: the
    quarantine is turned off (a program built without the sanitizer ignores the setting)."""
    env = dict(os.environ)
    env["ASAN_OPTIONS"] = ":".join(filter(None, [env.get("ASAN_OPTIONS"), "quarantine_size_mb=0"]))
    if TIME:
        proc = subprocess.run([TIME, "-f", "%M", str(MOMENTID), *map(str, args)], cwd=cwd,
                              capture_output=True, text=True, timeout=TIMEOUT, env=env)
        return int(proc.stderr.strip().splitlines()[-1]), proc
    wrapper = (
        "import resource, subprocess, sys\n"
        "p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
        "sys.stdout.write(p.stdout)\n"
        "sys.stderr.write(p.stderr + '\\n' + "
        "str(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss))\n"
        "sys.exit(p.returncode)\n"
    )
    proc = subprocess.run([sys.executable, "-c", wrapper, str(MOMENTID), *map(str, args)],
                          cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
    return int(proc.stderr.strip().splitlines()[-1]), proc


def test_hdf5_memory_stays_flat(tmp_path):
    rng = np.random.default_rng(7)
    peaks = {}
    for rows in (400_000, 4_000_000):
        path = tmp_path / f"rows{rows}.h5"
        with h5py.File(path, "w") as f:
            for name in ("y", "v", "x"):
                f.create_dataset(name, data=rng.standard_normal(rows), chunks=(65536,))
            f.attrs["dt"] = 0.01
        # The zero-lag pass: the reader is what is measured, and the lagged pass over these
        # rows takes 20 times as long under the sanitizers.
        peak, proc = peak_rss_kb(["identify", MODEL, path.name, "--input-hold", "zoh",
                                  "--method", "zero-lag"], cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert f"{rows} rows in 1 run" in proc.stdout
        peaks[rows] = peak
        path.unlink()
    growth_mb = (peaks[4_000_000] - peaks[400_000]) / 1024
    assert growth_mb < 30, peaks


# --- 4. --version -------------------------------------------------------------------------------


def test_version_lists_the_formats():
    proc = run("--version")
    assert proc.returncode == 0
    formats = [line for line in proc.stdout.splitlines() if line.startswith("data formats:")]
    assert len(formats) == 1, proc.stdout
    for name in ("CSV", "NumPy .npy", "MATLAB .mat levels 5 and 7.3", "HDF5", "matio "):
        assert name in formats[0], formats[0]


@pytest.mark.parametrize("target", ["acc.mat", "acc.h5"])
def test_convert_keeps_the_declaration_of_a_derivative_column(tmp_path, target):
    """simulate declares the acceleration column in the metadata; after convert, a model without
    the `measured` statement reads it (its noise variance is reported for it)."""
    proc = run("simulate", ROOT / "models" / "duffing_accelerometer.mom", "--samples", "20000",
               "--dt", "0.05", "--input", "x=multisine:f1=0.05,f2=2,lines=20,rms=3",
               "--observe", "y,x,a", "-o", "acc.csv", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "# momentid: measured.a=v'" in (tmp_path / "acc.csv").read_text()
    proc = run("convert", "acc.csv", target, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    # The lagged equations, which the record lacking v calls for (run() would ask for zero-lag).
    proc = subprocess.run([str(MOMENTID), "identify", str(MODEL), target, "--format", "json"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=TIMEOUT)
    assert proc.returncode == 0, proc.stderr
    assert "a" in json.loads(proc.stdout)["method"]["noise_variance"]
