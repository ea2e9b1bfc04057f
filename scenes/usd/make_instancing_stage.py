"""Writes a stage for measuring the USD import's speed (not committed:
1.2 MB): 200 meshes of 961 quads each, a point instancer of 100,000
spheres, 100 sphere lights and a camera, with Pixar's usd-core.

    pip install usd-core
    python3 scenes/usd/make_instancing_stage.py OUT.usdc

docs/notebook/measurements.md ("USD stages") times `lightcuts inspect OUT.usdc`.
"""

import random
import sys

from pxr import Gf, Usd, UsdGeom, UsdLux, Vt

stage = Usd.Stage.CreateNew(sys.argv[1])
UsdGeom.SetStageUpAxis(stage, 'Y')
UsdGeom.SetStageMetersPerUnit(stage, 1)
world = UsdGeom.Xform.Define(stage, '/World')
stage.SetDefaultPrim(world.GetPrim())
rng = random.Random(1)
n = 32
points = [Gf.Vec3f(i, (i * j) % 7 * 0.1, j) for i in range(n) for j in range(n)]
indices = []
for i in range(n - 1):
    for j in range(n - 1):
        a = i * n + j
        indices += [a, a + 1, a + n + 1, a + n]
for k in range(200):
    mesh = UsdGeom.Mesh.Define(stage, f'/World/M{k}')
    mesh.CreatePointsAttr(points)
    mesh.CreateFaceVertexCountsAttr([4] * ((n - 1) * (n - 1)))
    mesh.CreateFaceVertexIndicesAttr(indices)
    mesh.CreateSubdivisionSchemeAttr('none')
    UsdGeom.Xformable(mesh).AddTranslateOp().Set(Gf.Vec3d(rng.uniform(-100, 100), 0, rng.uniform(-100, 100)))
instancer = UsdGeom.PointInstancer.Define(stage, '/World/Scatter')
ball = UsdGeom.Sphere.Define(stage, '/World/Scatter/Ball')
ball.CreateRadiusAttr(0.2)
instancer.CreatePrototypesRel().SetTargets([ball.GetPath()])
count = 100000
instancer.CreateProtoIndicesAttr(Vt.IntArray([0] * count))
instancer.CreatePositionsAttr(
    Vt.Vec3fArray([Gf.Vec3f(rng.uniform(-100, 100), 1, rng.uniform(-100, 100)) for _ in range(count)]))
for k in range(100):
    light = UsdLux.SphereLight.Define(stage, f'/World/L{k}')
    light.CreateIntensityAttr(100)
    light.CreateRadiusAttr(0.1)
    UsdGeom.Xformable(light).AddTranslateOp().Set(Gf.Vec3d(rng.uniform(-100, 100), 5, rng.uniform(-100, 100)))
camera = UsdGeom.Camera.Define(stage, '/World/Camera')
xform = UsdGeom.Xformable(camera)
xform.AddTranslateOp().Set(Gf.Vec3d(0, 80, 150))
xform.AddRotateXOp().Set(-30.0)
stage.Save()
