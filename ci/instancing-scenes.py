#!/usr/bin/env python3
"""Writes two glTF files of the same 10,000 balls (an icosphere of 1,280
triangles each, on a 100 x 100 grid): DIR/instanced.gltf, one node with
EXT_mesh_gpu_instancing's 10,000 translations, and DIR/nodes.gltf, 10,000
nodes sharing one mesh. docs/notebook/measurements.md ("Instances") renders both.

    python3 ci/instancing-scenes.py DIR
"""
import base64
import json
import math
import struct
import os
import sys


def icosphere(levels):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    unit = lambda p: tuple(c / math.sqrt(sum(x * x for x in p)) for c in p)
    v = [unit(p) for p in v]
    for _ in range(levels):
        cache, finer = {}, []

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                v.append(unit([(v[a][i] + v[b][i]) / 2 for i in range(3)]))
                cache[key] = len(v) - 1
            return cache[key]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = finer
    return v, f


def scene(v, f, n, instanced):
    pos = b"".join(struct.pack("<3f", *[0.4 * x for x in p]) for p in v)
    nrm = b"".join(struct.pack("<3f", *p) for p in v)
    idx = b"".join(struct.pack("<3I", *t) for t in f)
    places = [(i - n / 2, 0.4, j - n / 2) for i in range(n) for j in range(n)]
    tr = b"".join(struct.pack("<3f", *p) for p in places) if instanced else b""
    data = pos + nrm + idx + tr
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
             {"buffer": 0, "byteOffset": len(pos), "byteLength": len(nrm)},
             {"buffer": 0, "byteOffset": len(pos) + len(nrm), "byteLength": len(idx)}]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3", "min": [-0.4] * 3, "max": [0.4] * 3},
        {"bufferView": 1, "componentType": 5126, "count": len(v), "type": "VEC3"},
        {"bufferView": 2, "componentType": 5125, "count": 3 * len(f), "type": "SCALAR"}]
    doc = {"asset": {"version": "2.0"}, "scene": 0, "accessors": accessors, "bufferViews": views,
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0}}]}
    if instanced:
        views.append({"buffer": 0, "byteOffset": len(pos) + len(nrm) + len(idx), "byteLength": len(tr)})
        accessors.append({"bufferView": 3, "componentType": 5126, "count": n * n, "type": "VEC3"})
        doc["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
        doc["nodes"] = [{"mesh": 0, "name": "ball",
                         "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 3}}}}]
    else:
        doc["nodes"] = [{"mesh": 0, "name": f"ball{k}", "translation": list(p)} for k, p in enumerate(places)]
    doc["scenes"] = [{"nodes": list(range(len(doc["nodes"])))}]
    uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    doc["buffers"] = [{"byteLength": len(data), "uri": uri}]
    return doc


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    v, f = icosphere(3)
    for name, instanced in [("instanced", True), ("nodes", False)]:
        with open(f"{out}/{name}.gltf", "w") as file:
            json.dump(scene(v, f, 100, instanced), file)


if __name__ == "__main__":
    main()
