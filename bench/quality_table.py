#!/usr/bin/env python3
"""Wraps every mesh of a folder at one base size and prints a Markdown table of the stage-4
quality analysis: each defect kind before and after the post-processing (remeshing of bad
regions, intersection repair), the regions rebuilt, and the distances; with --compare, the
same wrap without remeshing (--no-remesh) for the distances it would have had.
Usage: bench/quality_table.py [--vdbwrap build/client/vdbwrap] [--data tests/data] [--base-size 1%] [--compare] [extra wrap args...]"""
import argparse, json, os, subprocess, tempfile

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("--vdbwrap", default=os.path.join(root, "build", "client", "vdbwrap"))
ap.add_argument("--base-size", default="1%")
ap.add_argument("--data", default=os.path.join(root, "tests", "data"))
ap.add_argument("--compare", action="store_true", help="also wrap with --no-remesh and show its distances")
args, extra = ap.parse_known_args()

KINDS = [("self_intersecting_triangles", "self-int."), ("small_area_triangles", "small area"),
         ("sliver_triangles", "slivers"), ("short_edges", "short edges"), ("long_edges", "long edges"),
         ("normal_deviation_triangles", "poor normals"), ("lost_feature_samples", "lost feature samples")]


def wrap(path, tmp, more):
    out, rep = os.path.join(tmp, "out.stl"), os.path.join(tmp, "rep.json")
    run = subprocess.run([args.vdbwrap, "wrap", path, "-o", out, "--report", rep, "--base-size", args.base_size, "-q",
                          *extra, *more], capture_output=True, text=True)
    if run.returncode != 0:
        return None, f"FAILED ({run.returncode}): {run.stderr.strip()}"
    return json.load(open(rep)), ""


def distances(r):
    d, i, e = r["distance_output_to_input"], r["distance_input_to_output"], r["distance_sharp_edges_to_output"]
    edges = f"{e['mean_percent_of_diagonal']:.4f}" if e.get("samples") else "-"
    return f"{d['mean_percent_of_diagonal']:.4f} / {i['max_percent_of_diagonal']:.3f} / {edges}"


rows = []
with tempfile.TemporaryDirectory() as tmp:
    for name in sorted(os.listdir(args.data), key=str.lower):
        if not name.lower().endswith((".stl", ".obj", ".off", ".ply")):
            continue
        r, why = wrap(os.path.join(args.data, name), tmp, [])
        if r is None:
            rows.append(f"| {name} | {why} |" + " |" * (len(KINDS) + 5))
            continue
        q = r["quality"]
        b, a, m = q["before"], q["after"], q["remesh"]
        stages = {s["name"]: s["seconds"] for s in r["stages"]}
        cells = [f"{b[k]} → {a[k]}" for k, _ in KINDS]
        valid = "yes" if r["output"]["valid_closed_surface"] and r["output"]["intersecting_triangles"] == 0 else "NO"
        regions = f"{m['regions']}: {m['rebuilt_on_input']} + {m['rebuilt_by_ear_clipping']}"
        if q["intersection_repair"]["runs"]:
            regions += f"; repair {q['intersection_repair']['intersecting_triangles_before']} → {q['intersection_repair']['intersecting_triangles_after']}"
        dist = distances(r)
        if args.compare:
            r0, _ = wrap(os.path.join(args.data, name), tmp, ["--no-remesh"])
            dist = (distances(r0) if r0 else "failed") + " → " + dist
        rows.append(f"| {name} | {b['triangles']} → {a['triangles']} | " + " | ".join(cells) +
                    f" | {b['min_angle_deg']:.2f}° → {a['min_angle_deg']:.2f}° | {regions} | {valid} | {dist} | "
                    f"{stages.get('remesh', 0) + stages.get('quality', 0):.2f} | {r['total_seconds']:.2f} |")

print(f"Base size {args.base_size}, default options{(' ' + ' '.join(extra)) if extra else ''}. Counts before → after the "
      "post-processing; regions: tried: rebuilt on the input + by ear clipping. Distances (% of the diagonal): mean wrap → "
      "input / max input → wrap / mean sharp edges → wrap" + (" (without remeshing → with)" if args.compare else "") + ".\n")
print("| model | triangles | " + " | ".join(h for _, h in KINDS) +
      " | min angle | regions | valid | distances | quality + remesh (s) | total (s) |")
print("|---" * (len(KINDS) + 8) + "|")
print("\n".join(rows))
