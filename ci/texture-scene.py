#!/usr/bin/env python3
"""Writes DIR/textured.gltf: a quad under a point light whose material
carries three 4096 x 4096 PNG textures (an sRGB base colour, a normal map
and a metallic-roughness map: 50 million texels), with a camera. The
texture-heavy scene docs/notebook/measurements.md ("Textures in memory") measures.

    python3 ci/texture-scene.py DIR
"""
import json
import os
import sys

import numpy as np
from PIL import Image

SIZE = 4096


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    y, x = np.mgrid[0:SIZE, 0:SIZE].astype(np.float32) / SIZE
    rng = np.random.default_rng(1)
    grain = rng.integers(0, 32, (SIZE, SIZE), dtype=np.uint8)
    checks = ((np.floor(x * 16) + np.floor(y * 16)) % 2).astype(np.uint8)
    base = np.stack([checks * 180 + grain, (x * 200).astype(np.uint8) + grain, (y * 200).astype(np.uint8)], -1)
    normal = np.stack([128 + grain // 4, 128 + grain // 4, np.full_like(grain, 255)], -1)
    mr = np.stack([np.zeros_like(grain), 64 + grain * 4, checks * 255], -1)
    for name, data in [("base.png", base), ("normal.png", normal), ("mr.png", mr)]:
        Image.fromarray(data.astype(np.uint8), "RGB").save(os.path.join(out, name), compress_level=1)
    positions = np.array([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]], np.float32)
    normals = np.array([[0, 1, 0]] * 4, np.float32)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    indices = np.array([0, 2, 1, 0, 3, 2], np.uint32)
    blob = positions.tobytes() + normals.tobytes() + uvs.tobytes() + indices.tobytes()
    with open(os.path.join(out, "quad.bin"), "wb") as f:
        f.write(blob)
    views = [(0, 48, 34962), (48, 48, 34962), (96, 32, 34962), (128, 24, 34963)]
    gltf = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "buffers": [{"uri": "quad.bin", "byteLength": len(blob)}],
        "bufferViews": [{"buffer": 0, "byteOffset": o, "byteLength": n, "target": t} for o, n, t in views],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"},
        ],
        "images": [{"uri": "base.png"}, {"uri": "normal.png"}, {"uri": "mr.png"}],
        "textures": [{"source": 0}, {"source": 1}, {"source": 2}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 2}},
            "normalTexture": {"index": 1},
        }],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 60}]}},
        "nodes": [
            {"mesh": 0},
            {"camera": 0, "translation": [0, 1.5, 2.0], "rotation": [-0.3007, 0, 0, 0.9537]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.3, 1, 0.3]},
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 0,
    }
    with open(os.path.join(out, "textured.gltf"), "w") as f:
        json.dump(gltf, f, indent=1)


if __name__ == "__main__":
    main()
