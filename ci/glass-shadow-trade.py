#!/usr/bin/env python3
"""What stopping shadow rays at glass costs and what letting them through
would cost (docs/design.md §5.8, "Shadow rays stop at glass"), measured on
one lamp in a room: a bulb (an emissive box, 10 cm, radiance 50) and 64
point lights of 0.02 W/sr (1 cd read as 1 W/sr) inside a lampshade (a closed box of 60 cm) over a grey floor with a back
wall, lit by nothing else. The shade is one of:

- `glass`: a clear thin-walled glass shade (KHR_materials_transmission):
  shadow rays stop at it, so the room sees the lamp only through paths;
- `blend`: a shade of alphaMode BLEND and alpha 0.04, which shadow rays
  pass with probability 0.96 through Embree's filter functions (the
  machinery a thin wall's transmission would need, there a colour instead
  of a bit);
- `none`: no shade, the light the room would get.

Each is rendered without and with the path method (--indirect path),
whole processes, and the floor's mean radiance is printed with the time.

    python3 ci/glass-shadow-trade.py BIN [SPP] [--json]
"""
import json
import os
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenEXR


def quad(corner, u, v):
    """Four positions and two triangles, both faces' normals from u x v."""
    c, u, v = np.array(corner, float), np.array(u, float), np.array(v, float)
    return [c, c + u, c + u + v, c + v], [(0, 1, 2), (0, 2, 3)]


def box(centre, half):
    """A closed box's six faces, outward normals, as quads."""
    c = np.array(centre, float)
    h = half
    faces = []
    for axis in range(3):
        for sign in (-1, 1):
            n = np.zeros(3)
            n[axis] = sign
            a = np.zeros(3)
            a[(axis + 1) % 3] = 2 * h
            b = np.zeros(3)
            b[(axis + 2) % 3] = 2 * h
            if sign < 0:
                a, b = b, a
            corner = c + n * h - a / 2 - b / 2
            faces.append(quad(corner, a, b))
    return faces


class Gltf:
    def __init__(self):
        self.doc = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [], "accessors": [],
                    "meshes": [], "nodes": [], "materials": [], "scenes": [{"nodes": []}], "scene": 0,
                    "extensionsUsed": []}
        self.data = bytearray()

    def accessor(self, values, fmt, kind, component, target):
        raw = b"".join(struct.pack(fmt, *v) if isinstance(v, (tuple, list, np.ndarray)) else struct.pack(fmt, v)
                       for v in values)
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(raw), "target": target}
        self.data += raw
        self.doc["bufferViews"].append(view)
        accessor = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": component,
                    "count": len(values), "type": kind}
        if kind == "VEC3":
            arr = np.array(values, float)
            accessor["min"], accessor["max"] = arr.min(0).tolist(), arr.max(0).tolist()
        self.doc["accessors"].append(accessor)
        return len(self.doc["accessors"]) - 1

    def mesh(self, faces, material):
        positions, indices = [], []
        for corners, triangles in faces:
            base = len(positions)
            positions += [tuple(map(float, p)) for p in corners]
            indices += [base + i for t in triangles for i in t]
        p = self.accessor(positions, "<3f", "VEC3", 5126, 34962)
        i = self.accessor(indices, "<I", "SCALAR", 5125, 34963)
        self.doc["meshes"].append({"primitives": [{"attributes": {"POSITION": p}, "indices": i,
                                                   "material": material}]})
        self.node({"mesh": len(self.doc["meshes"]) - 1})

    def material(self, m):
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def node(self, n):
        self.doc["nodes"].append(n)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)

    def write(self, path):
        self.doc["buffers"] = [{"uri": os.path.basename(path) + ".bin", "byteLength": len(self.data)}]
        with open(path + ".bin", "wb") as f:
            f.write(self.data)
        with open(path, "w") as f:
            json.dump(self.doc, f)


def scene(path, shade):
    g = Gltf()
    grey = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0,
                                                "roughnessFactor": 1}})
    g.mesh([quad([-4, 0, 4], [8, 0, 0], [0, 0, -8]), quad([-4, 0, -3], [8, 0, 0], [0, 5, 0])], grey)
    bulb = g.material({"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}, "emissiveFactor": [1, 1, 1],
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 50}}})
    g.mesh(box([0, 1.5, 0], 0.05), bulb)
    lights = []
    for i in range(4):
        for j in range(4):
            for k in range(4):
                lights.append({"type": "point", "color": [1, 0.9, 0.8], "intensity": 0.02})
                g.node({"translation": [-0.15 + 0.1 * i, 1.35 + 0.1 * j, -0.15 + 0.1 * k],
                        "extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}})
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": lights}}
    g.doc["extensionsUsed"] += ["KHR_lights_punctual", "KHR_materials_emissive_strength"]
    if shade == "glass":
        glass = g.material({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0,
                                                     "roughnessFactor": 0},
                            "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}})
        g.doc["extensionsUsed"].append("KHR_materials_transmission")
        g.mesh(box([0, 1.5, 0], 0.3), glass)
    elif shade == "blend":
        blend = g.material({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.04], "metallicFactor": 0,
                                                     "roughnessFactor": 0}, "alphaMode": "BLEND",
                            "doubleSided": True})
        g.mesh(box([0, 1.5, 0], 0.3), blend)
    g.doc["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.01}}]
    g.node({"camera": 0, "translation": [0, 2.2, 5], "rotation": [-0.0998, 0, 0, 0.995]})
    g.write(path)


def floor_mean(exr):
    channels = OpenEXR.File(exr).channels()
    rgb = channels["RGBA"].pixels[..., :3] if "RGBA" in channels else channels["RGB"].pixels
    lower = np.asarray(rgb, float)[rgb.shape[0] * 3 // 4:]
    return float((lower @ [0.2126, 0.7152, 0.0722]).mean())


def main():
    binary = sys.argv[1]
    spp = next((a for a in sys.argv[2:] if a.isdigit()), "16")
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for shade in ("none", "glass", "blend"):
            path = os.path.join(work, f"{shade}.gltf")
            scene(path, shade)
            for indirect in ("none", "path"):
                out = os.path.join(work, f"{shade}-{indirect}.exr")
                start = time.time()
                subprocess.run([binary, "render", path, "-o", out, "--spp", spp, "--resolution", "320x240",
                                "--indirect", indirect, "--lumens-per-watt", "1", "--quiet"], check=True, stdout=subprocess.DEVNULL)
                seconds = time.time() - start
                rows.append({"shade": shade, "indirect": indirect, "seconds": round(seconds, 2),
                             "floor": round(floor_mean(out), 5)})
    if "--json" in sys.argv:
        print(json.dumps(rows, indent=1))
        return
    print(f"| shade | indirect | time ({spp} spp, 320x240) | floor's mean radiance |")
    print("|---|---|---|---|")
    for r in rows:
        print(f"| {r['shade']} | {r['indirect']} | {r['seconds']} s | {r['floor']} |")


main()
