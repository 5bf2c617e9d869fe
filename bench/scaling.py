#!/usr/bin/env python3
"""Scaling benchmark (issue 6): time and peak memory of `vdbwrap wrap` against input size
(the same generated assembly at 1x, 4x, 16x triangles), against base size (2, 1, 0.5,
0.25 %), and with 1 thread against 2; plus the large-input targets (the ~2.3M-triangle
assembly at 0.25 %, the 1M-triangle smooth body). Inputs come from bench/make_inputs
(generated once into bench/data/, which git ignores).

Usage: bench/scaling.py [--build build] [--runs 1] [--out bench/results/DATE.md] [--quick]
Prints Markdown; --out also writes it with the machine's description.
"""
import argparse, datetime, json, os, platform, statistics, subprocess, sys, tempfile

from child_peak import run_measured

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--build", default=os.path.join(root, "build"))
ap.add_argument("--runs", type=int, default=1)
ap.add_argument("--out")
ap.add_argument("--quick", action="store_true", help="skip the 16x input and the 0.25 %% runs")
args = ap.parse_args()
vdbwrap = os.path.join(args.build, "client", "vdbwrap")
make_inputs = os.path.join(args.build, "bench", "make_inputs")
data = os.path.join(root, "bench", "data")
os.makedirs(data, exist_ok=True)


def generated(scene, density):
    path = os.path.join(data, f"{scene}_{density}x.stl")
    if not os.path.exists(path):
        subprocess.run([make_inputs, scene, path, "--density", str(density)], check=True, stdout=subprocess.DEVNULL)
    return path


def run(mesh, base, threads=0):
    """Median wall time, peak RSS (MB), the last report, over args.runs runs."""
    walls, peaks, report = [], [], None
    with tempfile.TemporaryDirectory() as tmp:
        out, rep = os.path.join(tmp, "o.stl"), os.path.join(tmp, "r.json")
        for _ in range(args.runs):
            cmd = [vdbwrap, "wrap", mesh, "-o", out, "--base-size", base, "--no-distances", "-q", "--report", rep]
            if threads:
                cmd += ["--threads", str(threads)]
            wall, peak, proc = run_measured(cmd)
            walls.append(wall)
            peaks.append(peak)
            if proc.returncode != 0:
                return None, None, {"error": proc.stderr.strip()}
            report = json.load(open(rep))
    return statistics.median(walls), max(peaks), report


def triangles(mesh):
    with open(mesh, "rb") as f:
        f.seek(80)
        return int.from_bytes(f.read(4), "little")


def stages(report, top=3):
    st = sorted(report["stages"], key=lambda s: -s["seconds"])[:top]
    return ", ".join(f"{s['name']} {s['seconds']:.1f}" for s in st)


def row(label, mesh, base, threads=0):
    wall, peak, rep = run(mesh, base, threads)
    if wall is None:
        return f"| {label} | {base} | failed: {rep['error']} |"
    out = rep["output"]
    return (f"| {label} | {triangles(mesh):,} | {base} | {threads or 'all'} | {wall:.1f} | {peak:.0f} | {out['triangles']:,} | "
            f"{'yes' if out['valid_closed_surface'] else 'NO'} | {stages(rep)} |")


header = ("| input | input triangles | base size | threads | wall s | peak MB | output triangles | valid | slowest stages (s) |\n"
          "|---|---|---|---|---|---|---|---|---|")
lines = []
def emit(s=""):
    print(s, flush=True)
    lines.append(s)

cpu = ""
try:
    cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
except Exception:
    pass
mem = ""
try:
    mem = f"{int(next(l.split()[1] for l in open('/proc/meminfo') if l.startswith('MemTotal'))) / 1048576:.0f} GiB"
except Exception:
    pass
emit(f"# vdbwrap scaling benchmark, {datetime.date.today().isoformat()}")
emit()
emit(f"Machine: {os.cpu_count()} cores ({cpu}), {mem}, {platform.system()} {platform.release()}. "
     f"Median of {args.runs} run(s); wall time of the whole `vdbwrap wrap` (read, wrap, validate, write), "
     "distances off (`--no-distances`); peak memory is the process's maximum resident set.")
densities = [1, 2] if args.quick else [1, 2, 4]
emit()
emit("## Against input size (the same assembly, finer tessellation), base size 0.5 %")
emit()
emit(header)
for d in densities:
    emit(row(f"assembly {d * d}x", generated("assembly", d), "0.5%"))
emit()
emit("## Against base size (assembly 1x)")
emit()
emit(header)
for base in (["2%", "1%", "0.5%"] + ([] if args.quick else ["0.25%"])):
    emit(row("assembly 1x", generated("assembly", 1), base))
emit()
emit("## 1 thread against 2")
emit()
emit(header)
big = generated("assembly", densities[-1])
smooth = generated("smooth", 1)
for label, mesh in ((f"assembly {densities[-1] ** 2}x", big), ("smooth body", smooth)):
    emit(row(label, mesh, "0.5%", 1))
    emit(row(label, mesh, "0.5%", 2))
if not args.quick:
    emit()
    emit("## Large-input targets (2M-triangle assembly at 0.25 %: under 60 s and 4 GiB)")
    emit()
    emit(header)
    emit(row("assembly 16x", big, "0.25%"))
    emit(row("smooth body", smooth, "0.25%"))
if args.out:
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        f.write("\n".join(lines) + "\n")
