#!/usr/bin/env python3
"""Strut lattices: a 3D-printing infill of thin square struts, each its own closed box.

Usage: bench/make_lattice.py OUT_DIR [--cells N ...] [--thickness T] [--coincident]
Writes lattice_N.stl (binary STL) for each N (default 6, 8, 10): N^3 cubic cells of side 10,
a strut along every cell edge, each strut a separate box reaching past its nodes, so the
struts overlap and intersect at every node (an unmerged export); the whole lattice is turned
off the axes. The struts along x are T x the cell side thick (default 0.05: about a third of a
base cell at --base-size 1 %), those along y and z 0.9 and 0.8 of that, so no faces coincide;
with --coincident all are T thick, and at every node struts share corners, edges (welded,
four or more triangles) and overlapping coplanar faces. Pure Python, deterministic.
"""
import argparse
import math

from mesh_files import add_box, box_corners, write_named

SIDE = 10.0


def turn(p):
    """A fixed turn about an oblique axis, so no strut runs along the lattice."""
    ax, ay, az = 0.3, -0.5, 0.81
    n = math.sqrt(ax * ax + ay * ay + az * az)
    ax, ay, az = ax / n, ay / n, az / n
    c, s = math.cos(0.6), math.sin(0.6)
    x, y, z = p
    d = ax * x + ay * y + az * z
    cx, cy, cz = ay * z - az * y, az * x - ax * z, ax * y - ay * x
    return (x * c + cx * s + ax * d * (1 - c), y * c + cy * s + ay * d * (1 - c),
            z * c + cz * s + az * d * (1 - c))


def lattice(cells, thickness, coincident):
    points, triangles = [], []
    for axis in range(3):
        h = thickness * SIDE / 2 * (1.0 if coincident else (1.0, 0.9, 0.8)[axis])
        for i in range(cells + 1):
            for j in range(cells + 1):
                for k in range(cells):
                    lo, hi = [0.0] * 3, [0.0] * 3
                    u, v = (axis + 1) % 3, (axis + 2) % 3
                    lo[u], hi[u] = i * SIDE - h, i * SIDE + h
                    lo[v], hi[v] = j * SIDE - h, j * SIDE + h
                    lo[axis], hi[axis] = k * SIDE - h, (k + 1) * SIDE + h
                    add_box(points, triangles, [turn(c) for c in box_corners(lo, hi)])
    return points, triangles


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out")
    parser.add_argument("--cells", type=int, nargs="+", default=[6, 8, 10])
    parser.add_argument("--thickness", type=float, default=0.05)
    parser.add_argument("--coincident", action="store_true")
    args = parser.parse_args()
    suffix = "_coincident" if args.coincident else ""
    write_named(args.out, [(f"lattice_{n}{suffix}", lambda n=n: lattice(n, args.thickness, args.coincident))
                           for n in args.cells])

if __name__ == "__main__":
    main()
