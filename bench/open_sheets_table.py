#!/usr/bin/env python3
"""Distances, held-back nodes, validity and time of vdbwrap (and, with --alpha, CGAL's alpha
wrap) on the given inputs, as a Markdown table (issue 35: open sheets and max distance).

Usage: bench/open_sheets_table.py [--base-size 1%] [--alpha] [--build build] [--vdbwrap PATH]
       [--label NAME] [--extra='WRAP OPTIONS'] FILES...
Distances are output to input, in % of the input's diagonal, from `vdbwrap check --against`
(the same sampling for both tools). One run each: times are indicative only.
"""
import argparse, json, os, subprocess, sys, tempfile, time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--base-size", default="1%")
ap.add_argument("--alpha", action="store_true")
ap.add_argument("--build", default=os.path.join(root, "build"))
ap.add_argument("--vdbwrap")
ap.add_argument("--label", default="vdbwrap")
ap.add_argument("--extra", default="", help="more wrap options, space separated")
ap.add_argument("files", nargs="+")
args = ap.parse_args()
extra = args.extra.split()
vdbwrap = args.vdbwrap or os.path.join(args.build, "client", "vdbwrap")
alpha = os.path.join(args.build, "bench", "alpha_wrap_runner")


def check(mesh, reference, tmp):
    rep = os.path.join(tmp, "check.json")
    subprocess.run([vdbwrap, "check", mesh, "--against", reference, "--report", rep], capture_output=True, check=True)
    r = json.load(open(rep))
    t = r["to_reference"]
    return r["diagnostics"], t["mean_percent_of_diagonal"], t["p95_percent_of_diagonal"], t["max_percent_of_diagonal"]


def row(name, tool, seconds, d, mean, p95, mx, held="-", two="-"):
    valid = "yes" if d["valid_closed_surface"] else "NO"
    return f"| {name} | {tool} | {seconds:.2f} | {d['triangles']} | {valid} | {mean:.4f} | {p95:.4f} | {mx:.4f} | {held} | {two} |"


print(f"`--base-size {args.base_size}` {' '.join(extra)}; distances output to input in % of the diagonal (vdbwrap check).\n")
print("| model | tool | s | triangles | valid | mean | p95 | max | held back / nodes | two-sided area % |")
print("|---|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for f in args.files:
        name = os.path.basename(f)
        out, rep = os.path.join(tmp, "v.ply"), os.path.join(tmp, "v.json")
        t0 = time.perf_counter()
        p = subprocess.run([vdbwrap, "wrap", f, "-o", out, "--base-size", args.base_size, "-q", "--no-distances", "--report", rep]
                           + extra, capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        if p.returncode != 0:
            print(f"| {name} | {args.label} | {seconds:.2f} | failed ({p.returncode}): {p.stderr.strip()[:200]} |||||||")
        else:
            r = json.load(open(rep))
            pr = r.get("projection", {})
            held = pr.get("nodes_held_back", "-")
            nodes = pr.get("nodes")
            held_txt = f"{held} / {nodes}" if nodes else f"{held}"
            ts = r.get("two_sided", {})
            two = f"{ts['area_percent']:.1f}" if "area_percent" in ts else "-"
            d, mean, p95, mx = check(out, f, tmp)
            print(row(name, args.label, seconds, d, mean, p95, mx, held_txt, two), flush=True)
        if args.alpha:
            out = os.path.join(tmp, "a.ply")
            t0 = time.perf_counter()
            p = subprocess.run([alpha, f, out, repr(1.0 / 100), repr(1.0 / 3000)], capture_output=True, text=True)
            seconds = time.perf_counter() - t0
            if p.returncode != 0:
                print(f"| {name} | alpha wrap | failed ({p.returncode}) |||||||")
                continue
            d, mean, p95, mx = check(out, f, tmp)
            print(row(name, "alpha wrap", seconds, d, mean, p95, mx), flush=True)
