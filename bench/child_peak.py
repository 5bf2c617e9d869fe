"""Wall time and peak memory of one child process, measured from a small parent.

Linux counts the resident size a process had when it called exec into its child's peak
(ru_maxrss): a child started straight from a benchmark script that has grown (meshes read in
Python) reports the script's size, not its own. So each child is started by a fresh
interpreter of a few MB that only waits for it and writes down its figures.
"""
import json
import os
import subprocess
import sys
import tempfile

_WAITER = """
import json, os, subprocess, sys, time
t0 = time.perf_counter()
proc = subprocess.Popen(json.loads(sys.argv[2]))  # stdout and stderr: the waiter's own
_, status, usage = os.wait4(proc.pid, 0)
with open(sys.argv[1], "w") as f:
    json.dump([time.perf_counter() - t0, usage.ru_maxrss, os.waitstatus_to_exitcode(status)], f)
"""


def run_measured(cmd):
    """Runs cmd; returns (wall seconds, peak RSS MB of that child alone, CompletedProcess)."""
    with tempfile.TemporaryDirectory() as tmp:
        figures = os.path.join(tmp, "figures.json")
        waiter = subprocess.run([sys.executable, "-c", _WAITER, figures, json.dumps(cmd)], capture_output=True,
                                text=True)
        if not os.path.exists(figures):  # the waiter itself failed
            return 0.0, 0.0, subprocess.CompletedProcess(cmd, waiter.returncode or 1, waiter.stdout, waiter.stderr)
        wall, peak_kb, code = json.load(open(figures))
    return wall, peak_kb / 1024.0, subprocess.CompletedProcess(cmd, code, waiter.stdout, waiter.stderr)
