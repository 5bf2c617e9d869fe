#!/usr/bin/env python3
"""Rough scans whose noise is as coarse as their triangles: the inputs of
bench/results/2026-11-27-rough-scans.md.

Usage: bench/make_rough_scans.py OUT_DIR
Writes (binary STL):
- range_scan_10.stl, range_scan_30.stl, range_scan_45.stl: a bumpy unit sphere on a regular
  latitude-longitude grid of 400 x 260 (207k triangles, edges about half a base cell at 1 %),
  every vertex moved at random by up to 10, 30 or 45 % of an edge in each coordinate, as a range
  scanner's grid of depth samples: folds over the feature angle at almost every edge, lined up
  along the grid's straight lines, and self-intersections; range_scan_45 keeps the poles'
  duplicated vertices apart (two small holes);
- rough_closed_5.stl, rough_closed_6.stl: an icosphere of 20k or 82k triangles whose vertices'
  coordinates are each scaled by 1 +- up to 5 or 2 % (a watertight reconstruction of a rough
  scan): the closed surface whose thin bumps let the outside into it before 2026-11-27;
- coarse_noise_2.stl, coarse_noise_3.stl, coarse_noise_4.stl: an icosphere of 82k triangles
  (edges 0.02, half a base cell at 1 %) whose vertices each move by up to +-1, 1.5 or 2 % of
  the radius in each coordinate: noise as coarse as the faces, folded over every way and
  crossing the faces around them (bench/results/2026-11-27-coarse-noise.md);
- two_rough_3.stl: two such spheres (+-1.5 %, radii 1 and 0.9, centres 1.2 apart) left
  overlapping, an unmerged union of two rough scans.
Pure Python, deterministic.
"""
import math
import os
import random
import sys

from make_scan_classes import icosphere
from mesh_files import write_stl


def bumpy_sphere(cols, rows, amp, weld_poles=True):
    pts = []
    for j in range(rows + 1):
        ph = math.pi * j / rows
        ring = 1 if weld_poles and j in (0, rows) else cols
        for i in range(ring):
            th = 2 * math.pi * i / cols
            r = 1 + amp * math.sin(5 * th) * math.sin(4 * ph)
            pts.append((r * math.sin(ph) * math.cos(th), r * math.sin(ph) * math.sin(th), r * math.cos(ph)))

    def at(i, j):
        if weld_poles and j == 0:
            return 0
        if weld_poles and j == rows:
            return len(pts) - 1
        return (1 if weld_poles else 0) + (j - (1 if weld_poles else 0)) * cols + (i % cols)

    tris = []
    for j in range(rows):
        for i in range(cols):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            if j > 0:
                tris.append((a, c, b))
            if j < rows - 1:
                tris.append((a, d, c))
    return pts, tris


def jittered(level, centre, radius, seed, share):
    """An icosphere, every coordinate moved by up to +-share/2 of the radius."""
    rng = random.Random(seed)
    pts, tris = icosphere(level)
    pts = [tuple(centre[i] + radius * p[i] + share * radius * (rng.random() - 0.5) for i in range(3)) for p in pts]
    return pts, tris


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    edge = 2 * math.pi / 400
    for share, weld in ((10, True), (30, True), (45, False)):
        rng = random.Random(share)
        pts, tris = bumpy_sphere(400, 260, 0.05, weld)
        e = share / 100 * edge
        pts = [tuple(c + rng.uniform(-e, e) for c in p) for p in pts]
        write_stl(f"{out}/range_scan_{share}.stl", pts, tris)
        print(f"range_scan_{share}.stl: {len(tris)} triangles")
    for level, amp in ((5, 0.05), (6, 0.02)):
        rng = random.Random(level)
        pts, tris = icosphere(level)
        pts = [tuple(c * (1 + rng.uniform(-amp, amp)) for c in p) for p in pts]
        write_stl(f"{out}/rough_closed_{level}.stl", pts, tris)
        print(f"rough_closed_{level}.stl: {len(tris)} triangles")
    for share in (2, 3, 4):
        pts, tris = jittered(6, (0, 0, 0), 1, 1, share / 100)
        write_stl(f"{out}/coarse_noise_{share}.stl", pts, tris)
        print(f"coarse_noise_{share}.stl: {len(tris)} triangles")
    pts, tris = jittered(6, (0, 0, 0), 1, 1, 0.03)
    more, more_tris = jittered(6, (1.2, 0.3, 0.1), 0.9, 2, 0.03)
    tris = tris + [tuple(v + len(pts) for v in t) for t in more_tris]
    write_stl(f"{out}/two_rough_3.stl", pts + more, tris)
    print(f"two_rough_3.stl: {len(tris)} triangles")


if __name__ == "__main__":
    main()
