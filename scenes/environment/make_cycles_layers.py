"""Builds scenes/environment/clearcoat_test/ and sheen_chair/ and Cycles'
references of them with Blender (the `bpy` module, Blender 5.0.1): the
Khronos sample models ClearCoatTest (CC BY 4.0) and SheenChair (CC0), each
imported by Blender's glTF importer (KHR_materials_clearcoat becomes the
Principled BSDF's coat, KHR_materials_sheen its sheen), framed by a camera,
lit only by Blender's courtyard HDRI (courtyard.exr here, CC0, turned as
make_cycles.py explains), exported again by Blender's glTF exporter with
the camera; Cycles renders each with direct light only (max_bounces 0), a
box filter one pixel wide, no denoising, single-scattering GGX (glTF's
BRDF has none).

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/environment/make_cycles_layers.py SAMPLE_MODELS_DIR

SAMPLE_MODELS_DIR holds `ClearCoatTest/glTF-Binary/ClearCoatTest.glb` and
`SheenChair/glTF/SheenChair.gltf` of the Khronos glTF sample models.
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
# degrees, width and height in pixels).
MODELS = {
    "clearcoat_test": ("ClearCoatTest/glTF-Binary/ClearCoatTest.glb", 0.0, 10.0, 192, 320),
    "sheen_chair": ("SheenChair/glTF/SheenChair.gltf", 30.0, 20.0, 240, 200),
}


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


def build(name, path, azimuth, elevation, width, height):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    prepare_materials()
    lo, hi = bounds()
    centre, radius = (lo + hi) / 2, (hi - lo).length / 2
    scene = bpy.context.scene
    a, e = math.radians(azimuth), math.radians(elevation)
    direction = Vector((math.sin(a) * math.cos(e), -math.cos(a) * math.cos(e), math.sin(e)))
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.angle_y = math.radians(30.0)
    camera.data.sensor_fit = "VERTICAL"
    camera.location = centre + direction * (radius / math.sin(math.radians(15.0)))
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.world = world()
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
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
    for name, (path, azimuth, elevation, width, height) in MODELS.items():
        if not only or name == only:
            build(name, os.path.join(root, path), azimuth, elevation, width, height)


main()
