"""What the tests of the Python module share: the program, the Duffing model, and records
simulated by the program and by the module.

Run from the repository root:
    PYTHONPATH=build/python MOMENTID=build/momentid python3 -m pytest -q python/tests
"""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import momentid

ROOT = Path(__file__).resolve().parents[2]
DUFFING = ROOT / "models" / "duffing.mom"
TRUE = {"c": 0.5, "k": 4.0, "eps": 1.0}  # duffing.mom's nominal values, used by simulate
INPUT = "ma:K=10,w=0.1,sigma=20"


# --- helpers and fixtures ----------------------------------------------------------------------

@pytest.fixture(scope="session")
def cli():
    """Runs the program (path from $MOMENTID) and returns its standard output."""
    program = os.environ.get("MOMENTID")
    if not program:
        pytest.skip("MOMENTID (the path of the momentid program) is not set")
    program = str(Path(program).resolve())

    def run(*args, cwd=None):
        done = subprocess.run([program, *map(str, args)], capture_output=True, text=True,
                              cwd=cwd)
        assert done.returncode == 0, f"momentid {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout

    return run


@pytest.fixture(scope="session")
def duffing():
    return momentid.Model.from_file(DUFFING)


@pytest.fixture(scope="session")
def cli_csv(cli, tmp_path_factory):
    """The Duffing record the program simulates: 100000 samples, seed 3."""
    path = tmp_path_factory.mktemp("cli") / "duffing.csv"
    cli("simulate", DUFFING, "--samples", 100000, "--seed", 3, "--input", INPUT, "-o", path)
    return path


@pytest.fixture(scope="session")
def cli_json(cli, cli_csv):
    return json.loads(cli("identify", DUFFING, cli_csv, "--format", "json"))


@pytest.fixture(scope="session")
def ls_json(cli, cli_csv):
    return json.loads(cli("identify", DUFFING, cli_csv, "--format", "json", "--weighting", "ls"))


@pytest.fixture(scope="session")
def record(duffing):
    """A smaller in-memory Duffing record (20000 samples), with metadata."""
    return momentid.simulate(duffing, samples=20000, seed=3, inputs={"x": INPUT})


def sines(rng, count, band, amplitude):
    """A smooth random force: `count` sines at frequencies uniform on `band` (Hz), normal
    amplitudes of scale `amplitude` and uniform phases, as a function of time (array or
    scalar); its `lines` are the frequencies, amplitudes and phases."""
    frequencies = rng.uniform(band[0], band[1], count)
    amplitudes = rng.normal(0, amplitude, count)
    phases = rng.uniform(0, 2 * np.pi, count)

    def force(t):
        return np.sum(amplitudes * np.sin(2 * np.pi * frequencies * np.asarray(t)[..., None]
                                          + phases), axis=-1)
    force.lines = frequencies, amplitudes, phases
    return force


def read_csv(path):
    """The columns of a CSV file written by the program: {name: float64 array}, `#` lines
    (the metadata) skipped."""
    lines = Path(path).read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    names = lines[header].split(",")
    values = np.loadtxt(path, delimiter=",", skiprows=header + 1, ndmin=2)
    return {name: values[:, k] for k, name in enumerate(names)}


def read_metadata(path):
    """The `# momentid:` key=value pairs of a CSV file, as one dict."""
    out = {}
    for line in Path(path).read_text().splitlines():
        if not line.startswith("#"):
            break
        if line.startswith("# momentid:"):
            out.update(item.split("=", 1) for item in line[len("# momentid:"):].split())
    return out


def without(values, *keys):
    return {k: v for k, v in values.items() if k not in keys}
