#!/usr/bin/env python3
"""Writes the hand-made seed corpora of tests/fuzz/corpus (run from anywhere; overwrites
only the files named here). Each seed starts with the harness's selector byte."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def put(fuzzer, name, data):
    d = os.path.join(HERE, "corpus", fuzzer)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


# ---- fuzz_mesh_read: byte 0 = 0 detect, 1 STL, 2 OBJ, 3 OFF, 4 PLY --------------------------
SNIFF, STL, OBJ, OFF, PLY = b"\0", b"\1", b"\2", b"\3", b"\4"
M = "fuzz_mesh_read"

ascii_stl = """solid hot
 facet normal 0 0 -1
  outer loop
   vertex 0 0 0
   vertex 0 1 0
   vertex 1 0 0
  endloop
 endfacet
 facet normal 0 -1 0
  outer loop
   vertex 0 0 0
   vertex 1 0 0
   vertex 0 0 1
  endloop
 endfacet
endsolid hot
solid cold
 facet normal 1 1 1
  outer loop
   vertex 1 0 0
   vertex 0 1 0
   vertex 0 0 1e-3
  endloop
 endfacet
endsolid cold
"""
put(M, "stl_ascii", STL + ascii_stl.encode())
put(M, "stl_ascii_detect", SNIFF + ascii_stl.encode())


def binary_stl(tris, header=b"binary"):
    out = header.ljust(80, b"\0") + struct.pack("<I", len(tris))
    for t in tris:
        out += struct.pack("<3f", 0, 0, 0)
        for p in t:
            out += struct.pack("<3f", *p)
        out += struct.pack("<H", 0)
    return out


tet = [((0, 0, 0), (0, 1, 0), (1, 0, 0)), ((0, 0, 0), (1, 0, 0), (0, 0, 1)),
       ((0, 0, 0), (0, 0, 1), (0, 1, 0)), ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
put(M, "stl_binary", STL + binary_stl(tet))
# Header starting with "solid": must still be read as binary (the size matches).
put(M, "stl_binary_solid_header", SNIFF + binary_stl(tet[:2], b"solid but binary"))
put(M, "stl_binary_degenerate", STL + binary_stl([((1, 1, 1), (1, 1, 1), (2, 2, 2)), ((0, 0, 0), (1, 1, 1), (2, 2, 2))]))
# A count left at 0 by the writer: the records the file holds are read, with a note.
put(M, "stl_binary_stale_count", STL + binary_stl(tet[:2])[:80] + struct.pack("<I", 0) + binary_stl(tet[:2])[84:])

obj = """# a quad, a triangle with texture/normal indices, groups, negative indices
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 0.5 1 1.0
vt 0 0
vn 0 0 1
g base
f 1 2 3 4
o roof
f 1/1 2/1 5/1
f -4//1 -3//1 -1//1
g base
f 3 4 5
"""
put(M, "obj_groups", OBJ + obj.encode())
put(M, "obj_detect", SNIFF + obj.encode())
# A face continued over two lines with a backslash (OBJ spec), and a comment ending in one.
obj_cont = """v 0 0 0
v 2 0 0
v 2 2 0
v 1 3 0 \\
  
v 0 2 0
# C:\\models\\
f 1 2 \\
  3 4 5
f 1 3 5
"""
put(M, "obj_continuation", OBJ + obj_cont.encode())
put(M, "obj_nonconvex", OBJ + b"v 0 0 0\nv 4 0 0\nv 4 4 0\nv 2 1 0\nv 0 4 0\nf 1 2 3 4 5\n")

off = """OFF
# a square pyramid, the base a quad
5 5 0
0 0 0
1 0 0
1 1 0
0 1 0
0.5 0.5 1
4 3 2 1 0
3 0 1 4
3 1 2 4
3 2 3 4
3 3 0 4
"""
put(M, "off_pyramid", OFF + off.encode())
put(M, "off_detect", SNIFF + off.encode())
put(M, "off_coff", OFF + b"COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 9 9 9\n")

ply_ascii = """ply
format ascii 1.0
comment vdbwrap_part 0 lid
comment vdbwrap_part 1 box
element vertex 4
property float x
property float y
property float z
property uchar red
element face 3
property list uchar int vertex_indices
property int part
end_header
0 0 0 1
1 0 0 2
0 1 0 3
0 0 1 4
3 0 2 1 0
3 0 1 3 1
4 0 3 2 1 1
"""
put(M, "ply_ascii_parts", PLY + ply_ascii.encode())
put(M, "ply_detect", SNIFF + ply_ascii.encode())

# Triangle strips with -1 restarts (Stanford scans): two strips, one with a repeated index.
ply_strips = """ply
format ascii 1.0
element vertex 6
property float x
property float y
property float z
element tristrips 1
property list int int vertex_indices
end_header
0 0 0
1 0 0
0 1 0
1 1 0
0 2 0
1 2 0
12 0 1 2 3 -1 2 3 4 4 5 -1 0
"""
put(M, "ply_tristrips_ascii", PLY + ply_strips.encode())


def ply_binary(endian, strips=False):
    fmt = "<" if endian == "little" else ">"
    pts = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    head = "ply\nformat binary_%s_endian 1.0\nelement vertex 4\nproperty double x\nproperty double y\n" \
           "property double z\n" % endian
    body = b"".join(struct.pack(fmt + "3d", *p) for p in pts)
    if strips:
        head += "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
        idx = [0, 1, 2, 3, -1, 3, 2, 0]
        body += struct.pack(fmt + "i", len(idx)) + b"".join(struct.pack(fmt + "i", i) for i in idx)
    else:
        head += "element face 2\nproperty list uchar uint vertex_indices\nproperty short flags\nend_header\n"
        body += struct.pack(fmt + "B3Ih", 3, 0, 2, 1, 7) + struct.pack(fmt + "B4Ih", 4, 0, 1, 3, 2, 7)
    return head.encode() + body


put(M, "ply_binary_le", PLY + ply_binary("little"))
put(M, "ply_binary_be", PLY + ply_binary("big"))
put(M, "ply_tristrips_binary", PLY + ply_binary("little", strips=True))

# ---- fuzz_params_text: byte 0 = 0 JSON, 1 YAML, 2 control volume, 3 volume, 4 contact rule,
# 5 part size, 6 length -------------------------------------------------------------------
P = "fuzz_params_text"
put(P, "json_full", b"\0" + b"""{
  "base_size_percent": 0.8, "levels": 2, "feature_angle_deg": 35, "volume": "seed_points",
  "seed_points": [{"x": 0.5, "y": 0.5, "z": 0.5}, {"x": 1, "y": 2, "z": 3}],
  "gap_closure": {"model_units": 0.15},
  "control_volumes": [{"shape": "box", "a": {"x": 0, "y": 0, "z": 0}, "b": {"x": 1, "y": 1, "z": 1},
                       "size": {"percent": 0.25}},
                      {"shape": "SHAPE_CONE", "a": {"x": 0}, "b": {"z": 2}, "radius": 1, "radius_b": 0.5,
                       "size": {"model_units": 0.1}}],
  "part_sizes": [{"part": "hot", "size": {"percent": 0.5}}],
  "contact_prevention": [{"groups": [{"parts": ["hot"]}, {"parts": ["cold", "lid"]}]}],
  "contact_floor": {"percent": 0.01}, "threads": 1, "refine_max_triangles": 32,
  "refine_normal_spread_deg": 15, "presmooth_iterations": 8, "snap_features": false,
  "corner_angle_deg": 40, "validity_rounds": 100, "remesh": true, "coarsen_tolerance": 0.1
}""")
put(P, "json_nested", b"\0" + b'{"params": {"baseSizeModelUnits": 2.5, "volume": "VOLUME_INSIDE"}}')
put(P, "yaml_full", b"\1" + b"""# params.yaml
base_size_percent: 1
levels: 1
volume: inside
gap_closure:
  percent: 0.5
control_volumes:
  - shape: sphere
    a: {x: 0, y: 0, z: 0}
    radius: 2
    size: {percent: 0.25}
  - shape: cylinder
    a: {x: 0, y: 0, z: 0}
    b: {x: 0, y: 0, z: 1}
    radius: 0.5
    size: {model_units: 0.05}
part_sizes:
  - part: "123"
    size: {model_units: 0.2}
snap_features: true
""")
put(P, "yaml_empty", b"\1" + b"---\n")
put(P, "cv_box", b"\2box:0,0,0,1,2,3:0.5%")
put(P, "cv_cone", b"\2cone:0,0,0,0,0,1,1,0.5:0.1")
put(P, "volume_seeds", b"\3 0.5,0.5,0.5; 1e3,-2,3 ;")
put(P, "volume_inside", b"\3inside")
put(P, "contact_groups", b"\4hot,cold:lid, fan")
put(P, "part_size", b"\5inlet duct=0.25%")
put(P, "length", b"\0061.5e-3%")

# ---- fuzz_params_proto: byte 0 = 0 WrapParameters, 1 RepairParameters, 2 JobSpec (wire) ----
# Hand-encoded protobuf wire format (field numbers from proto/vdbwrap/v1/jobs.proto).
def varint(n):
    n &= (1 << 64) - 1
    out = b""
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out += bytes([b | 0x80])
        else:
            return out + bytes([b])


def f_varint(field, v):
    return varint(field << 3) + varint(v)


def f_double(field, v):
    return varint(field << 3 | 1) + struct.pack("<d", v)


def f_bytes(field, b):
    return varint(field << 3 | 2) + varint(len(b)) + b


def point(x, y, z):
    return f_double(1, x) + f_double(2, y) + f_double(3, z)


size_pct = lambda v: f_double(1, v)
size_units = lambda v: f_double(2, v)

wrap = (f_double(1, 0.8) + f_varint(3, 2) + f_double(4, 30) + f_varint(5, 3) + f_varint(6, 1)
        + f_bytes(16, point(0.5, 0.5, 0.5)) + f_bytes(17, size_pct(0.5))
        + f_bytes(18, f_varint(1, 3) + f_bytes(2, point(0, 0, 0)) + f_bytes(3, point(0, 0, 1))
                  + f_double(4, 1) + f_double(5, 0.5) + f_bytes(6, size_units(0.1)))
        + f_bytes(19, f_bytes(1, b"hot") + f_bytes(2, size_pct(0.25)))
        + f_bytes(20, f_bytes(1, f_bytes(1, b"hot")) + f_bytes(1, f_bytes(1, b"cold") + f_bytes(1, b"lid")))
        + f_bytes(21, size_units(0.001)) + f_double(22, 0.02) + f_varint(23, 1) + f_varint(24, 400))
put("fuzz_params_proto", "wrap_full", b"\0" + wrap)
put("fuzz_params_proto", "wrap_empty", b"\0")
repair = (f_varint(1, 15) + f_double(2, 0.25) + f_double(3, 0.1) + f_double(6, 0.95) + f_varint(8, 3)
          + f_varint(10, 1) + f_bytes(11, size_pct(0.5)) + f_varint(13, 16) + f_double(14, 1e-3) + f_varint(17, 1))
put("fuzz_params_proto", "repair_full", b"\1" + repair)
# JobSpec: file_name 1, input_format 2 (OBJ = 2), params 3, output_format 4, kind 7, repair_params 8.
spec = f_bytes(1, b"part.obj") + f_varint(2, 2) + f_bytes(3, wrap) + f_varint(4, 1)
put("fuzz_params_proto", "jobspec_wrap", b"\2" + spec)
put("fuzz_params_proto", "jobspec_repair", b"\2" + f_bytes(1, b"x.ply") + f_varint(7, 2) + f_bytes(8, repair))

# ---- fuzz_wrap: see the layout at the top of fuzz_wrap.cpp -------------------------------
W = "fuzz_wrap"


def g(x, y, z):  # grid point bytes: x, y, z on the integer grid
    return bytes([x, y, z])


# A box around the origin, outside, defaults.
put(W, "box_outside", bytes([0, 1, 10, 9, 0]) + bytes([7]) + g(1, 1, 1) + bytes([0x15]))
# Two boxes in two parts (a, b) touching, contact prevention between them.
put(W, "boxes_contact", bytes([8, 0, 8, 9, 0]) + bytes([7]) + g(0, 0, 0) + bytes([0x05])
    + bytes([7 | 64]) + g(2, 0, 0) + bytes([0x05]))
# An inside-out box wrapped inside, with a gap closure.
put(W, "box_inside_gap", bytes([1 | 4, 1, 12, 9, 40]) + bytes([7]) + g(0, 0, 0) + bytes([0x40 | 0x2A]))
# A seed point inside a box with a duplicated and a flipped face.
put(W, "box_seed", bytes([2, 0, 10, 9, 0, 0]) + bytes([50, 50, 50]) + bytes([7]) + g(0, 0, 0) + bytes([0x3F])
    + bytes([1, 3, 2, 5]))
# A tetrahedron plus degenerate triangles: coincident, collinear, near-degenerate.
put(W, "tet_degenerate", bytes([16, 1, 6, 9, 0]) + bytes([9]) + g(0, 0, 0) + g(3, 0, 0) + g(0, 3, 0) + g(0, 0, 3)
    + bytes([3]) + g(1, 1, 1) + g(2, 2, 2) + bytes([4]) + g(0, 0, 0) + g(3, 3, 3)
    + bytes([5]) + g(0, 0, 0) + g(3, 0, 0) + bytes([9]))
# A non-manifold fan: four triangles on one edge of a box.
put(W, "box_fan", bytes([0, 1, 8, 9, 0]) + bytes([7]) + g(1, 1, 1) + bytes([0x15])
    + bytes([6, 0, 0]) + g(6, 6, 6) + bytes([6, 0, 0]) + g(0, 6, 6) + bytes([6, 0, 0]) + g(6, 0, 6))
# Overlapping coplanar copies of a box's faces.
put(W, "box_coplanar", bytes([0, 0, 8, 9, 0]) + bytes([7]) + g(1, 1, 1) + bytes([0x2A])
    + bytes([8, 0, 4]) + bytes([8, 3, 9]) + bytes([8, 7, 30]))
# Tiny (1e-9) and huge (1e9) scales, and far from the origin.
put(W, "tet_tiny", bytes([0, 1, 8, 0, 0]) + bytes([9]) + g(0, 0, 0) + g(3, 0, 0) + g(0, 3, 0) + g(0, 0, 3))
put(W, "tet_huge_far", bytes([128, 1, 8, 18, 0, 5]) + bytes([9]) + g(0, 0, 0) + g(3, 0, 0) + g(0, 3, 0) + g(0, 0, 3))
# Three parts, group against group.
put(W, "three_parts", bytes([8 | 16, 1, 10, 9, 0]) + bytes([9]) + g(0, 0, 0) + g(2, 0, 0) + g(0, 2, 0) + g(0, 0, 2)
    + bytes([9 | 64]) + g(3, 0, 0) + g(5, 0, 0) + g(3, 2, 0) + g(3, 0, 2)
    + bytes([9 | 128]) + g(0, 3, 0) + g(2, 3, 0) + g(0, 5, 0) + g(0, 3, 2))
# An open soup of single triangles.
put(W, "soup", bytes([0, 2, 12, 9, 0]) + bytes([0]) + g(0, 0, 0) + g(5, 0, 0) + g(0, 5, 0)
    + bytes([0]) + g(0, 0, 1) + g(5, 5, 1) + g(0, 5, 3) + bytes([2, 0]) + bytes([1 | 16, 1]))
