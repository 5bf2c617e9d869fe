#!/usr/bin/env python3
"""Field classes not generated before (issue 35), as binary STL:

  foliage      a plant for a game or a render: a stem and branches (thin closed tubes) with 400
               leaves (foliage_dense: 2,000), each an open, curved card of 8 triangles, leaves
               crossing each other and the branches;
  hair_cards   a head (a closed sphere) with 300 hair cards (hair_cards_dense: 1,500): open curved
               strips a base cell wide and a sixth of the model long, clustered, crossing each
               other and the head;
  building     an architectural model: walls, floors and a roof as zero-thickness open faces
               (one side each), interior walls meeting the outer ones in T-edges (non-manifold),
               window holes, doors coplanar over their wall, a roof overhanging the walls;
  hollow_print a print hollowed for resin: a bumpy body and its inner surface an offset inward
               (the wall 0.5 or 2 base cells thick), the inner shell facing in, a drain hole
               through the bottom joining the two;
  sheet_metal  a bent bracket of sheet 0.6 % of the model thick (under a base cell at 1 %;
               sheet_metal_thin: 0.25 %), round holes and a slot, its bends tessellated radii;
  low_poly     low-poly art: an icosphere of 320 faces with its vertices moved by up to 15 %
               (facets of many base cells, every edge sharp, corners of five and six).

Deterministic (a fixed seed). Pure Python.

  bench/make_field_classes.py OUT_DIR
"""
import math
import os
import random
import sys

from make_scan_classes import icosphere
from mesh_files import write_stl


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def norm(a):
    return math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)


def unit(a):
    n = norm(a)
    return scale(a, 1 / n)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def random_unit(rng):
    while True:
        v = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))
        if 0.01 < norm(v) <= 1:
            return unit(v)


def frame(d):
    """Two unit vectors across the unit direction d."""
    a = (1, 0, 0) if abs(d[0]) < 0.9 else (0, 1, 0)
    u = unit(cross(d, a))
    return u, cross(d, u)


class Mesh:
    def __init__(self):
        self.points, self.tris = [], []

    def point(self, p):
        self.points.append(p)
        return len(self.points) - 1

    def grid(self, at, nu, nv, closed_u=False):
        """Quads over (u, v) in [0, nu] x [0, nv], at(u, v) -> point; u wraps when closed_u."""
        cols = nu if closed_u else nu + 1
        base = len(self.points)
        for j in range(nv + 1):
            for i in range(cols):
                self.point(at(i, j))
        for j in range(nv):
            for i in range(nu):
                a = base + j * cols + i
                b = base + j * cols + (i + 1) % cols
                c, d = b + cols, a + cols
                self.tris += [(a, b, c), (a, c, d)]
        return base, cols

    def tube(self, a, b, radius, sides=8, rows=4):
        """A closed tube from a to b (capped by fans)."""
        d = unit(tuple(b[k] - a[k] for k in range(3)))
        u, v = frame(d)

        def at(i, j):
            th = 2 * math.pi * i / sides
            c = add(a, scale(tuple(b[k] - a[k] for k in range(3)), j / rows))
            return add(c, add(scale(u, radius * math.cos(th)), scale(v, radius * math.sin(th))))

        base, cols = self.grid(at, sides, rows, closed_u=True)
        for end, centre, flip in ((0, a, True), (rows, b, False)):
            c = self.point(centre)
            for i in range(sides):
                p, q = base + end * cols + i, base + end * cols + (i + 1) % sides
                self.tris.append((c, q, p) if flip else (c, p, q))

    def box(self, lo, hi):
        """A closed box."""
        base = len(self.points)
        for z in (lo[2], hi[2]):
            for y in (lo[1], hi[1]):
                for x in (lo[0], hi[0]):
                    self.point((x, y, z))
        for f in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
            a, b, c, d = (base + k for k in f)
            self.tris += [(a, b, c), (a, c, d)]


def foliage(rng, leaves=400):
    m = Mesh()
    m.tube((0, 0, 0), (0, 0, 10), 0.15, rows=10)
    branches = []
    for k in range(12):
        z = 2 + 7 * k / 11
        d = unit((math.cos(k * 2.4), math.sin(k * 2.4), 0.6))
        end = add((0, 0, z), scale(d, 3.5 - 1.5 * k / 11))
        m.tube((0, 0, z), end, 0.07)
        branches.append(((0, 0, z), end))
    for _ in range(leaves):
        a, b = branches[rng.randrange(len(branches))]
        t = rng.uniform(0.3, 1.0)
        root = add(a, scale(tuple(b[k] - a[k] for k in range(3)), t))
        d = random_unit(rng)
        u, v = frame(d)
        length, width, bend = rng.uniform(0.5, 0.9), rng.uniform(0.15, 0.3), rng.uniform(-0.2, 0.2)

        def at(i, j, root=root, d=d, u=u, v=v, length=length, width=width, bend=bend):
            s = i / 4
            w = (j - 1) * width * math.sin(math.pi * min(0.95, max(0.05, s)))
            return add(root, add(scale(d, s * length), add(scale(u, w), scale(v, bend * s * s))))

        m.grid(at, 4, 2)
    return m


def hair_cards(rng, cards=300):
    m = Mesh()
    pts, tris = icosphere(4)
    base = len(m.points)
    m.points += [scale(unit(p), 1.0) for p in pts]
    m.tris += [(a + base, b + base, c + base) for a, b, c in tris]
    for _ in range(cards):
        n = random_unit(rng)
        if n[2] < -0.2:
            n = (n[0], n[1], -n[2])
        root = scale(n, 0.95)
        down = unit(add(scale(n, 0.6), (0, 0, -1.0)))
        side = unit(cross(n, down)) if norm(cross(n, down)) > 1e-6 else frame(n)[0]
        length, width = rng.uniform(0.4, 0.7), rng.uniform(0.03, 0.06)

        def at(i, j, root=root, n=n, down=down, side=side, length=length, width=width):
            s = i / 8
            c = add(root, add(scale(n, 0.12 * math.sin(math.pi * s) + 0.05 * s), scale(down, s * length)))
            return add(c, scale(side, (j - 0.5) * width))

        m.grid(at, 8, 1)
    return m


def building(rng):
    m = Mesh()

    def quad(a, b, c, d, nu=1, nv=1):
        def at(i, j):
            s, t = i / nu, j / nv
            p = add(scale(a, (1 - s) * (1 - t)), scale(b, s * (1 - t)))
            return add(p, add(scale(c, s * t), scale(d, (1 - s) * t)))

        m.grid(at, nu, nv)

    W, D, H = 12.0, 8.0, 3.0
    for floor in range(2):
        z0, z1 = floor * H, (floor + 1) * H
        quad((0, 0, z0), (W, 0, z0), (W, D, z0), (0, D, z0), 6, 4)  # the floor, one sheet
        # Outer walls with window holes: each wall a strip of panels, every other one a window
        # (a panel below and above the opening), so the window rims are open borders.
        for (ax, ay), (bx, by) in (((0, 0), (W, 0)), ((W, 0), (W, D)), ((W, D), (0, D)), ((0, D), (0, 0))):
            panels = 6
            for k in range(panels):
                s0, s1 = k / panels, (k + 1) / panels
                p0 = (ax + (bx - ax) * s0, ay + (by - ay) * s0)
                p1 = (ax + (bx - ax) * s1, ay + (by - ay) * s1)
                if k % 2 == 1:
                    for za, zb in ((z0, z0 + 0.9), (z0 + 2.1, z1)):
                        quad((p0[0], p0[1], za), (p1[0], p1[1], za), (p1[0], p1[1], zb), (p0[0], p0[1], zb))
                else:
                    quad((p0[0], p0[1], z0), (p1[0], p1[1], z0), (p1[0], p1[1], z1), (p0[0], p0[1], z1), 1, 3)
        # Interior walls meeting the outer walls in T-edges; a door coplanar over one of them.
        quad((W / 2, 0, z0), (W / 2, D, z0), (W / 2, D, z1), (W / 2, 0, z1), 4, 2)
        quad((0, D / 2, z0), (W / 2, D / 2, z0), (W / 2, D / 2, z1), (0, D / 2, z1), 3, 2)
        quad((W / 2, 1, z0), (W / 2, 2, z0), (W / 2, 2, z0 + 2.1), (W / 2, 1, z0 + 2.1))
    # A gable roof overhanging the walls, two open sheets meeting at the ridge, gables closed.
    o, top = 0.6, 2 * H + 2.5
    quad((-o, -o, 2 * H - 0.3), (W + o, -o, 2 * H - 0.3), (W + o, D / 2, top), (-o, D / 2, top), 8, 3)
    quad((W + o, D + o, 2 * H - 0.3), (-o, D + o, 2 * H - 0.3), (-o, D / 2, top), (W + o, D / 2, top), 8, 3)
    for x in (0, W):
        a, b, c = (x, 0, 2 * H), (x, D, 2 * H), (x, D / 2, top - 0.4)
        m.tris.append((m.point(a), m.point(b), m.point(c)))
    # A chimney: a closed box through the roof.
    m.box((2, 1.5, 2 * H - 1), (2.8, 2.3, top + 1))
    return m


def bumpy(p, amp=0.08):
    x, y, z = p
    return 1 + amp * math.sin(3 * x + 1) * math.sin(4 * y + 2) * math.sin(5 * z + 0.5)


def hollow_print(wall):
    """A bumpy body of radius about 1 and its inner surface `wall` in, joined by a drain hole
    (the faces of both shells within the hole's radius of the bottom left out, a tube between)."""
    pts, tris = icosphere(5)
    m = Mesh()
    hole = 0.12
    outer = [scale(unit(p), bumpy(unit(p))) for p in pts]
    inner = [scale(unit(p), bumpy(unit(p)) - wall) for p in pts]

    def in_hole(t, ps):
        return all(math.hypot(ps[v][0], ps[v][1]) < hole * 1.2 and ps[v][2] < 0 for v in t)

    no = len(pts)
    m.points = outer + inner
    kept = [t for t in tris if not in_hole(t, outer)]
    for t in kept:
        m.tris.append(t)
        m.tris.append((t[0] + no, t[2] + no, t[1] + no))  # the inner shell faces in
    edges = {(t[k], t[(k + 1) % 3]) for t in kept for k in range(3)}
    for a, b in edges:
        if (b, a) not in edges:  # the hole's rim: a band of the tube to the inner rim
            m.tris += [(b, a, a + no), (b, a + no, b + no)]
    return m


def sheet_metal(thickness=0.01):
    """An L bracket bent 90 degrees: a flange in x-y, a bend of inner radius 2 thicknesses, an
    upright flange in x-z; four round holes and a slot through the flanges. Built as a height
    field of the sheet's mid surface (u across, s along the unrolled length), offset both ways,
    the rims joined; holes as cells left out, their rims joined too."""
    m = Mesh()
    L1, L2, width, r = 1.0, 0.8, 0.8, 2 * thickness
    arc = math.pi / 2 * (r + thickness / 2)
    total = L1 + arc + L2
    ns, nu = 160, 64

    def mid(s, u, side):
        off = (side - 0.5) * thickness  # side 0: inner face, 1: outer
        if s <= L1:
            return (s, u, off)
        if s <= L1 + arc:
            a = (s - L1) / (r + thickness / 2)
            rr = r + thickness / 2 - off
            return (L1 + rr * math.sin(a), u, (r + thickness / 2) - rr * math.cos(a))
        t = s - L1 - arc
        return (L1 + r + thickness / 2 - off, u, r + thickness / 2 + t)

    holes = [(0.35, 0.2, 0.07), (0.35, 0.6, 0.07), (0.75, 0.4, 0.1), (L1 + arc + 0.45, 0.4, 0.12)]

    def solid(i, j):
        s, u = (i + 0.5) * total / ns, (j + 0.5) * width / nu
        for hs, hu, hr in holes:
            if math.hypot(s - hs, u - hu) < hr:
                return False
        if L1 + arc + 0.15 < s < L1 + arc + 0.25 and 0.1 < u < 0.7:  # a slot
            return False
        return True

    idx = {}

    def node(i, j, side):
        k = (i, j, side)
        if k not in idx:
            idx[k] = m.point(mid(i * total / ns, j * width / nu, side))
        return idx[k]

    cells = {(i, j) for i in range(ns) for j in range(nu) if solid(i, j)}
    for i, j in cells:
        a, b, c, d = (i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)
        for side, flip in ((1, False), (0, True)):
            q = [node(*p, side) for p in (a, b, c, d)]
            if flip:
                q.reverse()
            m.tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
        # Rims: a cell edge with no cell across joins the two faces.
        for (di, dj), (p, q) in (((0, -1), (a, b)), ((1, 0), (b, c)), ((0, 1), (c, d)), ((-1, 0), (d, a))):
            if (i + di, j + dj) not in cells:
                p1, q1, p0, q0 = node(*p, 1), node(*q, 1), node(*p, 0), node(*q, 0)
                m.tris += [(p1, p0, q0), (p1, q0, q1)]
    return m


def low_poly(rng):
    pts, tris = icosphere(2)
    m = Mesh()
    m.points = [scale(unit(p), 1 + rng.uniform(-0.15, 0.15)) for p in pts]
    m.tris = list(tris)
    return m


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    rng = random.Random(35)
    models = {
        "foliage": foliage(rng),
        "foliage_dense": foliage(rng, 2000),
        "hair_cards": hair_cards(rng),
        "hair_cards_dense": hair_cards(rng, 1500),
        "building": building(rng),
        "hollow_print_thin": hollow_print(0.0346 * 0.5),
        "hollow_print_thick": hollow_print(0.0346 * 2),
        "sheet_metal": sheet_metal(),
        "sheet_metal_thin": sheet_metal(0.004),
        "low_poly": low_poly(rng),
    }
    for name, m in models.items():
        write_stl(f"{out}/{name}.stl", m.points, m.tris)
        print(f"{name}.stl: {len(m.tris)} triangles")


if __name__ == "__main__":
    main()
