#!/usr/bin/python3
"""Reproduces the numerical study of Kozin & Kozin (1967), section IV, with momentid.

  study.py tables [--long N]   Figures 1-3 in the report's layout, next to the report's values,
                               then the same systems identified from N samples (default 10^6)
  study.py bias [--samples N]  the bias study: relative bias against the moving-average length K
                               for three ways of pairing the held input with the state
  study.py plot BIAS.json OUT.png   draws the bias study (matplotlib; the file's extension picks
                                   the format)

Uses the momentid executable (build/momentid, or the MOMENTID environment variable); the plot
needs matplotlib. The report's values quoted below are from its Figures 1-3.
"""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MOMENTID = os.environ.get("MOMENTID", os.path.join(ROOT, "build", "momentid"))
MODELS = os.path.join(ROOT, "models")

# The report's protocol: moving average of K = 10 independent normal values with weights 0.1,
# runs of 1300 samples following one another. dt and sigma are not given in the report; dt = 0.05
# and sigma = 15 make the simulated moments of systems 4.1a-c match the report's within about 10%
# (rms of the log ratio over the ten moments of Figures 1 and 2: 0.09; dt = 0.01, 0.02 or 0.1
# give 1.1, 0.8 and 0.4).
DT = 0.05
INPUT = "ma:K=10,w=0.1,sigma=15"
RUN = 1300
SEED = 1967

# Report, Figure 1 (system 4.1a): E{y^2}, E{xy}, a for three runs.
FIGURE_1 = [(5.6892, 6.0682, 1.0667), (4.4014, 4.8197, 1.0950), (3.3332, 4.7634, 1.0992)]
# Report, Figure 2: E{y1^2}, E{y1 y2}, E{y2^2}, E{y1 x}, E{y2 x}, a, b for three runs.
FIGURE_2 = {
    "kozin_4_1b": [(.0637, .0004, .4862, .5841, 2.0500, 4.2172, 16.8006),
                   (.0710, .0009, .5657, .6340, 2.3313, 4.1210, 17.3080),
                   (.0678, .0000, .5450, .5936, 2.2500, 4.1280, 16.7810)],
    "kozin_4_1c": [(.0029, .0001, .0881, .2098, .4074, 4.6190, 103.72),
                   (.0028, .0001, .0773, .2094, .3719, 4.8120, 103.27),
                   (.0028, .0001, .0873, .2065, .4084, 4.673, 103.74)],
}
# Report, Figure 3 (system 4.1d), two runs: the lower triangle of the moment matrix of
# y1..y4, x (rows y1..y4, x; columns y1..y4) and the estimates a, b, c, d.
FIGURE_3 = [
    ({("y1", "y1"): .2253, ("y2", "y1"): .0000, ("y2", "y2"): .8223, ("y3", "y1"): .3216,
      ("y3", "y2"): .0839, ("y3", "y3"): .4700, ("y4", "y1"): -.0837, ("y4", "y2"): 1.1044,
      ("y4", "y3"): .0004, ("y4", "y4"): 1.6038, ("x", "y1"): .1418, ("x", "y2"): 1.8412,
      ("x", "y3"): .5172, ("x", "y4"): 3.5491},
     (3.1790, 9.194, 4.3044, 16.7258)),
    ({("y1", "y1"): .2465, ("y2", "y1"): -.0004, ("y2", "y2"): .9255, ("y3", "y1"): .3505,
      ("y3", "y2"): .0924, ("y3", "y3"): .5105, ("y4", "y1"): -.0929, ("y4", "y2"): 1.2505,
      ("y4", "y3"): .0004, ("y4", "y4"): 1.8117, ("x", "y1"): .1000, ("x", "y2"): 2.1328,
      ("x", "y3"): .4837, ("x", "y4"): 3.9482},
     (3.1708, 9.2560, 4.2525, 16.8094)),
]
TRUTH = {"kozin_4_1a": {"a": 1}, "kozin_4_1b": {"a": 4, "b": 16},
         "kozin_4_1c": {"a": 5, "b": 100}, "kozin_4_1d": {"a": 3, "b": 9, "c": 4, "d": 16}}

# How the held input x_n is paired with the state (see README.md beside this file).
PAIRINGS = {
    "end": ["--input-hold", "sample", "--input-shift", "1"],  # x_n with y_{n+1}: the report's
    "start": ["--input-hold", "sample"],                       # x_n with y_n
    "consistent": ["--input-hold", "zoh"],                     # x_n with the interval's y
}


def run(*args):
    return subprocess.run([MOMENTID, *args], check=True, capture_output=True, text=True).stdout


def simulate(model, path, samples, runs=1, input_spec=INPUT, dt=DT, seed=SEED):
    run("simulate", os.path.join(MODELS, model + ".mom"), "--dt", str(dt), "--input", input_spec,
        "--samples", str(samples), "--runs", str(runs), "--continue", "--seed", str(seed),
        "-o", path)


def identify(model, path, pairing, batches=10):
    out = run("identify", os.path.join(MODELS, model + ".mom"), path, "--format", "json",
              "--batches", str(batches), *PAIRINGS[pairing])
    return json.loads(out)


def read_csv(path):
    header, rows = None, []
    with open(path) as f:
        for line in f:
            if line.startswith("#"):
                continue
            if header is None:
                header = line.strip().split(",")
                continue
            rows.append([float(v) for v in line.split(",")])
    return header, rows


def split_runs(path, directory):
    """Writes each run of a simulated file to a file of its own; returns their paths."""
    header, rows = read_csv(path)
    r = header.index("run")
    paths = []
    for number in sorted({int(row[r]) for row in rows}):
        p = os.path.join(directory, f"run{number}.csv")
        with open(p, "w") as f:
            f.write("# momentid: dt=%g input-hold=zoh\n" % DT)
            f.write(",".join(header[:r]) + "\n")
            for row in rows:
                if int(row[r]) == number:
                    f.write(",".join(repr(v) for v in row[:r]) + "\n")
        paths.append(p)
    return paths


def report_moments(path, names):
    """Simple arithmetic averages as the report's program formed them: products at the same
    row, except that the input x of row n is paired with the state of row n + 1."""
    header, rows = read_csv(path)
    col = {n: header.index(n) for n in names}
    n = len(rows) - 1
    moments = {}
    for a in names:
        for b in names:
            if a == "x" and b == "x":
                continue
            if a == "x" or b == "x":
                s = b if a == "x" else a
                moments[(a, b)] = sum(rows[i][col["x"]] * rows[i + 1][col[s]] for i in range(n)) / n
            else:
                moments[(a, b)] = sum(rows[i][col[a]] * rows[i][col[b]] for i in range(n)) / n
    return moments


def estimates(result):
    return {k: v["estimate"] for k, v in result["parameters"].items()}


def tables(long_samples):
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        # Figure 1
        data = os.path.join(tmp, "a.csv")
        simulate("kozin_4_1a", data, RUN, runs=3)
        runs = split_runs(data, tmp)
        out.append("Figure 1, system (4.1a): y' = -y + x (a = 1), runs of 1300 samples\n")
        out.append("      momentid (report's pairing)        | report (Kozin & Kozin 1967)   | momentid")
        out.append("run   E{y^2}    E{xy}     a              | E{y^2}    E{xy}     a         | consistent a")
        for i, path in enumerate(runs):
            m = report_moments(path, ["y", "x"])
            end, consistent = identify("kozin_4_1a", path, "end"), identify("kozin_4_1a", path, "consistent")
            r = FIGURE_1[i]
            out.append(f"{i + 1:<5} {m[('y', 'y')]:<9.4f} {m[('x', 'y')]:<9.4f} {estimates(end)['a']:<14.4f} | "
                       f"{r[0]:<9.4f} {r[1]:<9.4f} {r[2]:<9.4f} | {estimates(consistent)['a']:.4f}")
        # Figure 2
        out.append("\nFigure 2, systems (4.1b) a = 4, b = 16 and (4.1c) a = 5, b = 100, runs of 1300 samples\n")
        out.append("             E{y1^2}  E{y1y2}  E{y2^2}  E{y1x}   E{y2x}   a        b        | consistent a, b")
        for model in ["kozin_4_1b", "kozin_4_1c"]:
            data = os.path.join(tmp, model + ".csv")
            simulate(model, data, RUN, runs=3)
            for i, path in enumerate(split_runs(data, tmp)):
                m = report_moments(path, ["y1", "y2", "x"])
                e = estimates(identify(model, path, "end"))
                c = estimates(identify(model, path, "consistent"))
                r = FIGURE_2[model][i]
                label = "(4.1" + model[-1] + ")"
                out.append(f"{label} {i + 1} ours {m[('y1', 'y1')]:<8.4f} {m[('y1', 'y2')]:<8.4f} "
                           f"{m[('y2', 'y2')]:<8.4f} {m[('x', 'y1')]:<8.4f} {m[('x', 'y2')]:<8.4f} "
                           f"{e['a']:<8.4f} {e['b']:<8.3f} | {c['a']:.4f}, {c['b']:.3f}")
                out.append(f"        report {r[0]:<8.4f} {r[1]:<8.4f} {r[2]:<8.4f} {r[3]:<8.4f} {r[4]:<8.4f} "
                           f"{r[5]:<8.4f} {r[6]:<8.3f} |")
        # Figure 3
        out.append("\nFigure 3, system (4.1d) a = 3, b = 9, c = 4, d = 16, two runs of 1300 samples\n")
        data = os.path.join(tmp, "d.csv")
        simulate("kozin_4_1d", data, RUN, runs=2)
        names = ["y1", "y2", "y3", "y4", "x"]
        for i, path in enumerate(split_runs(data, tmp)):
            m = report_moments(path, names)
            ref, ref_est = FIGURE_3[i]
            out.append(f"Run {i + 1}: momentid (report's values in parentheses)")
            out.append("      " + "".join(f"{c:<18}" for c in names[:4]))
            for row in names:
                cells = []
                for c in names[:4]:
                    if names.index(c) > names.index(row) or c == row == "x":
                        break
                    cells.append(f"{m[(row, c)]:7.4f} ({ref[(row, c)]:7.4f}) ")
                out.append(f"{row:<6}" + "".join(cells))
            e = estimates(identify("kozin_4_1d", path, "end"))
            c = estimates(identify("kozin_4_1d", path, "consistent"))
            out.append("  estimates, report's pairing: " +
                       ", ".join(f"{k} = {e[k]:.4f} ({v:.4f})" for k, v in zip("abcd", ref_est)))
            out.append("  estimates, consistent:       " + ", ".join(f"{k} = {c[k]:.4f}" for k in "abcd"))
            out.append("")
        # Long records
        out.append(f"The same systems from {long_samples} samples (dt = {DT}, zoh-consistent moments)\n")
        out.append("system   parameter  truth    estimate      std error    relative error")
        for model, truth in TRUTH.items():
            data = os.path.join(tmp, model + "_long.csv")
            simulate(model, data, long_samples)
            result = identify(model, data, "consistent", batches=50)
            for name, value in truth.items():
                p = result["parameters"][name]
                out.append(f"(4.1{model[-1]})   {name:<10} {value:<8g} {p['estimate']:<13.6g} "
                           f"{p['std_error']:<12.3g} {(p['estimate'] - value) / value:+.3%}")
    return "\n".join(out)


def bias(samples):
    """Relative bias of each parameter against K, per system and pairing."""
    ks = [2, 3, 5, 10, 20, 50]
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for model in ["kozin_4_1a", "kozin_4_1b", "kozin_4_1c"]:
            for k in ks:
                data = os.path.join(tmp, "b.csv")
                # Weights 1/K keep the input's low-frequency level the same for every K.
                simulate(model, data, samples, input_spec=f"ma:K={k},w={1 / k!r},sigma=15")
                for pairing in PAIRINGS:
                    est = estimates(identify(model, data, pairing, batches=20))
                    for name, value in TRUTH[model].items():
                        key = f"{model}:{name}:{pairing}"
                        results.setdefault(key, []).append((k, (est[name] - value) / value))
    return {"K": ks, "samples": samples, "dt": DT, "bias": results}


def plot(bias_json, out_path):
    """A log-log plot of |relative bias| against K: one panel per system and parameter, a line
    per pairing; circles mark estimates biased up, squares estimates biased down."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    with open(bias_json) as f:
        data = json.load(f)
    pairings = {"end": ("#c0392b", "x_n with y_(n+1) (the report's program)"),
                "start": ("#2471a3", "x_n with y_n"),
                "consistent": ("#1e8449", "x_n with the interval's y (zoh)")}
    panels = [("kozin_4_1a", "a", "(4.1a) first order, a"), ("kozin_4_1b", "a", "(4.1b) oscillator, a"),
              ("kozin_4_1b", "b", "(4.1b) oscillator, b"), ("kozin_4_1c", "a", "(4.1c) oscillator, a"),
              ("kozin_4_1c", "b", "(4.1c) oscillator, b")]
    floor = 1e-6
    figure, axes = plt.subplots(2, 3, figsize=(9, 5.6), sharey=True)
    for ax, (model, name, title) in zip(axes.flat, panels):
        for pairing, (color, _) in pairings.items():
            points = data["bias"][f"{model}:{name}:{pairing}"]
            ks = [k for k, _ in points]
            ax.plot(ks, [max(abs(b), floor) for _, b in points], color=color, linewidth=1.5)
            for marker, up in (("o", True), ("s", False)):
                chosen = [(k, max(abs(b), floor)) for k, b in points if (b >= 0) == up]
                ax.plot([k for k, _ in chosen], [v for _, v in chosen], marker, color=color, markersize=5)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlim(data["K"][0] / 1.15, data["K"][-1] * 1.15)
        ax.set_ylim(floor, 1)
        ax.set_xticks(data["K"])
        ax.set_xticks([], minor=True)
        ax.set_xticklabels([str(k) for k in data["K"]])
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="major", color="#ddd")
    for ax in (axes[0, 2], axes[1, 0], axes[1, 1]):
        ax.set_xlabel("K (samples averaged)")
    for ax in axes[:, 0]:
        ax.set_ylabel("|relative bias|")
    legend = axes.flat[-1]
    legend.axis("off")
    handles = [Line2D([], [], color=color, linewidth=2, label=label) for color, label in pairings.values()]
    handles += [Line2D([], [], marker="o", linestyle="", color="black", label="biased up"),
                Line2D([], [], marker="s", linestyle="", color="black", label="biased down")]
    legend.legend(handles=handles, loc="center", fontsize=9, frameon=False,
                  title=f"{data['samples']} samples, dt = {data['dt']:g}", title_fontsize=9)
    figure.tight_layout()
    figure.savefig(out_path, dpi=100)
    plt.close(figure)


def main():
    if len(sys.argv) >= 2 and sys.argv[1] == "tables":
        long_samples = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[2] == "--long" else 1000000
        print(tables(long_samples))
    elif len(sys.argv) >= 2 and sys.argv[1] == "bias":
        samples = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[2] == "--samples" else 200000
        print(json.dumps(bias(samples), indent=1))
    elif len(sys.argv) == 4 and sys.argv[1] == "plot":
        plot(sys.argv[2], sys.argv[3])
    else:
        print(__doc__)
        sys.exit(1)


if __name__ == "__main__":
    main()
