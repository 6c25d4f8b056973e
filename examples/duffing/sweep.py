#!/usr/bin/python3
"""Identifies the Duffing oscillator (c = 0.5, k = 4, eps = 1) from records of increasing length
and shows how the estimates and their 95% intervals shrink.

  sweep.py [--max N] [--plot OUT.png]

Prints a table; with --plot also draws it (matplotlib; the file's extension picks the format).
Uses the momentid executable (build/momentid, or the MOMENTID environment variable).
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODEL = os.path.join(ROOT, "models", "duffing.mom")
TRUTH = {"c": 0.5, "k": 4.0, "eps": 1.0}
INPUT = "ma:K=10,w=0.1,sigma=20"  # strong enough that eps*y^3 carries a third of the force


def sweep(max_samples):
    sizes = []
    n = 1000
    while n <= max_samples:
        sizes += [n, 3 * n] if 3 * n <= max_samples else [n]
        n *= 10
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "d.csv")
        for n in sizes:
            subprocess.run([MOMENTID, "simulate", MODEL, "--samples", str(n), "--input", INPUT,
                            "--seed", "11", "-o", data], check=True)
            out = subprocess.run([MOMENTID, "identify", MODEL, data, "--degree", "3", "--batches",
                                  "20", "--format", "json"], check=True, capture_output=True,
                                 text=True).stdout
            rows.append((n, json.loads(out)["parameters"]))
    return rows


def table(rows):
    lines = ["samples   " + "".join(f"{p + ' (95% interval)':<36}" for p in TRUTH)]
    for n, params in rows:
        cells = []
        for p in TRUTH:
            e = params[p]
            cells.append(f"{e['estimate']:<9.5f} [{e['ci95'][0]:.4f}, {e['ci95'][1]:.4f}]".ljust(36))
        lines.append(f"{n:<10d}" + "".join(cells))
    lines.append("")
    lines.append("samples   " + "".join(f"{'|error| ' + p:<16}{'half-width ' + p:<18}" for p in TRUTH))
    for n, params in rows:
        cells = []
        for p, truth in TRUTH.items():
            e = params[p]
            cells.append(f"{abs(e['estimate'] - truth):<16.2e}{(e['ci95'][1] - e['ci95'][0]) / 2:<18.2e}")
        lines.append(f"{n:<10d}" + "".join(cells))
    return "\n".join(lines)


def plot(rows, path):
    """Three log-log panels: each parameter's |error| and 95% half-width against the record
    length, both relative to the true value, with lines of slope -1/2 and -1 for comparison."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(1, len(TRUTH), figsize=(9, 3.8))
    sizes = [n for n, _ in rows]
    for ax, (p, truth) in zip(axes, TRUTH.items()):
        half = [(r[p]["ci95"][1] - r[p]["ci95"][0]) / 2 / truth for _, r in rows]
        error = [max(abs(r[p]["estimate"] - truth) / truth, 1e-7) for _, r in rows]
        for slope, style, label in ((-0.5, "--", "slope -1/2"), (-1.0, ":", "slope -1")):
            ax.plot([sizes[0], sizes[-1]], [half[0], half[0] * (sizes[-1] / sizes[0]) ** slope],
                    style, color="grey", label=label)
        ax.plot(sizes, half, "o-", color="#2471a3", label="half-width of the 95% interval")
        ax.plot(sizes, error, "o-", color="#c0392b", label="|estimate - truth|")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{p}: relative to the true value {truth:g}", fontsize=10)
        ax.set_xlabel("samples")
        ax.grid(True, which="major", color="#eee")
    axes[0].set_ylabel("divided by the true value")
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles[2:] + handles[:2], labels[2:] + labels[:2], loc="lower center", ncol=4,
                  fontsize=9, frameon=False)
    figure.tight_layout(rect=(0, 0.07, 1, 1))
    figure.savefig(path, dpi=100)
    plt.close(figure)


def main():
    args = sys.argv[1:]
    max_samples = int(args[args.index("--max") + 1]) if "--max" in args else 1000000
    rows = sweep(max_samples)
    print(table(rows))
    if "--plot" in args:
        plot(rows, args[args.index("--plot") + 1])


if __name__ == "__main__":
    main()
