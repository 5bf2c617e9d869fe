#!/usr/bin/env python3
"""Runs `vdbwrap repair` on every mesh of a folder that has intersecting triangles and prints
a Markdown table from the reports: regions found / fixed by part 1 / by part 2 / by uniting
crossing closed bodies / left,
intersecting pairs before and after, free and non-manifold edges before and after, the
largest deviation (fraction of the diagonal) and the time.
Usage: bench/repair_table.py [--vdbwrap build/client/vdbwrap] [--data DIR] [extra repair args...]"""
import argparse, json, os, subprocess, tempfile

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--vdbwrap", default=os.path.join(root, "build", "client", "vdbwrap"))
ap.add_argument("--data", default=os.path.join(root, "tests", "data"))
args, extra = ap.parse_known_args()

rows = []
with tempfile.TemporaryDirectory() as tmp:
    for name in sorted(os.listdir(args.data), key=str.lower):
        if not name.lower().endswith((".stl", ".obj", ".off", ".ply")):
            continue
        out, rep = os.path.join(tmp, "out.ply"), os.path.join(tmp, "rep.json")
        run = subprocess.run([args.vdbwrap, "repair", os.path.join(args.data, name), "-o", out, "--report", rep, "-q",
                              *extra], capture_output=True, text=True)
        if run.returncode not in (0, 4):
            rows.append(f"| {name} | FAILED ({run.returncode}): {run.stderr.strip()} |")
            continue
        r = json.load(open(rep))
        g, b, a = r["regions"], r["before"], r["after"]
        if b["intersecting_pairs"] == 0:
            continue
        rows.append(f"| {name} | {b['triangles']} | {g['found']} | {g['fixed_by_local_operations']} | {g['fixed_by_refill']} | "
                    f"{g.get('fixed_by_union', 0)} | {g['left_unfixed']} | {b['intersecting_pairs']} -> {a['intersecting_pairs']} | "
                    f"{b['border_edges']} -> {a['border_edges']} | {b['nonmanifold_edges']} -> {a['nonmanifold_edges']} | "
                    f"{r['max_deviation_fraction_of_diagonal']:.4f} | {r['total_seconds']:.2f} | {run.returncode} |")
print(f"`vdbwrap repair` with default options{(' ' + ' '.join(extra)) if extra else ''}; deviation: largest two-sided "
      "sampled distance, fraction of the input's diagonal.\n")
print("| model | triangles | regions | fixed part 1 | fixed part 2 | fixed by union | left | intersecting pairs | free edges | non-manifold edges | max deviation | time (s) | exit |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
