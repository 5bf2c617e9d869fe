#!/usr/bin/env python3
"""Open inputs that the outside volume reaches from both sides (issue 35), written as PLY.

Usage: bench/make_open_sheets.py OUT_DIR [--density K]

  scan_closed.ply      a bumpy scanned-looking body on a flat base, closed (the reference)
  scan_base_holes.ply  the same body with jagged holes cut into its base (the outside gets in)
  sphere_patches.ply   a bumpy sphere with patches of triangles deleted
  half_sphere.ply      an open bowl: one sheet
  terrain.ply          a height field over a square: one sheet with open borders
  suzanne_holes.ply    tests/data/suzanne.ply with its underside deleted

Deterministic (fixed seeds). K scales the tessellation (K = 1: the scan has ~70k triangles).
"""
import argparse, math, os, random, struct

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def write_ply(path, points, tris):
    with open(path, "wb") as f:
        f.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
                 "property double z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n"
                 % (len(points), len(tris))).encode())
        for p in points:
            f.write(struct.pack("<3d", *p))
        for t in tris:
            f.write(struct.pack("<B3i", 3, *t))
    print(f"{os.path.basename(path)}: {len(tris)} triangles")


def uv_grid(nu, nv, f, closed_u=True):
    """Points f(u, v) on an nu x (nv + 1) grid (u wraps around when closed_u), with triangles."""
    pts = [f(i / nu, j / nv) for j in range(nv + 1) for i in range(nu)]
    tris = []
    cols = nu if closed_u else nu - 1
    for j in range(nv):
        for i in range(cols):
            a, b = j * nu + i, j * nu + (i + 1) % nu
            c, d = a + nu, b + nu
            tris.append((a, b, d))
            tris.append((a, d, c))
    return pts, tris


def bumpy_body(k):
    """A closed body like a scanned bust: bumpy sides over a flat base disc (z = 0) and a cap."""
    nu, nv = int(192 * k), int(132 * k)

    def side(u, v):
        th = 2 * math.pi * u
        ph = math.pi * (0.5 * v)  # 0 at the base rim, pi/2 at the top pole
        r = (1 + 0.05 * math.sin(7 * th) * math.cos(5 * ph) + 0.03 * math.sin(13 * th + 3 * ph)) * math.cos(ph)
        z = 1.3 * math.sin(ph) + 0.04 * math.sin(5 * th) * math.sin(2 * ph) + 0.15
        return (r * math.cos(th), 0.8 * r * math.sin(th), z if v > 0 else 0.15)

    pts, tris = uv_grid(nu, nv, side)
    # The top ring (v = 1) collapses at the pole: drop it and close with a fan.
    top = len(pts)
    pts.append((0.0, 0.0, side(0, 1)[2]))
    ring = nv - 1
    tris = [t for t in tris if max(t) < nv * nu]
    for i in range(nu):
        tris.append((ring * nu + i, ring * nu + (i + 1) % nu, top))
    # The base: the bottom rim (v = 0, z = 0.15) goes down to a flat disc at z = 0 through a
    # short skirt, and the disc is filled by rings to a centre.
    rings = int(48 * k)
    base_rings = []
    for r in range(rings + 1):
        s = 1 - r / rings
        ring_pts = []
        for i in range(nu):
            x, y, _ = pts[i]
            ring_pts.append(len(pts))
            pts.append((x * s, y * s, 0.0))
        base_rings.append(ring_pts)
    for i in range(nu):  # skirt: rim (z = 0.15) to the disc's outer ring (z = 0)
        a, b = i, (i + 1) % nu
        tris.append((base_rings[0][a], base_rings[0][b], b))
        tris.append((base_rings[0][a], b, a))
    for r in range(rings - 1):
        for i in range(nu):
            a, b = base_rings[r][i], base_rings[r][(i + 1) % nu]
            c, d = base_rings[r + 1][i], base_rings[r + 1][(i + 1) % nu]
            tris.append((a, c, d))
            tris.append((a, d, b))
    centre = len(pts)
    pts.append((0.0, 0.0, 0.0))
    last = base_rings[rings - 1]
    for i in range(nu):
        tris.append((last[i], centre, last[(i + 1) % nu]))
    # The last ring (s = 0) is unused: its points sit at the centre; leave them (stray points
    # are ignored by the wrap).
    return pts, tris


def cut_holes(pts, tris, holes, rng, rim=1.3):
    """Drops the triangles whose centroid is within a hole (centre, radius; in x, y on the base
    z < 0.01, or in 3D when the centre has a z), with a jagged rim."""
    kept = []
    for t in tris:
        c = [sum(pts[v][a] for v in t) / 3 for a in range(3)]
        drop = False
        for (h, r, plane) in holes:
            if plane and c[2] > 0.01:
                continue
            d = math.hypot(c[0] - h[0], c[1] - h[1]) if plane else math.dist(c, h)
            if d < r or (d < rim * r and rng.random() < 0.5):
                drop = True
        if not drop:
            kept.append(t)
    return kept


def sphere(k):
    nu, nv = int(120 * k), int(60 * k)

    def f(u, v):
        th, ph = 2 * math.pi * u, math.pi * v
        r = 1 + 0.06 * math.sin(4 * th + 1) * math.cos(3 * ph) + 0.02 * math.sin(13 * ph)
        return (r * math.sin(ph) * math.cos(th), r * math.sin(ph) * math.sin(th), r * math.cos(ph))

    pts, tris = uv_grid(nu, nv, f)
    # Poles: rows v = 0 and v = 1 collapse; drop their degenerate triangles (the wrap drops
    # them anyway) by merging each pole row into one point.
    north, south = 0, nv * nu
    remap = list(range(len(pts)))
    for i in range(nu):
        remap[i] = north
        remap[nv * nu + i] = south
    out = []
    for t in tris:
        t = tuple(remap[v] for v in t)
        if len(set(t)) == 3:
            out.append(t)
    return pts, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--density", type=float, default=1.0)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    k = a.density
    rng = random.Random(35)

    pts, tris = bumpy_body(k)
    write_ply(os.path.join(a.out, "scan_closed.ply"), pts, tris)
    holes = [((0.35, 0.1, 0), 0.22, True), ((-0.4, -0.2, 0), 0.15, True), ((-0.1, 0.45, 0), 0.1, True)]
    write_ply(os.path.join(a.out, "scan_base_holes.ply"), pts, cut_holes(pts, tris, holes, rng))

    pts, tris = sphere(k)
    patches = [((0.0, 0.0, -1.0), 0.35, False), ((0.8, 0.5, 0.3), 0.2, False), ((-0.6, 0.7, 0.2), 0.12, False)]
    write_ply(os.path.join(a.out, "sphere_patches.ply"), pts, cut_holes(pts, tris, patches, rng))
    half = [t for t in tris if all(pts[v][2] >= -1e-9 for v in t)]
    write_ply(os.path.join(a.out, "half_sphere.ply"), pts, half)

    n = int(150 * k)

    def height(u, v):
        x, y = 2 * u - 1, 2 * v - 1
        return (x, y, 0.15 * math.sin(3 * x + 0.5) * math.cos(4 * y) + 0.05 * math.sin(11 * x * y) + 0.1 * x * x)

    pts, tris = uv_grid(n + 1, n, lambda u, v: height(u * (n + 1) / n, v), closed_u=False)
    write_ply(os.path.join(a.out, "terrain.ply"), pts, tris)

    # Suzanne (ASCII PLY with quads and triangles): its underside deleted.
    with open(os.path.join(root, "tests", "data", "suzanne.ply")) as f:
        lines = f.read().split("\n")
    nv_ = nf = 0
    i = 0
    while lines[i] != "end_header":
        if lines[i].startswith("element vertex"):
            nv_ = int(lines[i].split()[2])
        if lines[i].startswith("element face"):
            nf = int(lines[i].split()[2])
        i += 1
    i += 1
    spts = [tuple(map(float, lines[i + j].split()[:3])) for j in range(nv_)]
    stris = []
    for j in range(nf):
        w = list(map(int, lines[i + nv_ + j].split()))
        poly = w[1:1 + w[0]]
        for m in range(1, len(poly) - 1):
            stris.append((poly[0], poly[m], poly[m + 1]))
    zmin = min(p[2] for p in spts)
    zmax = max(p[2] for p in spts)
    cut = zmin + 0.2 * (zmax - zmin)
    stris = [t for t in stris if max(spts[v][2] for v in t) > cut]
    write_ply(os.path.join(a.out, "suzanne_holes.ply"), spts, stris)


if __name__ == "__main__":
    main()
