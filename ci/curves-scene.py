#!/usr/bin/env python3
"""Writes DIR/fur.usda with usd-core: a ball of COUNT hairs (cubic
B-spline curves of 6 control points each, 2 mm wide at the root and
0.2 mm at the tip, brown through displayColor) and LIGHTS sphere lights
(256 unless given) around it, with a camera. The curves scene docs/notebook/measurements.md
("Curves and points") measures.

    python3 ci/curves-scene.py DIR [COUNT [LIGHTS]]
"""
import math
import os
import sys

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, Vt


def main():
    out = sys.argv[1]
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 100_000
    lights = int(sys.argv[3]) if len(sys.argv) > 3 else 256
    os.makedirs(out, exist_ok=True)
    stage = Usd.Stage.CreateNew(os.path.join(out, "fur.usda"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    rng = np.random.default_rng(1)
    # Roots spread evenly over a unit sphere (a Fibonacci lattice), each
    # hair 0.3 m long, bending down under gravity.
    k = np.arange(count) + 0.5
    phi = np.arccos(1 - 2 * k / count)
    theta = math.pi * (1 + 5**0.5) * k
    roots = np.stack([np.cos(theta) * np.sin(phi), np.cos(phi), np.sin(theta) * np.sin(phi)], -1)
    points = []
    for t in np.linspace(0.0, 1.0, 6):
        p = roots * (1.0 + 0.3 * t) + np.array([0.0, -0.12, 0.0]) * t * t
        points.append(p + rng.normal(0.0, 0.004, p.shape) * t)
    points = np.stack(points, 1).reshape(-1, 3)
    widths = np.tile(np.linspace(0.002, 0.0002, 6), count)
    curves = UsdGeom.BasisCurves.Define(stage, "/Fur")
    curves.CreateTypeAttr("cubic")
    curves.CreateBasisAttr("bspline")
    curves.CreateCurveVertexCountsAttr(Vt.IntArray([6] * count))
    curves.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)))
    curves.CreateWidthsAttr(Vt.FloatArray.FromNumpy(widths.astype(np.float32)))
    curves.SetWidthsInterpolation(UsdGeom.Tokens.vertex)
    curves.CreateDisplayColorAttr([Gf.Vec3f(0.35, 0.2, 0.1)])
    ball = UsdGeom.Sphere.Define(stage, "/Skin")
    ball.CreateRadiusAttr(1.0)
    ball.CreateDisplayColorAttr([Gf.Vec3f(0.3, 0.2, 0.15)])
    for i in range(lights):
        a = 2 * math.pi * i / lights
        light = UsdLux.SphereLight.Define(stage, f"/Lights/L{i}")
        light.CreateRadiusAttr(0.05)
        light.CreateIntensityAttr(150.0 * 256 / lights)
        light.CreateColorAttr(Gf.Vec3f(1.0, 0.9 + 0.1 * math.sin(a), 0.8))
        UsdGeom.Xformable(light).AddTranslateOp().Set(Gf.Vec3d(4 * math.cos(a), 2 + math.sin(7 * a), 4 * math.sin(a)))
    camera = UsdGeom.Camera.Define(stage, "/Camera")
    camera.CreateFocalLengthAttr(35.0)
    eye, target = Gf.Vec3d(0.0, 1.5, 7.0), Gf.Vec3d(0.0, 0.0, 0.0)
    look = Gf.Matrix4d().SetLookAt(eye, target, Gf.Vec3d(0, 1, 0)).GetInverse()
    camera.AddTransformOp().Set(look)
    stage.GetRootLayer().Save()


if __name__ == "__main__":
    main()
