#!/usr/bin/python3
"""Times `momentid identify` on one record in every format it reads, against the binary format.

  benchmarks/bench_formats.py [--rows 1e7] [--flat 1e8] [--directory DIR]

A Duffing record (t, y, v, x) of `rows` rows is simulated as a binary file and converted with
`momentid convert` into CSV, .npy, .mat (levels 5 and 7.3) and HDF5. Each file is identified
once (the best of `--repeat` runs is printed) with the program's peak resident memory, and the
throughput is given as a ratio to the binary file's in the same run. With --flat N, an HDF5
file of N rows is identified too, to show that memory does not grow with the record (HDF5 is
read in hyperslabs). Every format must give the binary file's estimates to 1e-12: the
least-squares ones (`--weighting ls`), as the optimal weighting is estimated from batches whose
cut follows each file's size, which moves the estimates by about 1e-10 of their value.
"""
import argparse
import json
import os
import shutil
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")


def run(*args):
    return subprocess.run([MOMENTID, *map(str, args)], check=True, capture_output=True,
                          text=True).stdout


def run_with_peak(command, env=None):
    """Seconds, the program's peak resident MB and its standard output: a wrapper process runs
    the command alone, so that its children's high-water mark is the program's (under mpirun,
    the largest of the processes')."""
    script = ("import resource, subprocess, sys, time\n"
              "t = time.perf_counter()\n"
              "p = subprocess.run(sys.argv[1:], capture_output=True, text=True)\n"
              "t = time.perf_counter() - t\n"
              "peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024\n"
              "sys.stderr.write(p.stderr)\n"
              "print(t, peak, p.returncode)\n"
              "print(p.stdout)\n")
    out = subprocess.run(["/usr/bin/python3", "-c", script, *command], check=True,
                         capture_output=True, text=True, env=env)
    first, rest = out.stdout.split("\n", 1)
    seconds, peak, status = first.split()
    if status != "0":
        raise RuntimeError(" ".join(command) + ": " + out.stderr)
    return float(seconds), float(peak), rest


def identify_with_peak(path, extra=()):
    """Seconds, the program's peak resident MB, and the estimates."""
    seconds, peak, out = run_with_peak([MOMENTID, "identify", MODEL, path, "--format", "json",
                                        "--weighting", "ls", *extra])
    estimates = {n: p["estimate"] for n, p in json.loads(out)["parameters"].items()}
    return seconds, peak, estimates


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=float, default=1e7)
    parser.add_argument("--flat", type=float, default=0, help="also an HDF5 file of N rows")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--directory", default=None)
    args = parser.parse_args()
    rows = int(args.rows)
    directory = tempfile.mkdtemp(dir=args.directory)
    try:
        source = os.path.join(directory, "duffing.bin")
        run("simulate", MODEL, "--samples", rows, "--seed", 5, "--input",
            "ma:K=10,w=0.1,sigma=20", "--format", "bin", "-o", source)
        files = {"binary": (source, ())}
        for name, target, extra in [("csv", "duffing.csv", ()), ("npy", "duffing.npy", ()),
                                    ("mat (5)", "duffing.mat", ()),
                                    ("mat (7.3)", "duffing73.mat", ("--format", "mat73")),
                                    ("hdf5", "duffing.h5", ())]:
            path = os.path.join(directory, target)
            run("convert", source, path, *extra)
            read = ("--names", "t,y,v,x", "--input-hold", "zoh") if name == "npy" else ()
            files[name] = (path, read)
        print(f"{rows} rows; best of {args.repeat}; peak = the program's resident high-water mark")
        print(f"{'format':<10} {'MB on disk':>10} {'seconds':>8} {'MB/s':>8} {'rows/s':>10} "
              f"{'vs binary':>9} {'peak MB':>8}")
        reference = None
        binary_seconds = None
        for name, (path, extra) in files.items():
            best = None
            for _ in range(args.repeat):
                result = identify_with_peak(path, extra)
                best = result if best is None or result[0] < best[0] else best
            seconds, peak, estimates = best
            if reference is None:
                reference, binary_seconds = estimates, seconds
            for p, value in estimates.items():
                assert abs(value - reference[p]) <= 1e-12 * abs(reference[p]), (name, p)
            size = os.path.getsize(path) / 1e6
            print(f"{name:<10} {size:>10.1f} {seconds:>8.2f} {size / seconds:>8.0f} "
                  f"{rows / seconds:>10.3g} {binary_seconds / seconds:>9.2f} {peak:>8.1f}")
        if args.flat:
            big_rows = int(args.flat)
            big = os.path.join(directory, "big.bin")
            run("simulate", MODEL, "--samples", big_rows, "--seed", 5, "--input",
                "ma:K=10,w=0.1,sigma=20", "--format", "bin", "-o", big)
            big_h5 = os.path.join(directory, "big.h5")
            run("convert", big, big_h5)
            os.remove(big)
            seconds, peak, _ = identify_with_peak(big_h5)
            small_peak = identify_with_peak(files["hdf5"][0])[1]
            print(f"\nHDF5 memory: {rows} rows {small_peak:.1f} MB, {big_rows} rows {peak:.1f} MB "
                  f"({seconds:.1f} s)")
    finally:
        shutil.rmtree(directory)


if __name__ == "__main__":
    main()
