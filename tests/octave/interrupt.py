"""Ctrl-C stops a pass of momentid_identify in Octave: SIGINT sent while a 2*10^7-row record is
read on one thread (about 3 s whole) ends Octave within 1.5 s, without the result.

Run by CTest (octave.interrupt) with MOMENTID_OCTAVE (the built functions) and MOMENTID_SOURCE
(the checkout) set, and the Octave interpreter as its argument.
"""

import os
import signal
import subprocess
import sys
import time

SCRIPT = """
addpath('{functions}');
n = 2e7;
rec = struct('t', (0:n-1)' * 0.01, 'y', randn(n, 1), 'v', randn(n, 1), 'x', randn(n, 1));
disp('reading'); fflush(stdout);
r = momentid_identify('{model}', rec, 'method', 'zero-lag', 'threads', 1);
disp('finished');
"""


def main():
    octave = sys.argv[1]
    script = SCRIPT.format(functions=os.environ["MOMENTID_OCTAVE"],
                           model=os.path.join(os.environ["MOMENTID_SOURCE"], "models",
                                              "duffing.mom"))
    process = subprocess.Popen([octave, "--no-gui", "--norc", "--quiet", "--eval", script],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    line = process.stdout.readline()
    assert line.strip() == "reading", f"expected 'reading', found {line!r}"
    time.sleep(0.3)
    process.send_signal(signal.SIGINT)
    sent = time.monotonic()
    output, _ = process.communicate(timeout=60)
    took = time.monotonic() - sent
    assert "finished" not in output, output
    assert took < 1.5, f"Octave ended {took:.2f} s after Ctrl-C"
    print(f"octave interrupt: ended {took:.2f} s after Ctrl-C, status {process.returncode}")


if __name__ == "__main__":
    main()
