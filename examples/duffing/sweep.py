#!/usr/bin/env python3
"""Identifies the Duffing oscillator (c = 0.5, k = 4, eps = 1) from records of increasing length
and shows how the estimates and their 95% intervals shrink.

  sweep.py [--max N] [--svg OUT.svg]

Prints a table; with --svg also draws it. Needs only the Python standard library and the
momentid executable (build/momentid, or the MOMENTID environment variable).
"""
import json
import math
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


def svg(rows, path):
    """Three log-log panels: each parameter's |error| and 95% half-width against the record
    length, with lines of slope -1/2 and -1 for comparison."""
    w, h, left = 330, 280, 60
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{3 * w + left}" height="{h + 70}" '
           'font-family="sans-serif" font-size="11">',
           f'<rect width="{3 * w + left}" height="{h + 70}" fill="white"/>']
    nmin, nmax = rows[0][0] / 1.5, rows[-1][0] * 1.5
    for i, (p, truth) in enumerate(TRUTH.items()):
        half = [(n, (r[p]["ci95"][1] - r[p]["ci95"][0]) / 2 / truth) for n, r in rows]
        error = [(n, max(abs(r[p]["estimate"] - truth) / truth, 1e-7)) for n, r in rows]
        vmin = 10 ** math.floor(math.log10(min(v for _, v in half + error)))
        vmax = 10 ** math.ceil(math.log10(max(v for _, v in half + error)))
        x0, y0, pw, ph = left + i * w, 25, w - 50, h - 50
        fx = lambda n: x0 + pw * (math.log(n) - math.log(nmin)) / (math.log(nmax) - math.log(nmin))
        fy = lambda v: y0 + ph * (1 - (math.log10(v) - math.log10(vmin)) / (math.log10(vmax) - math.log10(vmin)))
        out.append(f'<rect x="{x0}" y="{y0}" width="{pw}" height="{ph}" fill="none" stroke="#444"/>')
        out.append(f'<text x="{x0 + pw / 2}" y="{y0 - 8}" text-anchor="middle">{p}: relative to the true value {truth:g}</text>')
        e = math.log10(vmin)
        while e <= math.log10(vmax) + 1e-9:
            y = fy(10 ** e)
            out.append(f'<line x1="{x0}" x2="{x0 + pw}" y1="{y:.1f}" y2="{y:.1f}" stroke="#eee"/>')
            out.append(f'<text x="{x0 - 4}" y="{y + 4:.1f}" text-anchor="end">1e{int(round(e))}</text>')
            e += 1
        for k in range(3, 7):
            if nmin <= 10 ** k <= nmax:
                out.append(f'<text x="{fx(10 ** k):.1f}" y="{y0 + ph + 14}" text-anchor="middle">1e{k}</text>')
        out.append(f'<text x="{x0 + pw / 2}" y="{y0 + ph + 30}" text-anchor="middle">samples</text>')
        n0, v0 = half[0]
        for slope, dash in ((-0.5, "6,3"), (-1.0, "2,3")):
            n1 = rows[-1][0]
            v1 = v0 * (n1 / n0) ** slope
            out.append(f'<line x1="{fx(n0):.1f}" y1="{fy(v0):.1f}" x2="{fx(n1):.1f}" y2="{fy(max(v1, vmin)):.1f}" '
                       f'stroke="#888" stroke-dasharray="{dash}"/>')
        for series, color in ((half, "#2471a3"), (error, "#c0392b")):
            pts = " ".join(f"{fx(n):.1f},{fy(v):.1f}" for n, v in series)
            out.append(f'<polyline points="{pts}" fill="none" stroke="{color}" stroke-width="2"/>')
            for n, v in series:
                out.append(f'<circle cx="{fx(n):.1f}" cy="{fy(v):.1f}" r="3" fill="{color}"/>')
    out.append(f'<text x="{left}" y="{h + 40}">blue: half-width of the 95% interval; red: |estimate - truth|; '
               'both divided by the true value. Grey: slopes -1/2 (dashed) and -1 (dotted).</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    args = sys.argv[1:]
    max_samples = int(args[args.index("--max") + 1]) if "--max" in args else 1000000
    rows = sweep(max_samples)
    print(table(rows))
    if "--svg" in args:
        svg(rows, args[args.index("--svg") + 1])


if __name__ == "__main__":
    main()
