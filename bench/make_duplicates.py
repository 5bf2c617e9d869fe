#!/usr/bin/env python3
"""A part placed more than once a hair apart, as exports and slicers' plates make it.

Usage: bench/make_duplicates.py OUT_DIR MESH...
Writes, per MESH (STL or OBJ) named NAME (binary STL):
- NAME_moved.stl: the part three times, as given and moved by +-d (1, 0.5, 0), with d a hundredth
  of a percent of the diagonal (a fiftieth of a finest cell at --base-size 1 %): a body exported
  twice over with rounded placements;
- NAME_turned.stl: as given, moved by +d, and turned by a milliradian about z through the box's
  centre (copies that cross at a shallow angle along every face);
- NAME_retessellated.stl: as given, and again with every triangle split in three at its centroid
  (one CAD body tessellated twice: the faces coincide, the edges coincide, no triangle is a
  duplicate of another).
Pure Python, deterministic.
"""
import math
import os
import sys

from mesh_files import read_triangles, write_stl


def indexed(tris):
    points, index, triangles = [], {}, []
    for t in tris:
        ids = []
        for k in range(3):
            p = tuple(t[3 * k:3 * k + 3])
            if p not in index:
                index[p] = len(points)
                points.append(p)
            ids.append(index[p])
        triangles.append(tuple(ids))
    return points, triangles


def copies(points, triangles, placements):
    """The mesh once per placement (a function of a point), as one mesh."""
    out_p, out_t = [], []
    for place in placements:
        base = len(out_p)
        out_p += [place(p) for p in points]
        out_t += [(a + base, b + base, c + base) for a, b, c in triangles]
    return out_p, out_t


def retessellated(points, triangles):
    out_p, out_t = list(points), list(triangles)
    for a, b, c in triangles:
        m = len(out_p)
        out_p.append(tuple((points[a][k] + points[b][k] + points[c][k]) / 3 for k in range(3)))
        out_t += [(a, b, m), (b, c, m), (c, a, m)]
    return out_p, out_t


def main():
    if len(sys.argv) < 3 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    out_dir = sys.argv[1]
    os.makedirs(out_dir, exist_ok=True)
    for path in sys.argv[2:]:
        points, triangles = indexed(read_triangles(path))
        lo = [min(p[k] for p in points) for k in range(3)]
        hi = [max(p[k] for p in points) for k in range(3)]
        d = 1e-4 * math.dist(lo, hi)
        c = [(lo[k] + hi[k]) / 2 for k in range(3)]
        cos, sin = math.cos(1e-3), math.sin(1e-3)

        def turned(p):
            x, y = p[0] - c[0], p[1] - c[1]
            return (c[0] + x * cos - y * sin, c[1] + x * sin + y * cos, p[2])

        name = os.path.splitext(os.path.basename(path))[0]
        same = lambda p: p  # noqa: E731
        plus = lambda p: (p[0] + d, p[1] + 0.5 * d, p[2])  # noqa: E731
        minus = lambda p: (p[0] - d, p[1] - 0.5 * d, p[2])  # noqa: E731
        for suffix, (pts, tris) in (("moved", copies(points, triangles, (same, plus, minus))),
                                    ("turned", copies(points, triangles, (same, plus, turned))),
                                    ("retessellated", retessellated(points, triangles))):
            write_stl(os.path.join(out_dir, f"{name}_{suffix}.stl"), pts, tris)
            print(f"{name}_{suffix}.stl: {len(tris)} triangles")


if __name__ == "__main__":
    main()
