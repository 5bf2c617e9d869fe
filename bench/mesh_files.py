"""Triangles of STL (binary or ASCII) and OBJ files for the bench scripts, as nine floats each."""
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
