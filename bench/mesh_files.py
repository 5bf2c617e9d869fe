"""Mesh files for the bench scripts: triangles of STL (binary or ASCII) and OBJ files as nine
floats each; indexed meshes written as binary STL; the boxes and the closed revolved grid the
generators share."""
import math
import os
import struct


def read_triangles(path):
    data = open(path, "rb").read()
    if path.lower().endswith(".obj"):
        pts, tris = [], []
        for line in data.decode(errors="replace").splitlines():
            w = line.split()
            if not w:
                continue
            if w[0] == "v":
                pts.append(tuple(float(x) for x in w[1:4]))
            elif w[0] == "f":
                ids = [int(x.split("/")[0]) for x in w[1:]]
                ids = [i - 1 if i > 0 else len(pts) + i for i in ids]
                for k in range(1, len(ids) - 1):  # a fan over the polygon
                    tris.append(pts[ids[0]] + pts[ids[k]] + pts[ids[k + 1]])
        return tris
    if len(data) >= 84 and len(data) == 84 + 50 * struct.unpack_from("<I", data, 80)[0]:
        n = struct.unpack_from("<I", data, 80)[0]
        return [struct.unpack_from("<9f", data, 84 + 50 * i + 12) for i in range(n)]
    v = [float(w) for line in data.decode(errors="replace").splitlines() if line.strip().startswith("vertex")
         for w in line.split()[1:4]]
    return [tuple(v[i:i + 9]) for i in range(0, len(v) - 8, 9)]


def write_stl(path, points, triangles):
    """Binary STL of an indexed mesh (normals left zero: readers recompute them)."""
    out = [b"\0" * 80, struct.pack("<I", len(triangles))]
    for t in triangles:
        out.append(struct.pack("<12fH", 0, 0, 0, *points[t[0]], *points[t[1]], *points[t[2]], 0))
    with open(path, "wb") as f:
        f.write(b"".join(out))


def revolved(radius_at, columns, rows, length):
    """A closed body around the z axis from 0 to `length`: a grid of `columns` around by `rows`
    along, each node at radius radius_at(theta, z), capped by a fan at each end."""
    points, triangles = [], []
    for j in range(rows + 1):
        z = length * j / rows
        for i in range(columns):
            th = 2 * math.pi * i / columns
            r = radius_at(th, z)
            points.append((r * math.cos(th), r * math.sin(th), z))

    def at(i, j):
        return j * columns + (i % columns)

    for j in range(rows):
        for i in range(columns):
            a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
            triangles += [(a, b, c), (a, c, d)]
    bottom, top = len(points), len(points) + 1
    points += [(0, 0, 0), (0, 0, length)]
    for i in range(columns):
        triangles += [(bottom, at(i + 1, 0), at(i, 0)), (top, at(i, rows), at(i + 1, rows))]
    return points, triangles


def write_named(out_dir, meshes):
    """Each (name, make) of `meshes` as OUT_DIR/name.stl, make() giving (points, triangles)."""
    os.makedirs(out_dir, exist_ok=True)
    for name, make in meshes:
        points, triangles = make()
        write_stl(os.path.join(out_dir, name + ".stl"), points, triangles)
        print(f"{name}.stl: {len(triangles)} triangles")


def add_box(points, triangles, corners):
    """A closed box on 8 corners in bit order (bit a set: the high side of axis a), faces outward."""
    base = len(points)
    points.extend(corners)
    for q in ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)):
        a, b, c, d = (base + i for i in q)
        triangles += [(a, b, c), (a, c, d)]


def box_corners(lo, hi):
    """The 8 corners of the axis-aligned box lo-hi in add_box's order."""
    return [tuple(hi[a] if k >> a & 1 else lo[a] for a in range(3)) for k in range(8)]
