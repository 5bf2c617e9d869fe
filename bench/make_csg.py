#!/usr/bin/env python3
"""Surfaces as CSG and CAD exports make them: through-holes, T-junctions, fans, overlapping solids.

Usage: bench/make_csg.py OUT_DIR
Writes (binary STL):
- csg_plate.stl: a plate 100 x 60 x 8 with 37 round through-holes 3-8 across (2.6-6.8 base cells
  at --base-size 1 %; 40-gons), its faces triangulated cell by cell on a 10 x 6 grid as a
  boolean's export does: a hole's cell fans from its rim to eight border points, the corners and
  the side midpoints, where its plain neighbours have a corner only (T-junctions); the fans'
  triangles are long slivers and overlap in their plane (a broken boolean's export: 254 of the
  two-hole plate's 592 triangles intersect);
- csg_plate_clean.stl: the same plate, each hole's cell a clean strip between its border and the
  rim (T-junctions only), faces outward;
- csg_plate_two_holes.stl: the same plate with two of its holes only (3.1 and 3.9 across, in
  neighbouring cells): the plate the refit's trigger missed (tests/data);
- csg_union.stl: a slab with twelve boxes, cylinders and spheres stuck into and through it, every
  solid its own closed surface, nothing merged (a union exported without the boolean), the
  cylinders' caps fans from one rim point;
- csg_outlier.stl: a smaller holed plate and one stray triangle half a unit across, 800 units
  away (an export with a stray fragment: the diagonal, so the base cell, is the stray's).
Pure Python, deterministic.
"""
import math
import random
import sys

from mesh_files import write_named

CELL = 10.0


def hole_radii(nx, ny, seed=1):
    """The plate's holes by cell: three in five cells have one, radius 0.15-0.4 of the cell."""
    rnd = random.Random(seed)
    holes = {}
    for i in range(nx):
        for j in range(ny):
            if rnd.random() < 0.6:
                holes[(i, j)] = CELL * (0.15 + 0.25 * rnd.random())
    return holes


def plate(nx, ny, holes, thickness=8.0, segments=40, broken=True):
    """Points and triangles (unwelded, three points each) of the plate, holes {(i, j): radius}.
    broken: a hole's cell as overlapping fans; else a clean strip between the cell's border and
    the rim, faces outward."""
    tris = []

    def flat(a, b, c, z):
        tris.append(((a[0], a[1], z), (b[0], b[1], z), (c[0], c[1], z)))

    for i in range(nx):
        for j in range(ny):
            x0, y0, x1, y1 = i * CELL, j * CELL, (i + 1) * CELL, (j + 1) * CELL
            if (i, j) not in holes:
                for z in (thickness, 0.0):
                    flat((x0, y0), (x1, y0), (x1, y1), z)
                    flat((x0, y0), (x1, y1), (x0, y1), z)
                continue
            r, cx, cy = holes[(i, j)], x0 + CELL / 2, y0 + CELL / 2
            ring = [(cx + r * math.cos(2 * math.pi * k / segments), cy + r * math.sin(2 * math.pi * k / segments))
                    for k in range(segments)]
            border = [(x1, y0), (x1, (y0 + y1) / 2), (x1, y1), ((x0 + x1) / 2, y1), (x0, y1), (x0, (y0 + y1) / 2),
                      (x0, y0), ((x0 + x1) / 2, y0)]
            angle = [math.atan2(b[1] - cy, b[0] - cx) % (2 * math.pi) for b in border]

            def nearest_border(a):
                return min(range(8), key=lambda m: min(abs(angle[m] - a), 2 * math.pi - abs(angle[m] - a)))

            if not broken:
                tris += annulus(border, ring, (cx, cy), thickness)
                continue
            for z in (thickness, 0.0):
                for k in range(segments):  # a fan from each rim edge to a border point
                    mid = (2 * math.pi * k / segments + 2 * math.pi * (k + 1) / segments) / 2
                    flat(ring[k], ring[(k + 1) % segments], border[nearest_border(mid)], z)
                for m in range(8):  # and from each border edge to a rim point
                    p, q = border[m], border[(m + 1) % 8]
                    a = math.atan2((p[1] + q[1]) / 2 - cy, (p[0] + q[0]) / 2 - cx) % (2 * math.pi)
                    flat(q, p, ring[int(round(a / (2 * math.pi) * segments)) % segments], z)
                if z == thickness:  # the hole's wall, after the top's fans (the results depend on the order)
                    for k in range(segments):
                        a, b = ring[k], ring[(k + 1) % segments]
                        tris.append(((a[0], a[1], 0.0), (b[0], b[1], 0.0), (b[0], b[1], thickness)))
                        tris.append(((a[0], a[1], 0.0), (b[0], b[1], thickness), (a[0], a[1], thickness)))
    X, Y = nx * CELL, ny * CELL
    for a, b in (((0, 0), (X, 0)), ((X, 0), (X, Y)), ((X, Y), (0, Y)), ((0, Y), (0, 0))):
        tris.append(((a[0], a[1], 0), (b[0], b[1], 0), (b[0], b[1], thickness)))
        tris.append(((a[0], a[1], 0), (b[0], b[1], thickness), (a[0], a[1], thickness)))
    return soup(tris)


def annulus(border, ring, centre, thickness):
    """A hole's cell, clean: top and bottom each a strip between the border and the rim, merged
    by angle around the centre (outward normals), and the hole's wall facing its axis."""
    def by_angle(points, start):  # sorted by angle, from the last one at or before `start`
        a = [math.atan2(p[1] - centre[1], p[0] - centre[0]) % (2 * math.pi) for p in points]
        order = sorted(range(len(points)), key=lambda k: a[k])
        first = max([n for n, k in enumerate(order) if a[k] <= start], default=len(order) - 1)
        order = order[first:] + order[:first]
        angles = [a[k] for k in order]
        angles = [angles[0] - 2 * math.pi if angles[0] > start else angles[0]] + angles[1:]
        angles = [x + 2 * math.pi if n and x < angles[0] else x for n, x in enumerate(angles)]
        return [points[k] for k in order], angles + [angles[0] + 2 * math.pi]

    inner, a_in = by_angle(ring, 0.0)
    outer, a_out = by_angle(border, a_in[0])
    strip, i, k, n_in, n_out = [], 0, 0, len(inner), len(outer)
    while i < n_out or k < n_in:
        if k < n_in and (i == n_out or a_in[k + 1] <= a_out[i + 1]):
            strip.append((inner[k], outer[i % n_out], inner[(k + 1) % n_in]))
            k += 1
        else:
            strip.append((outer[i], outer[(i + 1) % n_out], inner[k % n_in]))
            i += 1
    out = []
    for a, b, c in strip:  # counter-clockwise seen from above: the top's normal up
        out.append(((a[0], a[1], thickness), (b[0], b[1], thickness), (c[0], c[1], thickness)))
        out.append(((a[0], a[1], 0.0), (c[0], c[1], 0.0), (b[0], b[1], 0.0)))
    for k in range(len(inner)):
        a, b = inner[k], inner[(k + 1) % len(inner)]
        out.append(((a[0], a[1], 0.0), (a[0], a[1], thickness), (b[0], b[1], thickness)))
        out.append(((a[0], a[1], 0.0), (b[0], b[1], thickness), (b[0], b[1], 0.0)))
    return out


def soup(tris):
    points = [p for t in tris for p in t]
    return points, [(3 * k, 3 * k + 1, 3 * k + 2) for k in range(len(tris))]


def box(c, s):
    lo = [c[k] - s[k] / 2 for k in range(3)]
    hi = [c[k] + s[k] / 2 for k in range(3)]
    v = [(lo[0], lo[1], lo[2]), (hi[0], lo[1], lo[2]), (hi[0], hi[1], lo[2]), (lo[0], hi[1], lo[2]),
         (lo[0], lo[1], hi[2]), (hi[0], lo[1], hi[2]), (hi[0], hi[1], hi[2]), (lo[0], hi[1], hi[2])]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5), (2, 3, 7),
             (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return [tuple(v[i] for i in f) for f in faces]


def cylinder(c, r, h, axis, segments=48):
    def at(a, z):
        u, v = r * math.cos(a), r * math.sin(a)
        return {0: (c[0] + z, c[1] + u, c[2] + v), 1: (c[0] + u, c[1] + z, c[2] + v),
                2: (c[0] + u, c[1] + v, c[2] + z)}[axis]

    out = []
    for k in range(segments):
        a0, a1 = 2 * math.pi * k / segments, 2 * math.pi * (k + 1) / segments
        out += [(at(a0, -h / 2), at(a1, -h / 2), at(a1, h / 2)), (at(a0, -h / 2), at(a1, h / 2), at(a0, h / 2))]
        if 0 < k < segments - 1:  # caps: fans from one rim point, as CAD exports do
            out += [(at(0, h / 2), at(a0, h / 2), at(a1, h / 2)), (at(0, -h / 2), at(a1, -h / 2), at(a0, -h / 2))]
    return out


def sphere(c, r, n=24):
    def at(t, p):
        return (c[0] + r * math.sin(t) * math.cos(p), c[1] + r * math.sin(t) * math.sin(p), c[2] + r * math.cos(t))

    out = []
    for i in range(n):
        t0, t1 = math.pi * i / n, math.pi * (i + 1) / n
        for j in range(2 * n):
            p0, p1 = math.pi * j / n, math.pi * (j + 1) / n
            out += [(at(t0, p0), at(t1, p0), at(t1, p1)), (at(t0, p0), at(t1, p1), at(t0, p1))]
    return out


def union():
    rnd = random.Random(7)
    tris = box((0, 0, 0), (60, 40, 10))
    for _ in range(12):
        c = (rnd.uniform(-25, 25), rnd.uniform(-15, 15), rnd.uniform(0, 10))
        kind = rnd.random()
        if kind < 0.4:
            tris += box(c, (rnd.uniform(3, 15), rnd.uniform(3, 15), rnd.uniform(5, 20)))
        elif kind < 0.8:
            tris += cylinder(c, rnd.uniform(1, 6), rnd.uniform(8, 30), rnd.randrange(3))
        else:
            tris += sphere(c, rnd.uniform(2, 8))
    return soup(tris)


def outlier():
    points, triangles = plate(6, 4, hole_radii(6, 4))
    n = len(points)
    points += [(500, 500, 500), (500.5, 500, 500), (500, 500.5, 500)]
    return points, triangles + [(n, n + 1, n + 2)]


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    holes = hole_radii(10, 6)
    two = {k: r for k, r in holes.items() if k in ((6, 0), (7, 0))}
    write_named(sys.argv[1], [("csg_plate", lambda: plate(10, 6, holes)),
                              ("csg_plate_clean", lambda: plate(10, 6, holes, broken=False)),
                              ("csg_plate_two_holes", lambda: plate(10, 6, two)), ("csg_union", union),
                              ("csg_outlier", outlier)])


if __name__ == "__main__":
    main()
