#!/usr/bin/python3
"""Times `momentid identify` on one or two threads, on one file and on eight, and under mpirun.

  benchmarks/bench_parallel.py [--rows 1e7] [--repeat 2] [--directory DIR]

A Duffing record (t, y, v, x) of `rows` rows is simulated as a binary file and converted to CSV;
eight records of rows/8 rows each (other seeds) are simulated in both formats too. Each data
set is identified with --threads 1 and 2 (best of `--repeat` runs) and, when this momentid has
MPI and mpirun is installed, by `mpirun -np 2 ... --threads 1`. Throughput is in MB/s and ns per
row, and as a ratio to one thread on the same data in the same run. The floor of each format is
a pass that only reads the rows (`momentid check FILE --lags 1`: the channels' means and lag-1
products, no moments) on two threads. Every way of reading one data set must give the same
estimates to the last bit. Peak memory is per process; one thread on a record of rows/10 rows
shows that it does not grow with the record.
"""
import argparse
import json
import os
import shutil
import subprocess
import tempfile

from bench_formats import run_with_peak

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
# Open MPI refuses to run as root unless told.
MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def run(*args):
    return subprocess.run([MOMENTID, *map(str, args)], check=True, capture_output=True,
                          text=True).stdout


def best(command, repeat):
    runs = [run_with_peak(command, MPI_ENV) for _ in range(repeat)]
    return min(r[0] for r in runs), max(r[1] for r in runs), runs[0][2]


def estimates(output):
    parameters = json.loads(output)["parameters"]
    return {name: (p["estimate"], p["std_error"]) for name, p in parameters.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=float, default=1e7)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--directory", default=None)
    args = parser.parse_args()
    rows = int(args.rows)
    directory = args.directory or tempfile.mkdtemp(prefix="momentid_bench_parallel_")
    os.makedirs(directory, exist_ok=True)
    mpirun = shutil.which("mpirun")
    with_mpi = mpirun is not None and "MPI" in run("--version")
    try:
        path = lambda name: os.path.join(directory, name)  # noqa: E731
        run("simulate", MODEL, "--samples", rows, "--seed", 1, "--format", "bin",
            "-o", path("one.bin"))
        run("convert", path("one.bin"), path("one.csv"))
        run("simulate", MODEL, "--samples", rows // 10, "--seed", 1, "--format", "bin",
            "-o", path("tenth.bin"))
        for k in range(8):
            run("simulate", MODEL, "--samples", rows // 8, "--seed", 10 + k, "--format", "bin",
                "-o", path(f"part{k}.bin"))
            run("convert", path(f"part{k}.bin"), path(f"part{k}.csv"))

        print(f"momentid identify, Duffing, {rows:.3g} rows; {os.cpu_count()} cores; "
              f"best of {args.repeat}")
        print(f"{'data':<16} {'how':<22} {'MB':>6} {'s':>7} {'MB/s':>7} {'ns/row':>7} "
              f"{'ratio':>6} {'peak MB':>8}")
        for fmt in ("csv", "bin"):
            for label, files in ((f"one {fmt}", [path(f"one.{fmt}")]),
                                 (f"8 {fmt} files", [path(f"part{k}.{fmt}") for k in range(8)])):
                size = sum(os.path.getsize(f) for f in files) / 1e6
                ways = [(f"--threads {t}", [], ["--threads", str(t)]) for t in (1, 2)]
                if with_mpi:
                    ways.append(("mpirun -np 2, 1 thread", [mpirun, "-np", "2"],
                                 ["--threads", "1"]))
                baseline = None
                reference = None
                for how, launcher, extra in ways:
                    seconds, peak, out = best([*launcher, MOMENTID, "identify", MODEL, *files,
                                               "--format", "json", *extra], args.repeat)
                    found = estimates(out)
                    if reference is None:
                        reference = found
                    elif found != reference:
                        raise SystemExit(f"{label}, {how}: {found} differs from {reference}")
                    baseline = baseline or seconds
                    print(f"{label:<16} {how:<22} {size:6.0f} {seconds:7.2f} "
                          f"{size / seconds:7.0f} {seconds / rows * 1e9:7.1f} "
                          f"{baseline / seconds:6.2f} {peak:8.1f}")
            seconds, peak, _ = best([MOMENTID, "check", path(f"one.{fmt}"), "--lags", "1",
                                     "--threads", "2"], args.repeat)
            size = os.path.getsize(path(f"one.{fmt}")) / 1e6
            print(f"{'one ' + fmt:<16} {'read only, 2 threads':<22} {size:6.0f} {seconds:7.2f} "
                  f"{size / seconds:7.0f} {seconds / rows * 1e9:7.1f} {'':>6} {peak:8.1f}")
        seconds, peak, _ = best([MOMENTID, "identify", MODEL, path("tenth.bin"), "--format",
                                 "json", "--threads", "1"], args.repeat)
        print(f"peak memory, one thread: {peak:.1f} MB at {rows // 10:.3g} rows "
              "(against the one-thread line of 'one bin' above)")
        if not with_mpi:
            print("(no mpirun line: this momentid was built without MPI, or mpirun is missing)")
    finally:
        if args.directory is None:
            shutil.rmtree(directory)


if __name__ == "__main__":
    main()
