#!/usr/bin/python3
"""Times identify from numpy arrays through the Python module, against files.

  PYTHONPATH=build/python benchmarks/bench_python.py [--sizes 1e5,1e6,1e7] [--repeat 3]

For each size, a Duffing record (y, v, x) is simulated into arrays, and the best of `repeat`
runs of momentid.identify on the arrays is printed with the peak memory the call adds above the
arrays (resident high-water mark, reset before the call; each size runs in a process of its
own). At 1e6 samples the same record is also written as a binary file and identified from it,
in the module and by the program (`momentid identify --format json`, process start included),
in the same run: the ratios compare the array path with the binary-file pass. The estimates of
the three must agree to 1e-12.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
INPUTS = {"x": "ma:K=10,w=0.1,sigma=20"}


def status_kb(field):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(field)


def measure(samples, repeat):
    """In this process: the best time and the peak extra memory of identify on arrays."""
    import momentid
    model = momentid.Model.from_file(MODEL)
    record = momentid.simulate(model, samples=samples, inputs=INPUTS, seed=7)
    momentid.identify(model, record)  # warm up: code and allocator
    best = float("inf")
    extra = 0
    for _ in range(repeat):
        base = status_kb("VmRSS")
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")  # resets the high-water mark to the current resident size
        start = time.perf_counter()
        result = momentid.identify(model, record)
        best = min(best, time.perf_counter() - start)
        extra = max(extra, status_kb("VmHWM") - base)
    return {"seconds": best, "extra_mb": extra / 1024, "estimates": result.estimates}


def compare_with_files(samples, repeat):
    import momentid
    model = momentid.Model.from_file(MODEL)
    record = momentid.simulate(model, samples=samples, inputs=INPUTS, seed=7)
    with tempfile.TemporaryDirectory() as directory:
        path = os.path.join(directory, "duffing.bin")
        momentid.simulate(model, samples=samples, inputs=INPUTS, seed=7, path=path,
                          format="bin")
        times = {"arrays": [], "module, binary file": [], "program, binary file": []}
        estimates = {}
        for _ in range(repeat):
            start = time.perf_counter()
            estimates["arrays"] = momentid.identify(model, record).estimates
            times["arrays"].append(time.perf_counter() - start)
            start = time.perf_counter()
            estimates["module, binary file"] = momentid.identify(model, path).estimates
            times["module, binary file"].append(time.perf_counter() - start)
            start = time.perf_counter()
            out = subprocess.run([MOMENTID, "identify", MODEL, path, "--format", "json"],
                                 check=True, capture_output=True, text=True).stdout
            times["program, binary file"].append(time.perf_counter() - start)
            estimates["program, binary file"] = {
                name: p["estimate"] for name, p in json.loads(out)["parameters"].items()}
    for name, values in estimates.items():
        for p, value in values.items():
            reference = estimates["arrays"][p]
            assert abs(value - reference) <= 1e-12 * abs(reference), (name, p, value, reference)
    return {name: min(t) for name, t in times.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1e5,1e6,1e7")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print(json.dumps(measure(args.child, args.repeat)))
        return
    print(f"{'samples':>10} {'identify (s)':>13} {'ns/sample':>10} {'extra peak MB':>14}")
    for size in (int(float(s)) for s in args.sizes.split(",")):
        out = subprocess.run([sys.executable, __file__, "--child", str(size), "--repeat",
                              str(args.repeat)], check=True, capture_output=True, text=True)
        r = json.loads(out.stdout)
        print(f"{size:>10} {r['seconds']:>13.4f} {1e9 * r['seconds'] / size:>10.1f} "
              f"{r['extra_mb']:>14.1f}")
    samples = 1_000_000
    times = compare_with_files(samples, args.repeat)
    print(f"\n{samples} samples, best of {args.repeat} (estimates agree to 1e-12):")
    for name, seconds in times.items():
        print(f"  {name:<22} {seconds:.4f} s  ratio to arrays {seconds / times['arrays']:.2f}")


if __name__ == "__main__":
    main()
