#!/usr/bin/env python3
"""The four generated classes of bench/make_scan_classes.py (a sculpt with subtools, voxel art,
a raw scan strewn with floating fragments, an unmerged three-view scan), small, wrapped by the
CLI at 1.5 %: each exits 0 with a valid surface, at most 1 % of its triangles under 10 degrees,
its mean distance to the input under the class's bound, and its farthest point within a base
cell (a cell and a half on the fragment-strewn scan, whose bridges between a fragment and the
scan are the known exception; bench/results/2026-11-26-new-classes.md).

Standard library only."""
import argparse
import json
import os
import subprocess
import sys

# class file -> (mean distance bound in % of the diagonal, max distance bound in base cells)
BOUNDS = {
    'sculpt_5.stl': (0.05, 1.0),
    'views_5.stl': (0.05, 1.0),
    # Faces where voxels touch are inside: flat where they meet, no feature (0.045 % before).
    'voxels_20.stl': (0.02, 1.0),
    'islands_5.stl': (0.2, 1.5),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--cli', required=True)
    ap.add_argument('--generator', required=True)
    ap.add_argument('--work', required=True)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    subprocess.run([sys.executable, a.generator, a.work, '--level', '5', '--seed', '3', '--fragments', '300'],
                   check=True, stdout=subprocess.DEVNULL)
    failures = []
    for name, (mean_bound, max_bound) in BOUNDS.items():
        path = os.path.join(a.work, name)
        out, report = path[:-4] + '_wrap.ply', path[:-4] + '.json'
        run = subprocess.run([a.cli, 'wrap', path, '-o', out, '--base-size', '1.5%', '-q', '--report', report],
                             capture_output=True, text=True)
        if run.returncode != 0:
            failures.append(f'{name}: exit {run.returncode}: {run.stderr.strip()[-300:]}')
            continue
        r = json.load(open(report))
        d = r['distance_output_to_input']
        tris = r['quality']['after']['triangles']
        slivers = 100.0 * r['quality']['sliver_removal']['slivers_after'] / tris
        max_cells = d['max'] / r['grid']['base_size']
        print(f"{name}: {tris} triangles, valid {r['output']['valid_closed_surface']}, mean "
              f"{d['mean_percent_of_diagonal']:.4f} %, max {max_cells:.3f} base cells, slivers {slivers:.2f} %")
        if not r['output']['valid_closed_surface']:
            failures.append(f'{name}: output not a valid closed surface')
        if slivers > 1.0:
            failures.append(f'{name}: {slivers:.2f} % of triangles under 10 degrees')
        if not d['mean_percent_of_diagonal'] < mean_bound:
            failures.append(f"{name}: mean {d['mean_percent_of_diagonal']:.4f} % >= {mean_bound} %")
        if not max_cells <= max_bound:
            failures.append(f"{name}: max {max_cells:.3f} base cells > {max_bound}")
    for f in failures:
        print('FAIL: ' + f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
