#!/usr/bin/env python3
"""Writes transformed.gltf and missing_bin.gltf (tests/unit/test_mesh.c).

transformed.gltf: a unit quad in the xy plane (normal +z) with normals and
uint16 indices in one base64-embedded buffer, on a child node (rotation 90
degrees about +x, uniform scale 2) under a parent node (translation 1,2,3),
so the importer must apply both transforms; one material with a base colour
and an emissive factor. test_mesh.c builds the same buffer for its runtime
.glb and external-.bin cases: keep the numbers in sync.

missing_bin.gltf: the same document with the buffer in "missing.bin", which
does not exist.

Run from this directory: python3 make_gltf.py
"""
import base64
import json
import math
import struct

POSITIONS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]
NORMALS = [(0, 0, 1)] * 4
INDICES = [0, 1, 2, 0, 2, 3]

buf = b"".join(struct.pack("<3f", *p) for p in POSITIONS)
buf += b"".join(struct.pack("<3f", *n) for n in NORMALS)
buf += struct.pack("<6H", *INDICES)
s = math.sqrt(0.5)


def document(uri):
    return {
        "asset": {"version": "2.0", "generator": "tests/data/meshes/make_gltf.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"translation": [1, 2, 3], "children": [1]},
            {"rotation": [s, 0, 0, s], "scale": [2, 2, 2], "mesh": 0},
        ],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1},
            "indices": 2, "material": 0, "mode": 4}]}],
        "materials": [{
            "name": "glow",
            "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1.0]},
            "emissiveFactor": [0.5, 0.25, 1.0]}],
        "buffers": [{"byteLength": len(buf), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 12,
             "target": 34962},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12, "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4,
             "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4,
             "type": "VEC3"},
            {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 6,
             "type": "SCALAR"},
        ],
    }


embedded = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
for name, uri in (("transformed.gltf", embedded), ("missing_bin.gltf", "missing.bin")):
    with open(name, "w") as f:
        json.dump(document(uri), f, indent=1)
        f.write("\n")
