#!/usr/bin/env python3
"""tests/hostile/make_corpus.py DIR -- writes the hostile inputs of issue 15
into DIR (made at test time: nothing large is committed).

Every file is small (the largest, the 200,000-gon, is 6 MB) except the sparse
2 GB file, which takes no disk space. Meshes are written in the units named in
their file names; the garment the cases are built around is made by
`panelize generate` in the test itself (tests/hostile/test_hostile.sh).

SPDX-License-Identifier: GPL-3.0-or-later
"""
import json
import math
import os
import struct
import sys


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def polygon_obj(path, corners, radius):
    """One convex polygon of `corners` corners (a CAD cap) in one face."""
    lines = ["# one %d-gon" % corners]
    for i in range(corners):
        a = 2 * math.pi * i / corners
        lines.append("v %.9f %.9f 0" % (radius * math.cos(a), radius * math.sin(a)))
    lines.append("f " + " ".join(str(i + 1) for i in range(corners)))
    write(path, "\n".join(lines) + "\n")


def morph_gltf(path, targets):
    """One triangle (in metres) with `targets` morph targets sharing one accessor (1.7 MB for 100,000)."""
    positions = struct.pack("<9f", 0, 0, 0, 0.5, 0, 0, 0, 0.5, 0)
    indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    data = positions + indices
    import base64
    uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [0.5, 0.5, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1,
                                    "targets": [{"POSITION": 0}] * targets}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    write(path, json.dumps(doc, separators=(",", ":")))


def ply_huge_count(path):
    """A PLY header declaring 4 billion vertices over 30 bytes of data."""
    header = ("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode() + b"\0" * 30)


def off_huge_count(path):
    write(path, "OFF\n2000000000 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")


def gltf_huge_accessor(path):
    """An accessor declaring 2^31 vertices over a 36-byte buffer."""
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64," + "A" * 48}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 2147483647, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0,
    }
    write(path, json.dumps(doc))


def scaled_obj(src, dst, scale):
    """A copy of an OBJ with every vertex multiplied by `scale`."""
    out = []
    with open(src) as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = (float(t) * scale for t in line.split()[1:4])
                line = "v %.9g %.9g %.9g\n" % (x, y, z)
            out.append(line)
    write(dst, "".join(out))


def first_line_changed(src, dst, prefix, change):
    """A copy of an OBJ with its first line starting with `prefix` replaced by change(line)."""
    out, done = [], False
    with open(src) as f:
        for line in f:
            if not done and line.startswith(prefix):
                line, done = change(line), True
            out.append(line)
    write(dst, "".join(out))


def flipped_obj(src, dst):
    """The first face reversed."""
    first_line_changed(src, dst, "f ", lambda line: "f " + " ".join(reversed(line.split()[1:])) + "\n")


def nan_pose(src, dst):
    """The first vertex not a number."""
    first_line_changed(src, dst, "v ", lambda line: "v nan 0 0\n")


def garment_vertices_and_faces(garment):
    vertices, faces = [], 0
    with open(garment) as f:
        for line in f:
            if line.startswith("v "):
                vertices.append([float(t) for t in line.split()[1:4]])
            elif line.startswith("f "):
                faces += 1
    return vertices, faces


def garment_cases(folder, garment):
    """Cases derived from the generated garment (millimetres, as `panelize generate` writes)."""
    vertices, faces = garment_vertices_and_faces(garment)
    on = [vertices[0], vertices[len(vertices) // 2]]    # two points on the surface
    curve = json.dumps(on)
    write(os.path.join(folder, "sketch_trailing.json"), '{"curves":[%s]} garbage' % curve)
    write(os.path.join(folder, "sketch_far.json"), '{"curves":[[%s,[1700000,0,0]]]}' % json.dumps(on[0]))
    # 1,000 curves on the surface, each across the garment: the samples are capped, not 1,000 x the diagonal;
    # 20,000 curves (2 MB) are more than a sketch may hold.
    write(os.path.join(folder, "sketch_many.json"), '{"curves":[' + ",".join([curve] * 1000) + "]}")
    write(os.path.join(folder, "sketch_too_many.json"), '{"curves":[' + ",".join([curve] * 20000) + "]}")
    write(os.path.join(folder, "panels_zero.txt"), "0\n" * faces)
    scaled_obj(garment, os.path.join(folder, "garment_cm.obj"), 0.1)       # a 0.6 m bodice, in cm
    scaled_obj(garment, os.path.join(folder, "giant_mm.obj"), 150.0)       # a 90 m garment in mm
    scaled_obj(garment, os.path.join(folder, "tiny_mm.obj"), 0.015)        # a 9 mm garment in mm
    scaled_obj(garment, os.path.join(folder, "pose_cm.obj"), 0.1)          # a pose in cm for a base in mm
    flipped_obj(garment, os.path.join(folder, "flipped.obj"))
    nan_pose(garment, os.path.join(folder, "pose_nan.obj"))


def plain_cases(folder):
    j = lambda name: os.path.join(folder, name)
    polygon_obj(j("poly5000.obj"), 5000, 150.0)
    polygon_obj(j("poly200k.obj"), 200000, 1000.0)
    morph_gltf(j("morph100k.gltf"), 100000)
    ply_huge_count(j("huge_count.ply"))
    off_huge_count(j("huge_count.off"))
    gltf_huge_accessor(j("huge_accessor.gltf"))
    write(j("huge_index.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 2000000000\n")
    write(j("empty.obj"), "")
    with open(j("binary.obj"), "wb") as f:
        f.write(bytes(range(256)) * 64)
    with open(j("sparse.ply"), "wb") as f:    # 2 GB of zeros, no disk space
        f.truncate(2 << 30)
    # JSON inputs: sketches and feature curves.
    write(j("sketch_1e306.json"), '{"curves":[[[1e306,0,0],[0,1e306,0]]]}')
    write(j("sketch_deep.json"), "[" * 100000 + "]" * 100000)
    write(j("features_trailing.json"),
          '{"curves":[{"kind":"key","points":[[0,0,0],[1,0,0]]}]}{"curves":[]}')
    # Line files: panels, seams, darts, allowances.
    write(j("panels_garbage.txt"), "0\n1\nbanana\n")
    write(j("panels_huge.txt"), "4000000000\n")
    write(j("seams_huge.txt"), "0 99999999999\n")
    write(j("darts_garbage.txt"), "0\n1 2 3 4\n")
    write(j("allowances_garbage.txt"), "0 1 1e300\n")


def main():
    folder = sys.argv[1]
    os.makedirs(folder, exist_ok=True)
    if len(sys.argv) > 2:
        garment_cases(folder, sys.argv[2])
    else:
        plain_cases(folder)


if __name__ == "__main__":
    main()
