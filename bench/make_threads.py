#!/usr/bin/env python3
"""Threaded rods: sharp helical crests and roots, oblique to the lattice everywhere.

Usage: bench/make_threads.py OUT_DIR
Writes (binary STL):
- screw.stl: a closed rod (radius 5, length 30) with a 60-degree V thread (depth 0.8, pitch 2),
  on a grid of 180 columns around and 16 rows per pitch, capped by fans at both ends;
- thread_open.stl: the same thread on helical rows (its crests and roots on vertex rows),
  open at the ends, where the rows clamped to the end planes fold into non-manifold,
  self-intersecting fans (a dirty export).
Pure Python, deterministic.
"""
import math
import sys

from mesh_files import revolved, write_named

R, DEPTH, PITCH, LENGTH = 5.0, 0.8, 2.0, 30.0


def radius(theta, z):
    s = ((z - PITCH * theta / (2 * math.pi)) / PITCH) % 1.0
    return R - DEPTH * abs(2 * s - 1)


def screw(columns=180, rows_per_pitch=16):
    return revolved(radius, columns, int(LENGTH / PITCH * rows_per_pitch), LENGTH)


def open_thread(columns=120, rows_per_pitch=8):
    rows = int(LENGTH / PITCH * rows_per_pitch) + 2 * rows_per_pitch
    points, triangles, index = [], [], {}

    def vertex(i, j):
        if i == columns:  # once around: the same helix one pitch on
            i, j = 0, j + rows_per_pitch
        if (i, j) not in index:
            th = 2 * math.pi * i / columns
            u = PITCH * (j - rows_per_pitch) / rows_per_pitch
            s = (u / PITCH) % 1.0
            r = R - DEPTH * abs(2 * s - 1)
            z = min(max(u + PITCH * i / columns, 0.0), LENGTH)
            index[(i, j)] = len(points)
            points.append((r * math.cos(th), r * math.sin(th), z))
        return index[(i, j)]

    for j in range(rows - rows_per_pitch):
        for i in range(columns):
            a, b, c, d = vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)
            triangles += [(a, b, c), (a, c, d)]
    return points, triangles


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    write_named(sys.argv[1], [("screw", screw), ("thread_open", open_thread)])

if __name__ == "__main__":
    main()
