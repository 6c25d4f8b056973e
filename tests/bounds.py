#!/usr/bin/python3
"""Hostile inputs end quickly in bounded memory: each case runs the program on an input made
here and asserts its exit status, the start of its message, and loose bounds (an order of
magnitude above what it takes) on its time and peak memory.

  bounds.py MOMENTID WORK_DIRECTORY
"""
import math
import os
import shutil
import subprocess
import sys
import time

momentid, work = sys.argv[1:3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)


def write(name, text):
    path = os.path.join(work, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def run(args):
    """Exit status, standard error, seconds and peak resident memory (MB) of one run."""
    start = time.monotonic()
    process = subprocess.Popen([momentid, *args], stdout=subprocess.DEVNULL,
                               stderr=subprocess.PIPE, text=True)
    stderr = process.stderr.read()
    _, status, usage = os.wait4(process.pid, 0)
    return os.waitstatus_to_exitcode(status), stderr, time.monotonic() - start, usage.ru_maxrss / 1024


failed = 0


def case(name, args, status, message, seconds, megabytes, stderr_bytes=None):
    global failed
    got, stderr, took, peak = run(args)
    first = stderr.splitlines()[0] if stderr else ""
    problems = []
    if got != status:
        problems.append(f"exit {got}, expected {status}")
    if message not in first:
        problems.append(f"message {first[:300]!r}, expected one holding {message!r}")
    if took > seconds:
        problems.append(f"{took:.1f} s, expected under {seconds} s")
    if peak > megabytes:
        problems.append(f"{peak:.0f} MB, expected under {megabytes} MB")
    if stderr_bytes is not None and len(stderr) > stderr_bytes:
        problems.append(f"{len(stderr)} bytes of messages, expected under {stderr_bytes}")
    print(f"{name}: exit {got}, {took:.2f} s, {peak:.0f} MB" +
          (": FAILED: " + "; ".join(problems) if problems else ""))
    failed += bool(problems)


# A CSV file of 10^4 columns and 300 rows (27 MB): check and convert read it in blocks of a
# bounded size (they took 0.5 MB per column).
columns = 10000
header = ",".join(["t", "y", "v", "x"] + [f"c{i}" for i in range(columns)])
row = ",".join(["0.25"] * (columns + 3))
wide = write("wide.csv", header + "\n" + "".join(f"{0.01 * r:g},{row}\n" for r in range(300)))
case("check, 10^4 columns", ["check", wide], 0, "", 20, 500)
case("convert, 10^4 columns", ["convert", wide, os.path.join(work, "wide.bin")], 0, "", 20, 500)

# Models beyond the limits, refused as they are read.
states = 10000
many_states = write("many_states.mom", "state " + ", ".join(f"y{i}" for i in range(states)) +
                    "\ninput x\nparam a\n" +
                    "".join(f"y{i}' = -a*y{i} + x\n" for i in range(states)))
case("10^4 states", ["derive", many_states], 2,
     "'y1000' is one variable too many: a model has at most 1000 states, inputs and measured "
     "columns in all", 5, 1000)
many_parameters = write("many_parameters.mom", "state y\ninput x\nparam " +
                        ", ".join(f"p{i}" for i in range(2000)) + "\ny' = -p0*y + x\n")
case("2000 parameters", ["derive", many_parameters], 2,
     "'p1000' is one parameter too many: a model has at most 1000 parameters", 5, 500)
repeated = write("repeated.mom", "state y, v\ninput x\nparam c\n" + "y' = v\n" * 100000 +
                 "v' = -c*v + x\n")
case("10^5 equations", ["derive", repeated], 2,
     "one equation too many: a model has at most 1000 equations", 5, 1500)
terms = write("terms.mom", "state y\ninput x\nparam c\ny' = -c*y + x" + " + y" * 2000000 + "\n")
case("2*10^6 terms (8 MB)", ["derive", terms], 2,
     "the model goes on past 1048576 bytes: a model's text is at most that long", 5, 200)
case("an endless model file", ["derive", "/dev/zero"], 2,
     "/dev/zero:1:1048577: the model goes on past 1048576 bytes", 5, 200)
# A name of 10^5 characters: refused without quoting it (the message held it whole).
long_name = write("long_name.mom", "state y\ninput x\nparam a\ny' = -a*y + " + "b" * 100000 +
                  "*y + x\n")
case("a name of 10^5 characters", ["derive", long_name], 2,
     "long_name.mom:4:13: a name of 100000 characters: a name has at most 255", 5, 200,
     stderr_bytes=1000)

# 100 parameters on a record of held inputs: the correction for the kinks of the held input
# would take seconds to minutes of symbolic work (it took over 100 s), and is left out, said so.
parameters = 100
model = write("held.mom", "state y, v\ninput x\nparam " +
              ", ".join(f"p{i}" for i in range(parameters)) + "\ny' = v\nv' = " +
              " + ".join(f"-p{i}*y^{i % 7 + 1}*v^{(i // 7) % 2}*x^{(i // 14) % 3}"
                         for i in range(parameters)) + " + x\n")
rows = "".join(f"{0.01 * n:g},{math.sin(0.05 * n):.6g},{math.cos(0.05 * n):.6g},"
               f"{math.sin(0.31 * n) + math.cos(0.17 * n):.6g}\n" for n in range(5000))
held = write("held.csv", "# momentid: dt=0.01 input-hold=zoh\nt,y,v,x\n" + rows)
case("100 parameters, held input", ["identify", model, held, "--batches", "20"], 0, "", 10, 2000)

sys.exit(1 if failed else 0)
