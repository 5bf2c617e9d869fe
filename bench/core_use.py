#!/usr/bin/python3
"""Where do the cores idle? Runs a command (a `vdbwrap wrap` with its progress on stderr, so
without -q), samples its CPU time every 0.1 s from /proc, and charges each sample to the
progress line last printed. Prints, per progress phase, its wall time, the cores in use on
average, and the core-seconds lost (cores available minus cores in use, times the time).

    bench/core_use.py [--cores N] -- build/client/vdbwrap wrap IN -o OUT --base-size 0.25% --no-distances

Linux only (reads /proc/PID/stat). A phase is as fine as the progress messages are.
"""
import argparse, os, subprocess, sys, threading, time

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--cores", type=int, default=os.cpu_count(), help="cores available (default: all)")
parser.add_argument("--interval", type=float, default=0.1, help="seconds between samples")
parser.add_argument("command", nargs=argparse.REMAINDER, help="the command, after --")
args = parser.parse_args()
command = args.command[1:] if args.command[:1] == ["--"] else args.command
if not command:
    parser.error("no command given")

proc = subprocess.Popen(command, stderr=subprocess.PIPE, text=True, bufsize=1)
phase = ["start"]


def follow_progress():
    # Progress lines end in \r (a terminal's redraw) or \n: either ends a message.
    line = ""
    while True:
        ch = proc.stderr.read(1)
        if not ch:
            return
        if ch in "\r\n":
            if line.strip():
                phase[0] = line.strip()
            line = ""
        else:
            line += ch


reader = threading.Thread(target=follow_progress, daemon=True)
reader.start()
ticks = os.sysconf("SC_CLK_TCK")
t0 = time.perf_counter()
previous = None
phases = {}  # phase -> [samples, summed cores], in order of first appearance
while proc.poll() is None:
    try:
        fields = open(f"/proc/{proc.pid}/stat").read().rsplit(")", 1)[1].split()
        cpu = (int(fields[11]) + int(fields[12])) / ticks  # utime + stime
    except (OSError, IndexError, ValueError):
        break
    now = time.perf_counter() - t0
    if previous:
        # "[  12.34s] stage  NN%  message": the stage, its fraction and the message's start,
        # without the time stamp, so that one phase stays one row.
        label = phase[0].split("]", 1)[-1].split()
        key = " ".join(label[:4])[:60]
        entry = phases.setdefault(key, [0, 0.0])
        entry[0] += 1
        entry[1] += (cpu - previous[1]) / (now - previous[0])
    previous = (now, cpu)
    time.sleep(args.interval)
proc.wait()
reader.join(1)

print(f"| phase (progress line) | wall s | cores in use | core-s lost of {args.cores} |")
print("|---|---|---|---|")
lost_total = wall_total = 0.0
for key, (samples, cores) in phases.items():
    wall = samples * args.interval
    mean = cores / samples
    lost = wall * (args.cores - mean)
    lost_total += lost
    wall_total += wall
    print(f"| {key} | {wall:.1f} | {mean:.2f} | {lost:.2f} |")
print(f"| all | {wall_total:.1f} | | {lost_total:.2f} |")
sys.exit(proc.returncode)
