#!/usr/bin/env python3
"""Wraps every mesh in tests/data at one base size and prints a Markdown table:
triangles in/out, time, validity and distances from the report.
Usage: bench/corpus_table.py [--vdbwrap build/client/vdbwrap] [--base-size 1%] [extra wrap args...]"""
import argparse, json, os, subprocess, sys, tempfile, time

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--vdbwrap", default=os.path.join(root, "build", "client", "vdbwrap"))
ap.add_argument("--base-size", default="1%")
ap.add_argument("--data", default=os.path.join(root, "tests", "data"))
args, extra = ap.parse_known_args()

rows = []
with tempfile.TemporaryDirectory() as tmp:
    for name in sorted(os.listdir(args.data), key=str.lower):
        if not name.lower().endswith((".stl", ".obj", ".off", ".ply")):
            continue
        out, rep = os.path.join(tmp, "out.stl"), os.path.join(tmp, "rep.json")
        t0 = time.time()
        run = subprocess.run([args.vdbwrap, "wrap", os.path.join(args.data, name), "-o", out, "--report", rep,
                              "--base-size", args.base_size, "-q", *extra], capture_output=True, text=True)
        wall = time.time() - t0
        if run.returncode != 0:
            rows.append(f"| {name} | - | - | {wall:.2f} | FAILED ({run.returncode}): {run.stderr.strip()} | | | |")
            continue
        r = json.load(open(rep))
        o, d = r["output"], r["distance_output_to_input"]
        valid = "yes" if o["valid_closed_surface"] and not o["self_intersecting"] else "NO"
        e = r.get("distance_sharp_edges_to_output", {})
        edges = (f"{e['mean_percent_of_diagonal']:.4f} / {e['p95_percent_of_diagonal']:.4f}" if e.get("samples") else "-")
        rows.append(f"| {name} | {r['input']['triangles']} | {o['triangles']} | {r['total_seconds']:.2f} | {valid} | "
                    f"{o['intersecting_triangles']} | {d['mean_percent_of_diagonal']:.4f} | {d['p95_percent_of_diagonal']:.4f} | {edges} |")
print(f"Base size {args.base_size}, default options{(' ' + ' '.join(extra)) if extra else ''}; "
      "distances from the wrap to the input as % of the input's bounding-box diagonal.\n")
print("| model | triangles in | triangles out | time (s) | valid (closed, manifold, outward, no self-intersection) | self-intersecting triangles | mean dist % | p95 dist % | sharp edges to wrap, mean / p95 % |")
print("|---|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
