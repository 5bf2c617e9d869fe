#!/usr/bin/env python3
"""The defects of real files, made on real meshes: cracks, holes and flipped faces.

Usage: bench/make_soups.py OUT_DIR MESH...
Writes, per MESH named NAME (binary STL):
- NAME_soup.stl: every triangle with its own three corners, each coordinate moved by up to a
  millionth of the diagonal (ten times the weld): a soup written with rounded coordinates,
  cracks along every edge;
- NAME_holes.stl: the triangles whose centroid lies within 2 % of the diagonal of one of 30
  random triangles' centroids removed (a scan's holes);
- NAME_flip.stl: 30 % of the triangles turned over (an export that lost the orientation);
- NAME_all.stl: the holes, then the flips and the soup's cracks together;
- NAME_gaps.stl: the soup with each coordinate moved by up to a thousandth of the diagonal
  (an exporter's tolerance: gaps up to a fifth of a base cell at --base-size 1%, the faces
  tilted by as much);
- NAME_tol.stl: the soup with each coordinate moved by up to a ten-thousandth of the diagonal
  (a CAD exporter's tolerance: a hairline to the crack test, five times the surface offset).
Pure Python, deterministic (seed 7).
"""
import math
import os
import random
import sys

from mesh_files import read_triangles, write_stl


def write_soup(path, tris):
    points = [t[3 * k:3 * k + 3] for t in tris for k in range(3)]
    write_stl(path, points, [(3 * i, 3 * i + 1, 3 * i + 2) for i in range(len(tris))])


def centroid(t):
    return ((t[0] + t[3] + t[6]) / 3, (t[1] + t[4] + t[7]) / 3, (t[2] + t[5] + t[8]) / 3)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for path in sys.argv[2:]:
        name = os.path.splitext(os.path.basename(path))[0]
        tris = [tuple(t) for t in read_triangles(path)]
        lo = [min(min(t[i::3]) for t in tris) for i in range(3)]
        hi = [max(max(t[i::3]) for t in tris) for i in range(3)]
        diag = math.dist(lo, hi)
        rng = random.Random(7)

        def cracked(ts, amount=1e-6):
            return [tuple(c + rng.uniform(-1, 1) * amount * diag for c in t) for t in ts]

        def flipped(ts):
            return [t[0:3] + t[6:9] + t[3:6] if rng.random() < 0.3 else t for t in ts]

        write_soup(os.path.join(out, f"{name}_soup.stl"), cracked(tris))
        centres = [centroid(rng.choice(tris)) for _ in range(30)]
        holes = [t for t in tris if all(math.dist(centroid(t), c) > 0.02 * diag for c in centres)]
        write_soup(os.path.join(out, f"{name}_holes.stl"), holes)
        write_soup(os.path.join(out, f"{name}_flip.stl"), flipped(tris))
        write_soup(os.path.join(out, f"{name}_all.stl"), cracked(flipped(holes)))
        write_soup(os.path.join(out, f"{name}_gaps.stl"), cracked(tris, 1e-3))
        write_soup(os.path.join(out, f"{name}_tol.stl"), cracked(tris, 1e-4))
        print(f"{name}: {len(tris)} triangles, {len(holes)} with holes")


if __name__ == "__main__":
    main()
