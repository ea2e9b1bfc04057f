"""Writes the USD fixtures of tests/usd.rs with Pixar's own library
(usd-core), and what each should render as, computed here from the
UsdLux schema and closed forms, not by the renderer:

    pip install usd-core numpy
    python3 scenes/usd/make_fixtures.py

- lights/*.usda: one light of each UsdLux kind (and an emissive
  UsdPreviewSurface mesh) over a Lambertian floor, in Y-up metres or
  Z-up centimetres, with a camera looking at the floor's centre past
  the light (and, for the textured dome, a second at a wall patch).
  lights/expected.json holds each stage's irradiance at the point each
  camera looks at, in W/m^2, from the schema's units: L = intensity x
  2^exposure x color, divided by the light's area in stage units^2 when
  normalize is on (a distant light's: its irradiance is then L itself,
  else L times its disc's solid angle); a sphere's far field L pi r^2 / d^2;
  a rectangle's, a disk's and a quad's by their form factors; a cylinder's
  and the textured dome's by quadrature here.
- fuzz/stage.usda and fuzz/stage.usdc: one small stage with most of what
  the import reads (an indexed, face-varying mesh split by GeomSubsets, a
  textured material, gprims, an internal instanceable reference, a point
  instancer, time samples, every UsdLux light, a camera), as text and as a
  crate file, for tests/fuzz.rs to mutate; fuzz/texture.jpg, a 16 x 16
  baseline JPEG of one colour (Pillow, when installed), for the tests of
  texture headers and the fuzzer's JPEG mutants.
- resolution/: asset paths as USD resolves them. root.usda references
  layers/asset.usda, whose material names `@../textures/checker.png@`
  (beside the layer that authors it, not the root), `@./flat.png@`, a
  search path `@maps/search.png@` found only under search/ (given as a
  search path), and `@missing.png@`, which is nowhere (its fallback is
  used). A second material reads the mesh's displayColor through a
  UsdPrimvarReader_float3. expected.json holds usd-core's own
  resolvedPath of each (relative to resolution/; null where it finds
  nothing), with search/ on ArDefaultResolver's search path.
- broken/huge-count.usdc is not written here: it is fuzz/stage.usdc with
  byte 100 set to 207 (found by mutating each byte), an array count that asks
  the reader for 3.5 TB; tests/usd.rs checks that the command reports it.
- composition/: a stage with a reference, a payload, a variant set, three
  instances of an instanceable asset and a textured quad, packaged as
  composition.usdz; composition/expected.json holds usd-core's own
  evaluation of it: every drawn gprim's path and world bounds (metres, the
  renderer's +y-up frame).

The floor is UsdPreviewSurface's specular workflow with a black
specularColor and roughness 1, so that it reflects as a Lambertian of its
diffuseColor: the specular term's Fresnel factor is (1 - v.h)^5 at most,
below 1e-4 for these cameras and lights.
"""

import json
import math
import os
import shutil
import struct
import zlib

import numpy as np
from pxr import Ar, Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, UsdUtils, Vt

HERE = os.path.dirname(os.path.abspath(__file__))
ALBEDO = 0.5


def stage_at(path, up='Y', meters=1.0):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up == 'Y' else UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, meters)
    world = UsdGeom.Xform.Define(stage, '/World')
    stage.SetDefaultPrim(world.GetPrim())
    return stage


def lambert(stage, path, albedo=ALBEDO):
    material = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, path + '/Surface')
    shader.CreateIdAttr('UsdPreviewSurface')
    shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(albedo, albedo, albedo))
    shader.CreateInput('useSpecularWorkflow', Sdf.ValueTypeNames.Int).Set(1)
    shader.CreateInput('specularColor', Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0, 0, 0))
    shader.CreateInput('roughness', Sdf.ValueTypeNames.Float).Set(1.0)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
    return material


def up_vector(up):
    return Gf.Vec3d(0, 1, 0) if up == 'Y' else Gf.Vec3d(0, 0, 1)


def frame(up):
    """(horizontal u, horizontal v, up) of a stage."""
    if up == 'Y':
        return np.array([1.0, 0, 0]), np.array([0, 0, -1.0]), np.array([0, 1.0, 0])
    return np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])


def quad(stage, path, centre, u, v, material):
    """A quad centre +- u/2 +- v/2 facing u x v."""
    c, u, v = np.array(centre), np.array(u), np.array(v)
    corners = [c - u / 2 - v / 2, c + u / 2 - v / 2, c + u / 2 + v / 2, c - u / 2 + v / 2]
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in corners])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    mesh.CreateSubdivisionSchemeAttr('none')
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    return mesh


def floor(stage, up, size):
    u, v, _ = frame(up)
    quad(stage, '/World/Floor', [0, 0, 0], u * size, v * size, lambert(stage, '/World/Looks/Floor'))


def camera_looking(stage, path, eye, target, up_hint, focal=200.0, aperture=(2.0, 2.0)):
    """A camera at eye looking at target (its -Z), by default with a
    narrow field (a 2 x 2 aperture at 200 mm: 0.57 degrees)."""
    camera = UsdGeom.Camera.Define(stage, path)
    camera.CreateFocalLengthAttr(focal)
    camera.CreateHorizontalApertureAttr(aperture[0])
    camera.CreateVerticalApertureAttr(aperture[1])
    camera.CreateClippingRangeAttr(Gf.Vec2f(0.01, 1e6))
    look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(*target), up_hint).GetInverse()
    UsdGeom.Xformable(camera).AddTransformOp().Set(look)


def place_down(light, position, up):
    """Puts a light at `position` shining straight down (its -Z along -up)."""
    xform = UsdGeom.Xformable(light)
    xform.AddTranslateOp().Set(Gf.Vec3d(*position))
    if up == 'Y':
        xform.AddRotateXOp().Set(-90.0)


def lux(light, intensity=None, exposure=None, color=None, normalize=None):
    api = light.LightAPI() if hasattr(light, 'LightAPI') else light
    if intensity is not None:
        api.CreateIntensityAttr(intensity)
    if exposure is not None:
        api.CreateExposureAttr(exposure)
    if color is not None:
        api.CreateColorAttr(Gf.Vec3f(*color))
    if normalize is not None:
        api.CreateNormalizeAttr(normalize)


def rectangle_factor(a, b):
    """Form factor from a point to a parallel rectangle a x b (in units of
    the height) with one corner straight above it."""
    return (a / math.sqrt(1 + a * a) * math.atan(b / math.sqrt(1 + a * a))
            + b / math.sqrt(1 + b * b) * math.atan(a / math.sqrt(1 + b * b))) / (2 * math.pi)


def radiance(intensity, exposure, color):
    return [intensity * 2 ** exposure * c for c in color]


def write_lights():
    out = os.path.join(HERE, 'lights')
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    expected = {}

    def new(name, up='Y', meters=1.0, floor_size=20.0):
        stage = stage_at(os.path.join(out, name + '.usda'), up, meters)
        floor(stage, up, floor_size)
        return stage

    def look_down(stage, up, height):
        """A camera over the floor's centre, 56 degrees off its normal, so
        that it looks past the light above the centre, not at it (the
        floor's specular term stays below 1e-4 there)."""
        u, _, n = frame(up)
        camera_looking(stage, '/World/Camera', list(n * height + u * 1.5 * height), [0, 0, 0], Gf.Vec3d(*n))

    # A sphere light, not normalised: E = L pi r^2 / d^2 (its far field is exact
    # for a sphere wholly above the tangent plane).
    stage = new('sphere')
    light = UsdLux.SphereLight.Define(stage, '/World/Bulb')
    light.CreateRadiusAttr(0.1)
    lux(light, intensity=100.0, exposure=1.0, color=(1.0, 0.5, 0.25))
    UsdGeom.Xformable(light).AddTranslateOp().Set(Gf.Vec3d(0, 2, 0))
    look_down(stage, 'Y', 4.0)
    stage.Save()
    expected['sphere'] = {'/World/Camera': [x * math.pi * 0.1 ** 2 / 2.0 ** 2 for x in radiance(100, 1, (1, 0.5, 0.25))]}

    # Normalised, in centimetres and Z up: L / (4 pi r^2) per cm^2 times pi r^2
    # / d^2, all in centimetres: L / (4 d^2), whatever the radius.
    stage = new('sphere_normalized', 'Z', 0.01, 2000.0)
    light = UsdLux.SphereLight.Define(stage, '/World/Bulb')
    light.CreateRadiusAttr(5.0)
    lux(light, intensity=1.0e6, normalize=True)
    UsdGeom.Xformable(light).AddTranslateOp().Set(Gf.Vec3d(0, 0, 200))
    look_down(stage, 'Z', 400.0)
    stage.Save()
    expected['sphere_normalized'] = {'/World/Camera': [1.0e6 / (4 * 200.0 ** 2)] * 3}

    # A spot: a sphere light with ShapingAPI, the point on its axis.
    stage = new('spot')
    light = UsdLux.SphereLight.Define(stage, '/World/Spot')
    light.CreateRadiusAttr(0.05)
    lux(light, intensity=2000.0)
    UsdLux.ShapingAPI.Apply(light.GetPrim()).CreateShapingConeAngleAttr(30.0)
    place_down(light, (0, 3, 0), 'Y')
    look_down(stage, 'Y', 6.0)
    stage.Save()
    expected['spot'] = {'/World/Camera': [2000.0 * math.pi * 0.05 ** 2 / 3.0 ** 2] * 3}

    # A rectangle 1.2 x 0.8 one metre up, centred: E = pi L F, F four
    # quadrants' form factors.
    for name, up, meters, normalize in [('rect', 'Y', 1.0, False), ('rect_normalized', 'Z', 0.01, True)]:
        scale = 1.0 / meters
        stage = new(name, up, meters, 20.0 * scale)
        light = UsdLux.RectLight.Define(stage, '/World/Panel')
        light.CreateWidthAttr(1.2 * scale)
        light.CreateHeightAttr(0.8 * scale)
        lux(light, intensity=5.0 if not normalize else 5.0e4, color=(0.9, 1.0, 0.8), normalize=normalize)
        _, _, n = frame(up)
        place_down(light, tuple(n * scale), up)
        look_down(stage, up, 2.0 * scale)
        stage.Save()
        area = (1.2 * scale) * (0.8 * scale)
        L = [x / (area if normalize else 1.0) for x in radiance(5.0 if not normalize else 5.0e4, 0, (0.9, 1.0, 0.8))]
        factor = 4 * rectangle_factor(0.6, 0.4)
        expected[name] = {'/World/Camera': [math.pi * x * factor for x in L]}

    # A disk of radius 0.5 one metre up: E = pi L R^2 / (R^2 + d^2).
    stage = new('disk')
    light = UsdLux.DiskLight.Define(stage, '/World/Disk')
    light.CreateRadiusAttr(0.5)
    lux(light, intensity=3.0)
    place_down(light, (0, 1, 0), 'Y')
    look_down(stage, 'Y', 2.0)
    stage.Save()
    expected['disk'] = {'/World/Camera': [math.pi * 3.0 * 0.25 / (0.25 + 1.0)] * 3}

    # A cylinder (along x, radius 0.1, length 1) one metre up: by quadrature
    # over its side (a convex surface sees the point where n . (p - x) > 0).
    stage = new('cylinder')
    light = UsdLux.CylinderLight.Define(stage, '/World/Tube')
    light.CreateRadiusAttr(0.1)
    light.CreateLengthAttr(1.0)
    lux(light, intensity=4.0)
    UsdGeom.Xformable(light).AddTranslateOp().Set(Gf.Vec3d(0, 1, 0))
    look_down(stage, 'Y', 2.0)
    stage.Save()
    n_len, n_phi = 2000, 2000
    total = 0.0
    for i in range(n_len):
        x = -0.5 + (i + 0.5) / n_len
        phi = (np.arange(n_phi) + 0.5) / n_phi * 2 * math.pi
        normal = np.stack([np.zeros_like(phi), np.cos(phi), np.sin(phi)], axis=1)
        point = np.stack([np.full_like(phi, x), 1.0 + 0.1 * np.cos(phi), 0.1 * np.sin(phi)], axis=1)
        to_p = -point
        d2 = (to_p ** 2).sum(axis=1)
        d = np.sqrt(d2)
        cos_s = np.maximum((normal * to_p).sum(axis=1) / d, 0)
        cos_r = np.maximum(point[:, 1] / d, 0)
        total += (cos_s * cos_r / d2).sum() * (1.0 / n_len) * (0.1 * 2 * math.pi / n_phi)
    expected['cylinder'] = {'/World/Camera': [4.0 * total] * 3}

    # The sun at its fallbacks (intensity 50,000, angle 0.53 degrees, not
    # normalised), 30 degrees from the zenith: E = L x (its disc's solid
    # angle) x cos 30.
    stage = new('distant')
    light = UsdLux.DistantLight.Define(stage, '/World/Sun')
    UsdGeom.Xformable(light).AddRotateXOp().Set(-60.0)
    look_down(stage, 'Y', 2.0)
    stage.Save()
    solid_angle = 2 * math.pi * (1 - math.cos(math.radians(0.53 / 2)))
    expected['distant'] = {'/World/Camera': [50000.0 * solid_angle * math.cos(math.radians(30))] * 3}

    # Normalised, Z up: E = L cos theta, whatever the angle.
    stage = new('distant_normalized', 'Z', 1.0)
    light = UsdLux.DistantLight.Define(stage, '/World/Sun')
    light.CreateAngleAttr(2.0)
    lux(light, intensity=3.0, color=(1.0, 0.9, 0.7), normalize=True)
    UsdGeom.Xformable(light).AddRotateYOp().Set(40.0)
    look_down(stage, 'Z', 2.0)
    stage.Save()
    expected['distant_normalized'] = {'/World/Camera': [3.0 * c * math.cos(math.radians(40)) for c in (1.0, 0.9, 0.7)]}

    # A constant dome: E = pi L over the upper hemisphere.
    stage = new('dome')
    light = UsdLux.DomeLight.Define(stage, '/World/Sky')
    lux(light, intensity=0.5, exposure=-1.0, color=(1.0, 0.8, 0.6))
    look_down(stage, 'Y', 2.0)
    stage.Save()
    expected['dome'] = {'/World/Camera': [math.pi * x for x in radiance(0.5, -1, (1.0, 0.8, 0.6))]}

    # A textured dome, turned 90 degrees about its y, in a Z-up stage (so its
    # pole lies along the stage's y): a floor patch and a wall patch facing
    # the stage's +x, each by quadrature over the texture in USD's
    # convention (OpenEXR's lat-long on the dome's own +y pole).
    write_dome_texture(os.path.join(out, 'sky.exr'))
    stage = stage_at(os.path.join(out, 'dome_texture.usda'), 'Z', 1.0)
    material = lambert(stage, '/World/Looks/Patch')
    quad(stage, '/World/Floor', [0, 0, 0], [1, 0, 0], [0, 1, 0], material)
    quad(stage, '/World/Wall', [500, 0, 0], [0, 1, 0], [0, 0, 1], material)
    light = UsdLux.DomeLight.Define(stage, '/World/Sky')
    light.CreateTextureFileAttr('sky.exr')
    light.CreateTextureFormatAttr('latlong')
    lux(light, intensity=2.0)
    UsdGeom.Xformable(light).AddRotateYOp().Set(90.0)
    camera_looking(stage, '/World/FloorCamera', [0, 0, 2], [0, 0, 0], Gf.Vec3d(1, 0, 0))
    camera_looking(stage, '/World/WallCamera', [502, 0, 0], [500, 0, 0], Gf.Vec3d(0, 0, 1))
    stage.Save()
    rotation = np.array(Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(0, 1, 0), 90.0)))[:3, :3].T
    expected['dome_texture'] = {
        '/World/FloorCamera': dome_irradiance(os.path.join(out, 'sky.exr'), rotation, np.array([0, 0, 1.0]), 2.0),
        '/World/WallCamera': dome_irradiance(os.path.join(out, 'sky.exr'), rotation, np.array([1.0, 0, 0]), 2.0),
    }

    # An emissive UsdPreviewSurface quad 0.8 x 0.8 one metre up, facing
    # down: an area light of its emissiveColor.
    stage = new('mesh_emitter')
    material = UsdShade.Material.Define(stage, '/World/Looks/Glow')
    shader = UsdShade.Shader.Define(stage, '/World/Looks/Glow/Surface')
    shader.CreateIdAttr('UsdPreviewSurface')
    shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0, 0, 0))
    shader.CreateInput('emissiveColor', Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(2.0, 1.5, 1.0))
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
    # u x v = (0.8, 0, 0) x (0, 0, 0.8) points down.
    quad(stage, '/World/Glow', [0, 1, 0], [0.8, 0, 0], [0, 0, 0.8], material)
    look_down(stage, 'Y', 2.0)
    stage.Save()
    factor = 4 * rectangle_factor(0.4, 0.4)
    expected['mesh_emitter'] = {'/World/Camera': [math.pi * x * factor for x in (2.0, 1.5, 1.0)]}

    with open(os.path.join(out, 'expected.json'), 'w') as f:
        json.dump({'albedo': ALBEDO, 'irradiance': expected}, f, indent=1, sort_keys=True)


SKY_SIZE = (64, 32)


def sky_texels():
    """A dim sky with one bright patch: longitude 40..70 degrees, latitude
    20..45 (OpenEXR's lat-long: x from longitude +pi at the left to -pi,
    y from latitude +pi/2 at the top)."""
    width, height = SKY_SIZE
    texels = np.full((height, width, 3), 0.05, dtype=np.float32)
    for y in range(height):
        lat = math.pi / 2 - (y + 0.5) / height * math.pi
        for x in range(width):
            lon = math.pi - (x + 0.5) / width * 2 * math.pi
            if math.radians(40) <= lon <= math.radians(70) and math.radians(20) <= lat <= math.radians(45):
                texels[y, x] = (20.0, 16.0, 12.0)
    return texels


def write_dome_texture(path):
    """The sky as an uncompressed scan-line OpenEXR of 32-bit floats."""
    texels = sky_texels()
    height, width, _ = texels.shape

    def attribute(name, kind, value):
        return name.encode() + b'\0' + kind.encode() + b'\0' + struct.pack('<i', len(value)) + value

    channels = b''.join(c.encode() + b'\0' + struct.pack('<iBBBBii', 2, 0, 0, 0, 0, 1, 1) for c in 'BGR') + b'\0'
    header = (attribute('channels', 'chlist', channels)
              + attribute('compression', 'compression', b'\0')
              + attribute('dataWindow', 'box2i', struct.pack('<iiii', 0, 0, width - 1, height - 1))
              + attribute('displayWindow', 'box2i', struct.pack('<iiii', 0, 0, width - 1, height - 1))
              + attribute('lineOrder', 'lineOrder', b'\0')
              + attribute('pixelAspectRatio', 'float', struct.pack('<f', 1.0))
              + attribute('screenWindowCenter', 'v2f', struct.pack('<ff', 0, 0))
              + attribute('screenWindowWidth', 'float', struct.pack('<f', 1.0)) + b'\0')
    start = 8 + len(header) + 8 * height
    rows, offsets = [], []
    for y in range(height):
        data = b''.join(texels[y, :, k].astype('<f4').tobytes() for k in (2, 1, 0))
        offsets.append(start + sum(len(r) for r in rows))
        rows.append(struct.pack('<ii', y, len(data)) + data)
    with open(path, 'wb') as f:
        f.write(struct.pack('<ii', 20000630, 2) + header + b''.join(struct.pack('<Q', o) for o in offsets) + b''.join(rows))


def dome_irradiance(path, rotation, normal, scale):
    """E at a surface of normal `normal` (stage space) under the dome: the
    sum over the texture's pixels of L cos(theta) d(omega), each pixel's
    direction in the dome's space turned by `rotation` into the stage."""
    texels = sky_texels()
    height, width, _ = texels.shape
    total = np.zeros(3)
    sub = 8
    for y in range(height):
        for x in range(width):
            for sy in range(sub):
                for sx in range(sub):
                    lat = math.pi / 2 - (y + (sy + 0.5) / sub) / height * math.pi
                    lon = math.pi - (x + (sx + 0.5) / sub) / width * 2 * math.pi
                    d = np.array([math.cos(lat) * math.sin(lon), math.sin(lat), math.cos(lat) * math.cos(lon)])
                    cos = float(np.dot(rotation @ d, normal))
                    if cos > 0:
                        d_omega = (2 * math.pi / (width * sub)) * (math.pi / (height * sub)) * math.cos(lat)
                        total += texels[y, x] * cos * d_omega
    return list(scale * total)


def write_composition():
    """A stage that composes: a reference, a payload, a variant set,
    instanceable references and a texture, packaged as a .usdz."""
    out = os.path.join(HERE, 'composition')
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    # The referenced asset: a cube and a sphere, one material with a texture.
    asset = stage_at(os.path.join(out, 'asset.usda'))
    root = UsdGeom.Xform.Define(asset, '/Asset')
    asset.SetDefaultPrim(root.GetPrim())
    cube = UsdGeom.Cube.Define(asset, '/Asset/Box')
    cube.CreateSizeAttr(0.5)
    UsdGeom.Xformable(cube).AddTranslateOp().Set(Gf.Vec3d(0, 0.25, 0))
    ball = UsdGeom.Sphere.Define(asset, '/Asset/Ball')
    ball.CreateRadiusAttr(0.2)
    UsdGeom.Xformable(ball).AddTranslateOp().Set(Gf.Vec3d(0, 0.7, 0))
    asset.Save()
    # The payload: a sphere whose size is a variant.
    payload = stage_at(os.path.join(out, 'payload.usda'))
    prop = UsdGeom.Xform.Define(payload, '/Prop')
    payload.SetDefaultPrim(prop.GetPrim())
    sizes = prop.GetPrim().GetVariantSets().AddVariantSet('size')
    for name, radius in [('small', 0.3), ('large', 0.6)]:
        sizes.AddVariant(name)
        sizes.SetVariantSelection(name)
        with sizes.GetVariantEditContext():
            UsdGeom.Sphere.Define(payload, '/Prop/Globe').CreateRadiusAttr(radius)
    sizes.SetVariantSelection('small')
    payload.Save()
    # A texture, a 2 x 2 PNG.
    write_png(os.path.join(out, 'checker.png'), [[(230, 40, 40), (40, 40, 230)], [(40, 230, 40), (230, 230, 230)]])
    main = stage_at(os.path.join(out, 'main.usda'))
    for k, x in enumerate((-1.5, 0.0, 1.5)):
        instance = UsdGeom.Xform.Define(main, f'/World/Asset{k}')
        instance.GetPrim().GetReferences().AddReference('./asset.usda')
        instance.GetPrim().SetInstanceable(True)
        UsdGeom.Xformable(instance).AddTranslateOp().Set(Gf.Vec3d(x, 0, -1))
        UsdGeom.Xformable(instance).AddRotateYOp().Set(30.0 * k)
    prop = UsdGeom.Xform.Define(main, '/World/Prop')
    prop.GetPrim().GetPayloads().AddPayload('./payload.usda')
    prop.GetPrim().GetVariantSets().GetVariantSet('size').SetVariantSelection('large')
    UsdGeom.Xformable(prop).AddTranslateOp().Set(Gf.Vec3d(0, 0.6, 1))
    material = UsdShade.Material.Define(main, '/World/Looks/Checker')
    shader = UsdShade.Shader.Define(main, '/World/Looks/Checker/Surface')
    shader.CreateIdAttr('UsdPreviewSurface')
    texture = UsdShade.Shader.Define(main, '/World/Looks/Checker/Texture')
    texture.CreateIdAttr('UsdUVTexture')
    texture.CreateInput('file', Sdf.ValueTypeNames.Asset).Set('checker.png')
    texture.CreateInput('wrapS', Sdf.ValueTypeNames.Token).Set('repeat')
    texture.CreateInput('wrapT', Sdf.ValueTypeNames.Token).Set('repeat')
    reader = UsdShade.Shader.Define(main, '/World/Looks/Checker/Coordinates')
    reader.CreateIdAttr('UsdPrimvarReader_float2')
    reader.CreateInput('varname', Sdf.ValueTypeNames.String).Set('st')
    texture.CreateInput('st', Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), 'result')
    texture.CreateOutput('rgb', Sdf.ValueTypeNames.Float3)
    shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).ConnectToSource(texture.ConnectableAPI(), 'rgb')
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
    ground = quad(main, '/World/Ground', [0, 0, 0], [6, 0, 0], [0, 0, -6], material)
    st = UsdGeom.PrimvarsAPI(ground).CreatePrimvar('st', Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    st.Set(Vt.Vec2fArray([Gf.Vec2f(0, 0), Gf.Vec2f(3, 0), Gf.Vec2f(3, 3), Gf.Vec2f(0, 3)]))
    sun = UsdLux.DistantLight.Define(main, '/World/Sun')
    lux(sun, intensity=3.0, normalize=True)
    UsdGeom.Xformable(sun).AddRotateXOp().Set(-50.0)
    sky = UsdLux.DomeLight.Define(main, '/World/Sky')
    lux(sky, intensity=0.3)
    camera_looking(main, '/World/Camera', [0, 2.5, 5], [0, 0.3, 0], Gf.Vec3d(0, 1, 0), 35.0, (36.0, 24.0))
    main.Save()
    UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(os.path.join(out, 'main.usda')), os.path.join(out, 'composition.usdz'))

    # usd-core's evaluation of the package: every drawn gprim's world bounds.
    stage = Usd.Stage.Open(os.path.join(out, 'composition.usdz'))
    cache = UsdGeom.BBoxCache(Usd.TimeCode.Default(), [UsdGeom.Tokens.default_, UsdGeom.Tokens.render])
    objects = {}
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if prim.IsA(UsdGeom.Gprim):
            box = cache.ComputeWorldBound(prim).ComputeAlignedRange()
            objects[str(prim.GetPath())] = [list(box.GetMin()), list(box.GetMax())]
    with open(os.path.join(out, 'expected.json'), 'w') as f:
        json.dump({'objects': objects}, f, indent=1, sort_keys=True)


def write_png(path, rows):
    """An 8-bit RGB PNG of `rows` (lists of (r, g, b))."""
    height, width = len(rows), len(rows[0])
    raw = b''.join(b'\0' + bytes(c for pixel in row for c in pixel) for row in rows)

    def chunk(kind, data):
        return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)

    ihdr = struct.pack('>IIBBBBB', width, height, 8, 2, 0, 0, 0)
    with open(path, 'wb') as f:
        f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', ihdr) + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))


def write_fuzz():
    out = os.path.join(HERE, 'fuzz')
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    stage = stage_at(os.path.join(out, 'stage.usda'), 'Z', 0.1)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(10)
    write_png(os.path.join(out, 'texture.png'), [[(200, 30, 30), (30, 200, 30)], [(30, 30, 200), (220, 220, 220)]])
    try:
        from PIL import Image
        Image.new('RGB', (16, 16), (100, 150, 200)).save(os.path.join(out, 'texture.jpg'), quality=90)
    except ImportError:
        print('Pillow is not installed: fuzz/texture.jpg left as it is')
    material = UsdShade.Material.Define(stage, '/World/Looks/Textured')
    shader = UsdShade.Shader.Define(stage, '/World/Looks/Textured/Surface')
    shader.CreateIdAttr('UsdPreviewSurface')
    texture = UsdShade.Shader.Define(stage, '/World/Looks/Textured/Texture')
    texture.CreateIdAttr('UsdUVTexture')
    texture.CreateInput('file', Sdf.ValueTypeNames.Asset).Set('texture.png')
    texture.CreateInput('wrapS', Sdf.ValueTypeNames.Token).Set('mirror')
    texture.CreateInput('scale', Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(0.9, 0.9, 0.9, 1))
    reader = UsdShade.Shader.Define(stage, '/World/Looks/Textured/Coordinates')
    reader.CreateIdAttr('UsdPrimvarReader_float2')
    reader.CreateInput('varname', Sdf.ValueTypeNames.String).Set('st')
    turn = UsdShade.Shader.Define(stage, '/World/Looks/Textured/Turn')
    turn.CreateIdAttr('UsdTransform2d')
    turn.CreateInput('rotation', Sdf.ValueTypeNames.Float).Set(30.0)
    turn.CreateInput('in', Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), 'result')
    texture.CreateInput('st', Sdf.ValueTypeNames.Float2).ConnectToSource(turn.ConnectableAPI(), 'result')
    shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).ConnectToSource(texture.ConnectableAPI(), 'rgb')
    shader.CreateInput('roughness', Sdf.ValueTypeNames.Float).ConnectToSource(texture.ConnectableAPI(), 'g')
    shader.CreateInput('metallic', Sdf.ValueTypeNames.Float).Set(0.3)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
    glow = UsdShade.Material.Define(stage, '/World/Looks/Glow')
    glow_shader = UsdShade.Shader.Define(stage, '/World/Looks/Glow/Surface')
    glow_shader.CreateIdAttr('UsdPreviewSurface')
    glow_shader.CreateInput('emissiveColor', Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(3, 3, 2))
    glow.CreateSurfaceOutput().ConnectToSource(glow_shader.ConnectableAPI(), 'surface')
    mesh = UsdGeom.Mesh.Define(stage, '/World/Floor')
    mesh.CreatePointsAttr([Gf.Vec3f(x, y, 0) for x, y in [(-20, -20), (20, -20), (20, 20), (-20, 20), (0, 0)]])
    mesh.CreateFaceVertexCountsAttr([3, 3, 3, 3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4])
    normals = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar('normals', Sdf.ValueTypeNames.Normal3fArray, UsdGeom.Tokens.faceVarying)
    normals.Set(Vt.Vec3fArray([Gf.Vec3f(0, 0, 1)]))
    normals.SetIndices(Vt.IntArray([0] * 12))
    st = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar('st', Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    st.Set(Vt.Vec2fArray([Gf.Vec2f(0, 0), Gf.Vec2f(2, 0), Gf.Vec2f(2, 2), Gf.Vec2f(0, 2), Gf.Vec2f(1, 1)]))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    subset = UsdGeom.Subset.Define(stage, '/World/Floor/Glowing')
    subset.CreateElementTypeAttr('face')
    subset.CreateFamilyNameAttr('materialBind')
    subset.CreateIndicesAttr([2])
    UsdShade.MaterialBindingAPI.Apply(subset.GetPrim()).Bind(glow)
    proto = UsdGeom.Xform.Define(stage, '/World/Proto')
    cube = UsdGeom.Cube.Define(stage, '/World/Proto/Box')
    cube.CreateSizeAttr(2.0)
    cylinder = UsdGeom.Cylinder.Define(stage, '/World/Proto/Post')
    UsdGeom.Xformable(cylinder).AddTranslateOp().Set(Gf.Vec3d(0, 0, 2))
    for k in range(2):
        instance = UsdGeom.Xform.Define(stage, f'/World/Copy{k}')
        instance.GetPrim().GetReferences().AddInternalReference('/World/Proto')
        instance.GetPrim().SetInstanceable(True)
        UsdGeom.Xformable(instance).AddTranslateOp().Set(Gf.Vec3d(-8 + 4 * k, 4, 0))
    ball = UsdGeom.Sphere.Define(stage, '/World/Ball')
    ball.CreateRadiusAttr(1.5)
    moving = UsdGeom.Xformable(ball).AddTranslateOp()
    moving.Set(Gf.Vec3d(0, -5, 1.5), 1)
    moving.Set(Gf.Vec3d(3, -5, 1.5), 10)
    instancer = UsdGeom.PointInstancer.Define(stage, '/World/Scatter')
    cone = UsdGeom.Cone.Define(stage, '/World/Scatter/Cone')
    instancer.CreatePrototypesRel().SetTargets([cone.GetPath()])
    instancer.CreateProtoIndicesAttr([0, 0, 0])
    instancer.CreatePositionsAttr([Gf.Vec3f(6, 0, 1), Gf.Vec3f(8, 2, 1), Gf.Vec3f(6, 4, 1)])
    instancer.CreateOrientationsAttr([Gf.Quath(1, 0, 0, 0)] * 3)
    instancer.CreateScalesAttr([Gf.Vec3f(1, 1, 1), Gf.Vec3f(0.5, 0.5, 2), Gf.Vec3f(1, 1, 1)])
    sphere = UsdLux.SphereLight.Define(stage, '/World/Lights/Bulb')
    sphere.CreateRadiusAttr(0.5)
    lux(sphere, intensity=500.0)
    UsdGeom.Xformable(sphere).AddTranslateOp().Set(Gf.Vec3d(0, 0, 12))
    spot = UsdLux.SphereLight.Define(stage, '/World/Lights/Spot')
    lux(spot, intensity=2000.0, normalize=True)
    UsdLux.ShapingAPI.Apply(spot.GetPrim()).CreateShapingConeAngleAttr(25.0)
    UsdGeom.Xformable(spot).AddTranslateOp().Set(Gf.Vec3d(5, 5, 10))
    rect = UsdLux.RectLight.Define(stage, '/World/Lights/Panel')
    lux(rect, intensity=20.0, exposure=1.0)
    UsdGeom.Xformable(rect).AddTranslateOp().Set(Gf.Vec3d(-5, 0, 8))
    disk = UsdLux.DiskLight.Define(stage, '/World/Lights/Disk')
    lux(disk, intensity=10.0, normalize=True)
    UsdGeom.Xformable(disk).AddTranslateOp().Set(Gf.Vec3d(5, -5, 8))
    tube = UsdLux.CylinderLight.Define(stage, '/World/Lights/Tube')
    lux(tube, intensity=8.0)
    UsdGeom.Xformable(tube).AddTranslateOp().Set(Gf.Vec3d(0, 8, 6))
    sun = UsdLux.DistantLight.Define(stage, '/World/Lights/Sun')
    UsdGeom.Xformable(sun).AddRotateXYZOp().Set(Gf.Vec3f(30, 20, 0))
    sky = UsdLux.DomeLight.Define(stage, '/World/Lights/Sky')
    lux(sky, intensity=0.2)
    camera_looking(stage, '/World/Camera', [0, -30, 20], [0, 0, 0], Gf.Vec3d(0, 0, 1), 35.0, (36.0, 27.0))
    stage.Save()
    # The root layer as it is: a stage's Export flattens it and anchors
    # asset paths to this machine's directory.
    stage.GetRootLayer().Export(os.path.join(out, 'stage.usdc'))


def write_resolution():
    """Asset paths resolved against the layer that authors them, a search
    path, a missing texture, and a primvar reader (see the docstring)."""
    out = os.path.join(HERE, 'resolution')
    shutil.rmtree(out, ignore_errors=True)
    for folder in ['layers', 'textures', 'search/maps']:
        os.makedirs(os.path.join(out, folder))
    write_png(os.path.join(out, 'textures', 'checker.png'), [[(230, 40, 40), (40, 40, 230)], [(40, 230, 40), (230, 230, 230)]])
    write_png(os.path.join(out, 'layers', 'flat.png'), [[(40, 200, 40)]])
    write_png(os.path.join(out, 'search', 'maps', 'search.png'), [[(40, 40, 200)]])
    asset = stage_at(os.path.join(out, 'layers', 'asset.usda'))
    root = UsdGeom.Xform.Define(asset, '/Asset')
    asset.SetDefaultPrim(root.GetPrim())
    textures = {}
    for k, (name, file) in enumerate([('Checker', '../textures/checker.png'), ('Flat', './flat.png'),
                                      ('Search', 'maps/search.png'), ('Missing', 'missing.png')]):
        material = UsdShade.Material.Define(asset, f'/Asset/Looks/{name}')
        shader = UsdShade.Shader.Define(asset, f'/Asset/Looks/{name}/Surface')
        shader.CreateIdAttr('UsdPreviewSurface')
        texture = UsdShade.Shader.Define(asset, f'/Asset/Looks/{name}/Texture')
        texture.CreateIdAttr('UsdUVTexture')
        texture.CreateInput('file', Sdf.ValueTypeNames.Asset).Set(file)
        texture.CreateInput('fallback', Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(0.9, 0.6, 0.1, 1.0))
        texture.CreateOutput('rgb', Sdf.ValueTypeNames.Float3)
        shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).ConnectToSource(texture.ConnectableAPI(), 'rgb')
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
        tile = quad(asset, f'/Asset/Tile{name}', [-3 + 2 * k, 0, 0], [1.8, 0, 0], [0, 0, -1.8], material)
        st = UsdGeom.PrimvarsAPI(tile).CreatePrimvar('st', Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
        st.Set(Vt.Vec2fArray([Gf.Vec2f(0, 0), Gf.Vec2f(1, 0), Gf.Vec2f(1, 1), Gf.Vec2f(0, 1)]))
        textures[name] = f'/World/Asset/Looks/{name}/Texture'
    # The mesh's own colour, read by the material through a primvar reader.
    material = UsdShade.Material.Define(asset, '/Asset/Looks/Painted')
    shader = UsdShade.Shader.Define(asset, '/Asset/Looks/Painted/Surface')
    shader.CreateIdAttr('UsdPreviewSurface')
    reader = UsdShade.Shader.Define(asset, '/Asset/Looks/Painted/Colour')
    reader.CreateIdAttr('UsdPrimvarReader_float3')
    reader.CreateInput('varname', Sdf.ValueTypeNames.String).Set('displayColor')
    reader.CreateOutput('result', Sdf.ValueTypeNames.Float3)
    shader.CreateInput('diffuseColor', Sdf.ValueTypeNames.Color3f).ConnectToSource(reader.ConnectableAPI(), 'result')
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), 'surface')
    painted = quad(asset, '/Asset/Painted', [0, 0, -2.2], [7.8, 0, 0], [0, 0, -1.8], material)
    painted.CreateDisplayColorAttr([Gf.Vec3f(0.8, 0.1, 0.7)])
    asset.Save()
    main = stage_at(os.path.join(out, 'root.usda'))
    placed = UsdGeom.Xform.Define(main, '/World/Asset')
    placed.GetPrim().GetReferences().AddReference('./layers/asset.usda')
    sun = UsdLux.DistantLight.Define(main, '/World/Sun')
    lux(sun, intensity=3.0, normalize=True)
    UsdGeom.Xformable(sun).AddRotateXOp().Set(-60.0)
    camera_looking(main, '/World/Camera', [0, 9, 3], [0, 0, -1.1], Gf.Vec3d(0, 1, 0), 35.0, (36.0, 24.0))
    main.Save()
    # usd-core's resolution, with search/ on the default resolver's search path.
    Ar.DefaultResolver.SetDefaultSearchPath([os.path.join(out, 'search')])
    stage = Usd.Stage.Open(os.path.join(out, 'root.usda'))
    expected = {}
    for name, path in textures.items():
        resolved = stage.GetPrimAtPath(path).GetAttribute('inputs:file').Get().resolvedPath
        expected[name] = os.path.relpath(resolved, out) if resolved else None
    with open(os.path.join(out, 'expected.json'), 'w') as f:
        json.dump({'search_path': 'search', 'resolved': expected}, f, indent=1, sort_keys=True)


if __name__ == '__main__':
    write_lights()
    write_composition()
    write_fuzz()
    write_resolution()
