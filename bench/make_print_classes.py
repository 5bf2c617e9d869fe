#!/usr/bin/env python3
"""Surfaces typical of 3D-printing files: knurled grips, a gyroid infill sheet, pixel art, a name tag.

Usage: bench/make_print_classes.py OUT_DIR
Writes (binary STL):
- knurl_coarse.stl, knurl_fine.stl: a closed cylinder (radius 5, length 20) with a diamond
  knurl, sharp ridges crossing at 45 degrees oblique to the lattice everywhere; pitch 0.8 (about
  3 base cells at --base-size 1 %, 126k triangles) and 0.25 (about one cell, 1.29M triangles);
- gyroid.stl: the zero set of sin x cos y + sin y cos z + sin z cos x over two periods, clipped
  to a cube (an open, doubly curved sheet with 2,880 border edges, as a TPMS infill exported as a
  surface), by marching tetrahedra on 48^3 cubes, triangles in no consistent orientation;
- pixel_line.stl: a line of pixel art extruded, 40 square rods 0.05 across and 30 long
  zigzagging, each touching the next along an edge only (welded, those edges have four
  triangles; at 1 % a rod is a sixth of a base cell across);
- name_tag.stl: a tag 100 x 30 x 2 with twelve letters of 3-5 strokes each (boxes 0.6 wide,
  about half a base cell, and 1 high, sunk 0.1 into the tag, crossing each other at random
  angles), every stroke its own closed box, nothing merged;
- lip_plate.stl, lip_plate_low.stl: a plate 10 x 10 x 1 whose far half steps up by 0.004 /
  0.002 (a lip on a print, the step's face a strip between two sharp edges 0.056 of the finest
  cell apart at 1 % / at 0.5 %).
Pure Python, deterministic. Strut lattices: bench/make_lattice.py.
"""
import math
import random
import sys

from mesh_files import add_box, box_corners, revolved, write_named


def knurl(pitch, radius=5.0, length=20.0):
    """Two crossing helical saw-tooth grooves: the radius is the deeper of the two."""
    depth = 0.3 * pitch

    def radius_at(th, z):
        s = radius * th
        a, b = ((s + z) / pitch) % 1.0, ((s - z) / pitch) % 1.0
        return radius - depth * max(abs(2 * a - 1), abs(2 * b - 1))

    return revolved(radius_at, int(2 * math.pi * radius / pitch * 8), int(length / pitch * 8), length)


def gyroid(n=48, periods=2.0):
    h = 2 * math.pi * periods / n
    values = {}

    def value(c):
        if c not in values:
            x, y, z = c[0] * h + 0.01, c[1] * h + 0.02, c[2] * h + 0.03
            values[c] = math.sin(x) * math.cos(y) + math.sin(y) * math.cos(z) + math.sin(z) * math.cos(x)
        return values[c]

    points, triangles, on_edge = [], [], {}

    def vertex(a, b):
        key = (min(a, b), max(a, b))
        if key not in on_edge:
            fa, fb = value(a), value(b)
            t = fa / (fa - fb)
            on_edge[key] = len(points)
            points.append(tuple((a[m] + (b[m] - a[m]) * t) * h for m in range(3)))
        return on_edge[key]

    tetrahedra = [(0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)]
    for i in range(n):
        for j in range(n):
            for k in range(n):
                for tet in tetrahedra:
                    c = [(i + (x & 1), j + ((x >> 1) & 1), k + ((x >> 2) & 1)) for x in tet]
                    below = [q for q in c if value(q) < 0]
                    above = [q for q in c if value(q) >= 0]
                    if len(below) in (1, 3):
                        a, others = (below[0], above) if len(below) == 1 else (above[0], below)
                        triangles.append(tuple(vertex(a, o) for o in others))
                    elif len(below) == 2:
                        (a, b), (c1, d) = below, above
                        q = [vertex(a, c1), vertex(a, d), vertex(b, d), vertex(b, c1)]
                        triangles += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    return points, triangles


def pixel_line(rods=40, size=0.05, length=30.0):
    points, triangles = [], []
    x = y = 0
    for i in range(rods):
        lo, hi = (x * size, y * size, 0.0), ((x + 1) * size, (y + 1) * size, length)
        add_box(points, triangles, box_corners(lo, hi))
        x += 1
        y += 1 if (i // 8) % 2 == 0 else -1
    return points, triangles


def turned_box(points, triangles, centre, size, angle, z0):
    """A box `size` (length, width, height) from height z0, turned by `angle` about z."""
    c, s = math.cos(angle), math.sin(angle)
    corners = []
    for k in range(8):
        x = size[0] / 2 * (1 if k & 1 else -1)
        y = size[1] / 2 * (1 if k & 2 else -1)
        corners.append((centre[0] + c * x - s * y, centre[1] + s * x + c * y, z0 + (size[2] if k & 4 else 0)))
    add_box(points, triangles, corners)


def name_tag(letters=12):
    rng = random.Random(3)
    points, triangles = [], []
    turned_box(points, triangles, (50, 15), (100, 30, 2), 0, 0)
    for ch in range(letters):
        x0 = 5 + ch * 7.8
        for _ in range(rng.randint(3, 5)):
            centre = (x0 + rng.uniform(0, 5), 8 + rng.uniform(0, 14))
            turned_box(points, triangles, centre, (rng.uniform(3, 9), 0.6, 1.0), rng.uniform(0, math.pi), 1.9)
    return points, triangles


def lip_plate(step):
    """The profile (y, z) extruded along x from 0 to 10; the T-joints of the profile kept."""
    profile = [(0, 0), (5, 0), (10, 0), (10, 1), (10, 1 + step), (5, 1 + step), (5, 1), (0, 1)]
    points, triangles, index = [], [], {}

    def at(x, yz):
        q = (x, yz[0], yz[1])
        if q not in index:
            index[q] = len(points)
            points.append(q)
        return index[q]

    def quad(a, b, c, d):
        triangles.extend([(a, b, c), (a, c, d)])

    for i, u in enumerate(profile):
        v = profile[(i + 1) % len(profile)]
        quad(at(0, u), at(0, v), at(10, v), at(10, u))
    for cell in ((0, 1, 6, 7), (1, 2, 3, 6), (6, 3, 4, 5)):
        quad(*(at(10, profile[k]) for k in cell))
        quad(*(at(0, profile[k]) for k in reversed(cell)))
    return points, triangles


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    write_named(sys.argv[1], [("knurl_coarse", lambda: knurl(0.8)), ("knurl_fine", lambda: knurl(0.25)),
                              ("gyroid", gyroid), ("pixel_line", pixel_line), ("name_tag", name_tag),
                              ("lip_plate", lambda: lip_plate(0.004)), ("lip_plate_low", lambda: lip_plate(0.002))])

if __name__ == "__main__":
    main()
