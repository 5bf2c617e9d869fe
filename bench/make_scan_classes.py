#!/usr/bin/env python3
"""Generated inputs of four classes the wrapper meets in the field (issue 35), as binary STL:

  sculpt    a sculpted figure: a finely subdivided sphere under smooth displacement of seven
            octaves, stretched, with four small closed spheres stuck through its surface
            (eyes, studs: intersecting subtools);
  voxels    voxel art for printing: every voxel of a noisy blob its own closed cube, so the
            shared faces coincide with opposite orientation and every edge is non-manifold;
  islands   a raw scan: an open, slightly noisy surface (a turntable scan's open base and five
            holes) with floating fragments near it (3,000 by default), fans of 1-19 triangles;
  views     an unmerged multi-view scan: three overlapping open partial shells of one shape,
            each a little off the others (registration error), so the views cross.

Deterministic (Python's own `random` with a fixed seed). Pure Python: the largest level takes a
minute or so.

  bench/make_scan_classes.py OUT_DIR [--level L] [--seed S] [--fragments N]

writes OUT_DIR/sculpt_L.stl, voxels_N.stl, islands_L.stl, views_L.stl. See
bench/results/2026-11-26-new-classes.md for what they showed.
"""
import argparse, math, os, random, struct


def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    v = [unit(p) for p in v]
    for _ in range(level):
        mid = {}

        def m(a, b):
            k = (a, b) if a < b else (b, a)
            if k not in mid:
                v.append(unit(tuple(v[a][i] + v[b][i] for i in range(3))))
                mid[k] = len(v) - 1
            return mid[k]

        nf = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f


def unit(p):
    n = math.sqrt(sum(x * x for x in p))
    return tuple(x / n for x in p)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def write_stl(path, tris):
    with open(path, 'wb') as out:
        out.write(b'\0' * 80 + struct.pack('<I', len(tris)))
        rec = struct.Struct('<12fH')
        for t in tris:
            out.write(rec.pack(0, 0, 0, *t[0], *t[1], *t[2], 0))
    print(path, len(tris), 'triangles')


def random_unit(rng):
    return unit((rng.gauss(0, 1), rng.gauss(0, 1), rng.gauss(0, 1)))


def sculpt(level, rng):
    v, f = icosphere(level)
    waves = [[(tuple(rng.gauss(0, 1) * 1.5 * 2 ** o for _ in range(3)), rng.uniform(0, 6.28)) for _ in range(6)]
             for o in range(7)]
    stretch = (1.0, 1.4, 0.8)
    pts = []
    for p in v:
        d = sum(0.12 / 1.8 ** o * math.sin(dot(p, k) + ph) / 6 for o in range(7) for k, ph in waves[o])
        pts.append(tuple(p[i] * (1 + d) * stretch[i] for i in range(3)))
    tris = [(pts[a], pts[b], pts[c]) for a, b, c in f]
    sv, sf = icosphere(max(level - 3, 2))
    for _ in range(4):
        c = random_unit(rng)
        c = tuple(c[i] * stretch[i] * 0.95 for i in range(3))
        r = rng.uniform(0.1, 0.25)
        sp = [tuple(c[i] + r * p[i] for i in range(3)) for p in sv]
        tris += [(sp[a], sp[b], sp[c]) for a, b, c in sf]
    return tris


def voxels(n, rng):
    waves = [(tuple(rng.gauss(0, 1) * 3 for _ in range(3)), rng.uniform(0, 6)) for _ in range(5)]
    corner = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (2, 3, 7), (2, 7, 6), (1, 2, 6),
             (1, 6, 5), (0, 4, 7), (0, 7, 3)]
    tris = []
    for x in range(n):
        for y in range(n):
            for z in range(n):
                c = tuple((q - (n - 1) / 2) / (n / 2) for q in (x, y, z))
                noise = sum(0.15 * math.sin(dot(c, k) + ph) for k, ph in waves)
                if math.sqrt(c[0] ** 2 + (0.7 * c[1]) ** 2 + (1.2 * c[2]) ** 2) + noise < 0.85:
                    pts = [(x + a, y + b, z + d) for a, b, d in corner]
                    tris += [(pts[a], pts[b], pts[c]) for a, b, c in faces]
    return tris


def shape_radius(p, rng_noise):
    return 1 + 0.08 * math.sin(5 * p[0]) * math.cos(4 * p[1]) + 0.03 * math.sin(11 * p[2] + 1) + rng_noise


def centroid_dir(v, t):
    return unit(tuple(v[t[0]][i] + v[t[1]][i] + v[t[2]][i] for i in range(3)))


def islands(level, rng, fragments=3000):
    v, f = icosphere(level)
    stretch = (1.0, 0.8, 1.3)
    pts = [tuple(p[i] * shape_radius(p, 0.002 * rng.gauss(0, 1)) * stretch[i] for i in range(3)) for p in v]
    holes = [(random_unit(rng), math.cos(rng.uniform(0.05, 0.2))) for _ in range(5)]
    tris = []
    for t in f:
        c = centroid_dir(v, t)
        if c[2] > -0.7 and all(dot(c, d) < lim for d, lim in holes):
            tris.append((pts[t[0]], pts[t[1]], pts[t[2]]))
    edge = math.dist(pts[f[0][0]], pts[f[0][1]])
    for _ in range(fragments):  # floating fragments: small flat fans near the surface, a little rough
        d = random_unit(rng)
        c = tuple(d[i] * stretch[i] * rng.uniform(0.9, 1.15) for i in range(3))
        t1 = unit((d[1] * 0.8 - d[2] * 0.5, d[2] * 0.3 - d[0] * 0.8, d[0] * 0.5 - d[1] * 0.3))
        t2 = (d[1] * t1[2] - d[2] * t1[1], d[2] * t1[0] - d[0] * t1[2], d[0] * t1[1] - d[1] * t1[0])
        k = rng.randrange(1, 20)
        angles = sorted(rng.uniform(0, 2 * math.pi) for _ in range(k + 1))
        ring = []
        for a in angles:
            r = edge * rng.uniform(0.5, 2.0)
            ring.append(tuple(c[i] + math.cos(a) * r * t1[i] + math.sin(a) * r * t2[i] + 0.1 * edge * rng.gauss(0, 1)
                              for i in range(3)))
        tris += [(c, ring[j], ring[j + 1]) for j in range(k)]
    return tris


def views(level, rng, off=0.004):
    v, f = icosphere(level)
    stretch = (1.0, 0.8, 1.3)
    tris = []
    for _ in range(3):
        look = random_unit(rng)
        shift = tuple(off * rng.gauss(0, 1) for _ in range(3))
        scale = off * rng.gauss(0, 1)
        pts = [tuple(p[i] * shape_radius(p, 0.002 * rng.gauss(0, 1) + scale) * stretch[i] + shift[i] for i in range(3))
               for p in v]
        holes = [(random_unit(rng), math.cos(rng.uniform(0.05, 0.15))) for _ in range(3)]
        for t in f:
            c = centroid_dir(v, t)
            if dot(c, look) > -0.2 and all(dot(c, d) < lim for d, lim in holes):
                tris.append((pts[t[0]], pts[t[1]], pts[t[2]]))
    return tris


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('out_dir')
    ap.add_argument('--level', type=int, default=6, help='sphere subdivisions (6: 82k triangles, 7: 328k)')
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--fragments', type=int, default=3000, help='floating fragments of the islands scan')
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)
    rng = random.Random(a.seed)
    write_stl(os.path.join(a.out_dir, f'sculpt_{a.level}.stl'), sculpt(a.level, rng))
    n = 10 * (a.level - 3)
    write_stl(os.path.join(a.out_dir, f'voxels_{n}.stl'), voxels(n, rng))
    write_stl(os.path.join(a.out_dir, f'islands_{a.level}.stl'), islands(a.level, rng, a.fragments))
    write_stl(os.path.join(a.out_dir, f'views_{a.level}.stl'), views(a.level, rng))


if __name__ == '__main__':
    main()
