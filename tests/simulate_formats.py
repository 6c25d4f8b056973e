#!/usr/bin/env python3
"""`momentid simulate -o FILE` writes the format FILE's extension names (.npy, .mat, .h5, .hdf5,
and .mat level 7.3 with --format mat73), as `momentid convert` does, and so does `simulate
--input-file`. Each file, converted back to CSV, holds the values of the CSV that simulate writes
with the same seed, as the same text (CSV numbers are the shortest that read back exactly, so the
same text is the same double), and the .mat and HDF5 files its metadata lines; `check` reads each,
the .npy file with the options its warning gives; identify gives the same result on the .mat and
HDF5 files as on the CSV (not on the .npy file, which loses the metadata lines of the noise that
identify reads).

Usage: simulate_formats.py MOMENTID MODEL DIRECTORY
"""

import json
import shutil
import subprocess
import sys
from pathlib import Path

MOMENTID, MODEL = (str(Path(a).resolve()) for a in sys.argv[1:3])
DIR = Path(sys.argv[3]).resolve()
SIMULATION = ["--samples", "3000", "--runs", "2", "--seed", "7",
              "--input", "ma:K=10,w=0.1,sigma=20", "--noise", "y=0.05"]
TARGETS = [("out.npy", []), ("out.mat", []), ("out73.mat", ["--format", "mat73"]),
           ("out.h5", []), ("out.hdf5", [])]
failures = []


def run(*args):
    return subprocess.run([MOMENTID, *map(str, args)], capture_output=True, text=True, cwd=DIR)


def succeed(*args):
    done = run(*args)
    if done.returncode != 0:
        sys.exit(f"momentid {' '.join(map(str, args))}: exit {done.returncode}: {done.stderr}")
    return done


def check(condition, what):
    print(("ok: " if condition else "FAILED: ") + what)
    if not condition:
        failures.append(what)


def csv_columns(path):
    """The `# momentid:` lines and {column: its fields as text} of a CSV file."""
    lines = (DIR / path).read_text().splitlines()
    metadata = [line for line in lines if line.startswith("#")]
    rows = [line.split(",") for line in lines if not line.startswith("#")]
    return metadata, {name: [row[k] for row in rows[1:]] for k, name in enumerate(rows[0])}


def same_as(reference, written, read_options=(), metadata_kept=True):
    """`written` converted back to CSV holds `reference`'s columns, text for text."""
    back = written + ".back.csv"
    succeed("convert", written, back, *read_options)
    want_metadata, want = csv_columns(reference)
    got_metadata, got = csv_columns(back)
    check(sorted(got) == sorted(want) and all(got[name] == want[name] for name in want),
          f"{written}: the values of {reference}, bit for bit ({len(want['t'])} rows)")
    if metadata_kept:
        check(got_metadata == want_metadata, f"{written}: the metadata lines of {reference}")


def identify(path, *options):
    report = json.loads(succeed("identify", MODEL, path, "--format", "json", *options).stdout)
    report.pop("data")
    return report


shutil.rmtree(DIR, ignore_errors=True)
DIR.mkdir(parents=True)
succeed("simulate", MODEL, *SIMULATION, "-o", "ref.csv")
reference = identify("ref.csv")
npy_options = ["--names", "t,y,v,x,run", "--input-hold", "zoh"]
for name, options in TARGETS:
    done = succeed("simulate", MODEL, *SIMULATION, *options, "-o", name)
    if name.endswith(".npy"):
        warning = ("momentid: warning: a .npy file keeps neither column names nor metadata: "
                   f"read {name} with {' '.join(npy_options)}\n")
        check(done.stderr == warning, f"{name}: the warning says how to read it back")
        same_as("ref.csv", name, npy_options[:2], metadata_kept=False)
    else:
        check(done.stderr == "", f"{name}: nothing to warn of")
        same_as("ref.csv", name)
        check(identify(name) == reference, f"{name}: identify as on the CSV")
    summary = succeed("check", name, *(npy_options if name.endswith(".npy") else [])).stdout
    check(summary.startswith(f"data {name}: 6000 rows in 2 runs, dt = 0.01\n"),
          f"check {name}: {summary.splitlines()[0]}")
check((DIR / "out73.mat").read_bytes().startswith(b"MATLAB 7.3 MAT-file"),
      "--format mat73 writes a level 7.3 file")
check((DIR / "out.mat").read_bytes().startswith(b"MATLAB 5.0 MAT-file"), ".mat is level 5")

# The response to a recorded input, in the record's layout, in each format.
succeed("simulate", MODEL, "--input-file", "ref.csv", "--set", "c=0.7", "-o", "replay.csv")
for name, options in TARGETS:
    replay = "replay_" + name
    read = npy_options[:2] if name.endswith(".npy") else []
    succeed("simulate", MODEL, "--input-file", "ref.csv", "--set", "c=0.7", *options, "-o", replay)
    same_as("replay.csv", replay, read, metadata_kept=not name.endswith(".npy"))

leftovers = sorted(p.name for p in DIR.iterdir() if ".partial-" in p.name)
check(not leftovers, f"no temporary file left ({leftovers})")
sys.exit(1 if failures else 0)
