"""Builds OUT/clearcoat_test/, sheen_chair/, transmission_test/,
glass_vase_flowers/ and toy_car/ and Cycles' references of them with
Blender (the `bpy` module, Blender 5.0.1): the Khronos sample models
ClearCoatTest (CC BY 4.0), SheenChair, TransmissionTest, GlassVaseFlowers
and ToyCar (CC0), each imported by Blender's glTF importer
(KHR_materials_clearcoat becomes the Principled BSDF's coat,
KHR_materials_sheen its sheen, KHR_materials_transmission its
transmission, alpha blending its alpha), framed by a camera,
lit only by Blender's courtyard HDRI (courtyard.exr here, CC0, turned as
make_cycles.py explains), exported again by Blender's glTF exporter with
the camera; Cycles renders each with direct light only (`light_paths`:
through glass, the paths lightcuts follows by default), a box filter one
pixel wide, no denoising, single-scattering GGX (glTF's BRDF has none).

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/environment/make_cycles_layers.py SAMPLE_MODELS_DIR

SAMPLE_MODELS_DIR holds the Khronos glTF sample models' files named in
MODELS below. OUT (default: this folder) is where the scenes go.
Textures are scaled down to 512 x 512 (the repository stays small).
ONLY=sheen_chair rebuilds one model; SAMPLES sets Cycles' samples.
"""

import math
import os
import sys

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLES = int(os.environ.get("SAMPLES", "4096"))
OUT = os.environ.get("OUT", HERE)

# name -> (file under SAMPLE_MODELS_DIR, view azimuth and elevation in
# degrees (for a model without a camera of its own), width and height in
# pixels, whether it has glass).
MODELS = {
    "clearcoat_test": ("ClearCoatTest/glTF-Binary/ClearCoatTest.glb", 0.0, 10.0, 192, 320, False),
    "sheen_chair": ("SheenChair/glTF/SheenChair.gltf", 30.0, 20.0, 240, 200, False),
    "transmission_test": ("TransmissionTest/glTF/TransmissionTest.gltf", 0.0, 25.0, 320, 240, True),
    "glass_vase_flowers": ("GlassVaseFlowers/glTF/GlassVaseFlowers.gltf", 0.0, 10.0, 240, 320, True),
    "toy_car": ("ToyCar/glTF/ToyCar.gltf", 30.0, 20.0, 320, 240, True),
}


def light_paths(cycles, glass):
    """Direct light only, as lightcuts renders by default; with glass, the
    camera paths also follow what lightcuts' default mode follows
    (docs/design.md §5.8): up to 4 reflections, 12 transmissions, 16
    alpha-blended layers, and no diffuse bounce (so no caustic)."""
    if not glass:
        cycles.max_bounces = 0
        return
    cycles.max_bounces = 32
    cycles.diffuse_bounces = 0
    cycles.glossy_bounces = 4
    cycles.transmission_bounces = 12
    cycles.transparent_max_bounces = 16
    cycles.volume_bounces = 0
    cycles.caustics_reflective = False
    cycles.caustics_refractive = False


def prepare_materials():
    for material in bpy.data.materials:
        if material.use_nodes:
            for node in material.node_tree.nodes:
                if node.type == "BSDF_PRINCIPLED":
                    node.distribution = "GGX"
    for image in bpy.data.images:
        if image.size[0] > 512:
            image.scale(512, 512)


def bounds():
    lo, hi = Vector((1e9,) * 3), Vector((-1e9,) * 3)
    for obj in bpy.data.objects:
        if obj.type != "MESH":
            continue
        for corner in obj.bound_box:
            p = obj.matrix_world @ Vector(corner)
            lo = Vector(map(min, lo, p))
            hi = Vector(map(max, hi, p))
    return lo, hi


def world():
    w = bpy.data.worlds.new("courtyard")
    w.use_nodes = True
    nodes, links = w.node_tree.nodes, w.node_tree.links
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(os.path.join(HERE, "courtyard.exr"))
    texture.interpolation = "Closest"
    coordinates = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(-90.0))
    links.new(coordinates.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 1.0
    return w


def own_camera():
    """The model's own camera (its author's framing; the first by name of
    several, the others removed so that the export has that one alone),
    if it has one."""
    cameras = sorted((obj for obj in bpy.data.objects if obj.type == "CAMERA"), key=lambda c: c.name)
    for other in cameras[1:]:
        bpy.data.objects.remove(other)
    return cameras[0] if cameras else None


def frame(azimuth, elevation):
    """A camera of 30 degrees vertically that frames the model's bounds
    from `azimuth` and `elevation` (degrees)."""
    lo, hi = bounds()
    centre, radius = (lo + hi) / 2, (hi - lo).length / 2
    a, e = math.radians(azimuth), math.radians(elevation)
    direction = Vector((math.sin(a) * math.cos(e), -math.cos(a) * math.cos(e), math.sin(e)))
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.angle_y = math.radians(30.0)
    camera.data.sensor_fit = "VERTICAL"
    camera.location = centre + direction * (radius / math.sin(math.radians(15.0)))
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(camera)
    return camera


def build(name, path, azimuth, elevation, width, height, glass):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    prepare_materials()
    scene = bpy.context.scene
    scene.camera = own_camera() or frame(azimuth, elevation)
    scene.world = world()
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    light_paths(scene.cycles, glass)
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    out = os.path.join(OUT, name)
    os.makedirs(out, exist_ok=True)
    bpy.ops.export_scene.gltf(
        filepath=os.path.join(out, f"{name}.gltf"),
        export_format="GLTF_SEPARATE",
        export_cameras=True,
        export_lights=False,
        export_yup=True,
    )
    scene.render.filepath = os.path.join(out, f"cycles_{SAMPLES}.exr")
    bpy.ops.render.render(write_still=True)


def main():
    root = sys.argv[-1]
    only = os.environ.get("ONLY")
    for name, (path, *view) in MODELS.items():
        if not only or name == only:
            build(name, os.path.join(root, path), *view)


main()
