#!/usr/bin/env python3
"""What a gap closure costs away from the openings (issue 35): each input wrapped without gap
closure and with it (and, with --before, by a second build with it), as a Markdown table.

Usage: bench/gap_closure_table.py [--gap 3%] [--base-size 1%] [--vdbwrap PATH] [--before PATH]
       FILES...
Distances are the wrap's own report (output to input, % of the diagonal). A gap closure should
bridge the openings only (holes in a surface, gaps into spaces the volume does not hold); on a
model without any, the wrap with it should be the wrap without it. The count at the end: the
models whose mean and p95 with gap closure are within 10 % of those without. One run each,
builds alternated per model: times are indicative only.
"""
import argparse, json, os, sys, tempfile

from child_peak import run_measured

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--gap", default="3%")
ap.add_argument("--base-size", default="1%")
ap.add_argument("--vdbwrap", default=os.path.join(root, "build", "client", "vdbwrap"))
ap.add_argument("--before", help="a second build, wrapped with the gap closure too")
ap.add_argument("files", nargs="+")
args = ap.parse_args()


def run(binary, mesh, gap, tmp):
    out, rep = os.path.join(tmp, "w.stl"), os.path.join(tmp, "w.json")
    cmd = [binary, "wrap", mesh, "-o", out, "--base-size", args.base_size, "--report", rep, "-q"]
    if gap:
        cmd += ["--gap-closure", gap]
    seconds, _, done = run_measured(cmd)
    if done.returncode != 0:
        return None
    r = json.load(open(rep))
    d, o = r["distance_output_to_input"], r["output"]
    return {"s": seconds, "mean": d["mean_percent_of_diagonal"], "p95": d["p95_percent_of_diagonal"],
            "two": r.get("two_sided", {}).get("area_percent", 0.0), "volume": o["volume"],
            "valid": o["valid_closed_surface"]}


def near(a, b):  # within 10 % of the wrap without gap closure
    return a["mean"] <= 1.1 * b["mean"] and a["p95"] <= 1.1 * b["p95"]


tools = [("before", args.before)] if args.before else []
tools.append(("with", args.vdbwrap))
print(f"`--base-size {args.base_size}`, `--gap-closure {args.gap}`; distances output to input, % of the diagonal.\n")
head = " | ".join(f"{t} s / mean / p95 / two-sided % / volume" for t, _ in tools)
print(f"| model | without: mean / p95 / volume | {head} | valid |")
print("|---|---|" + "---|" * len(tools) + "---|")
counts = {t: 0 for t, _ in tools}
total = 0
with tempfile.TemporaryDirectory() as tmp:
    for f in args.files:
        name = os.path.basename(f)
        plain = run(args.vdbwrap, f, None, tmp)
        rows = [(t, run(b, f, args.gap, tmp)) for t, b in tools]
        if plain is None or any(r is None for _, r in rows):
            print(f"| {name} | failed | " + " | ".join("-" for _ in tools) + " | - |")
            continue
        total += 1
        cells = []
        for t, r in rows:
            counts[t] += near(r, plain)
            cells.append(f"{r['s']:.2f} / {r['mean']:.4f} / {r['p95']:.4f} / {r['two']:.1f} / {r['volume']:.4g}")
        valid = "yes" if plain["valid"] and all(r["valid"] for _, r in rows) else "NO"
        print(f"| {name} | {plain['mean']:.4f} / {plain['p95']:.4f} / {plain['volume']:.4g} | "
              + " | ".join(cells) + f" | {valid} |")
        sys.stdout.flush()
print()
for t, _ in tools:
    print(f"{t}: mean and p95 within 10 % of the wrap without gap closure on {counts[t]} of {total} models")
