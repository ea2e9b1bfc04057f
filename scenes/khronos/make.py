"""Builds the Khronos sample models' comparison scenes with Blender (the
`bpy` module, Blender 5.0.1): imports each model's glTF, frames it with a
camera and lights it with a key, a fill and a ring of 24 small lights (true
point lights), exports it with Blender's own glTF exporter and renders
Cycles' reference of the same scene (the .blend is not kept: this script
rebuilds it).

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/khronos/make.py SAMPLE_MODELS_DIR

SAMPLE_MODELS_DIR holds `Avocado/glTF/` and `WaterBottle/glTF/` of the
Khronos glTF sample models (both CC0 1.0; see LICENSE.md here).

What is changed on import, and why (see README.md): textures are scaled
down to 512 x 512 (the repository stays small); the Principled BSDF uses
single-scattering GGX (glTF's BRDF has no multiple scattering).
EMISSION=0 removes emission (to measure what the emissive texture adds);
ONLY=water_bottle rebuilds one model.
"""

import math
import os
import sys

import bpy
from mathutils import Vector

HERE = os.environ.get("OUT", os.path.dirname(os.path.abspath(__file__)))
# NORMAL_MAPS=0 disconnects the models' normal maps (to measure what they add).
NORMAL_MAPS = os.environ.get("NORMAL_MAPS", "1") == "1"
# EMISSION=0 removes the models' emission (to measure what it adds).
EMISSION = os.environ.get("EMISSION", "1") == "1"
SIZE = 160
SAMPLES = int(os.environ.get("SAMPLES", "4096"))

# name -> (folder under SAMPLE_MODELS_DIR, view azimuth and elevation in
# degrees, emission strength): the Water Bottle faces its emissive logo to
# the camera, eight times as bright as the file has it, so that the
# comparison sees the emissive texture (at 1 it adds 0.2% to the mean).
MODELS = {
    "avocado": ("Avocado/glTF/Avocado.gltf", 25.0, 20.0, 1.0),
    "water_bottle": ("WaterBottle/glTF/WaterBottle.gltf", 40.0, 15.0, 8.0),
}
# Built only when ONLY names them, into OUT (never into the repository):
# DamagedHelmet is CC BY-NC (docs/notebook/measurements.md, "DamagedHelmet against
# Cycles").
MEASURED_ONLY = {
    "damaged_helmet": ("DamagedHelmet/glTF/DamagedHelmet.gltf", 25.0, 20.0, 1.0),
}


def prepare_materials(emission_strength):
    for material in bpy.data.materials:
        if not material.use_nodes:
            continue
        tree = material.node_tree
        for node in tree.nodes:
            if node.type == "BSDF_PRINCIPLED":
                node.distribution = "GGX"
                node.subsurface_method = "BURLEY"
                for link in list(node.inputs["Normal"].links) if not NORMAL_MAPS else []:
                    tree.links.remove(link)
                if not EMISSION:
                    for link in list(node.inputs["Emission Color"].links):
                        tree.links.remove(link)
                    node.inputs["Emission Strength"].default_value = 0.0
                else:
                    node.inputs["Emission Strength"].default_value *= emission_strength
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


def point(name, location, watts, colour=(1.0, 1.0, 1.0)):
    data = bpy.data.lights.new(name, "POINT")
    data.energy = watts
    data.color = colour
    data.shadow_soft_size = 0.0
    data.use_soft_falloff = False
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)


def build(name, path, azimuth, elevation, emission_strength):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    prepare_materials(emission_strength)
    lo, hi = bounds()
    centre, radius = (lo + hi) / 2, (hi - lo).length / 2
    scene = bpy.context.scene
    # Blender is Z up: the glTF's +Y up is Blender's +Z.
    def around(distance, azimuth_deg, elevation_deg):
        a, e = math.radians(azimuth_deg), math.radians(elevation_deg)
        return centre + distance * Vector((math.sin(a) * math.cos(e), -math.cos(a) * math.cos(e), math.sin(e)))

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.angle_y = math.radians(30.0)
    camera.data.sensor_fit = "VERTICAL"
    camera.location = around(radius / math.sin(math.radians(15.0)) * 1.05, azimuth, elevation)
    camera.rotation_euler = (centre - camera.location).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    # Point lights: W of Blender's point lamp = 4 pi x W/sr; irradiance of
    # about 2 W/m^2 from the key at the model.
    d = 3.0 * radius
    point("key", around(d, azimuth - 40.0, 45.0), 4 * math.pi * 2.0 * d * d, (1.0, 0.95, 0.85))
    point("fill", around(d, azimuth + 70.0, 10.0), 4 * math.pi * 0.6 * d * d, (0.8, 0.9, 1.0))
    for i in range(24):
        point(f"ring{i:02}", around(1.6 * radius, i * 15.0, 60.0 if i % 2 else -20.0), 4 * math.pi * 0.02 * d * d)
    scene.world = bpy.data.worlds.new("black")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
    scene.cycles.use_light_tree = True
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.render.resolution_x = SIZE
    scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    out = os.path.join(HERE, name)
    os.makedirs(out, exist_ok=True)
    bpy.ops.export_scene.gltf(
        filepath=os.path.join(out, f"{name}.gltf"),
        export_format="GLTF_SEPARATE",
        export_cameras=True,
        export_lights=True,
        export_import_convert_lighting_mode="SPEC",
        export_yup=True,
    )
    scene.render.filepath = os.path.join(out, f"cycles_{SAMPLES}.exr")
    bpy.ops.render.render(write_still=True)


def main():
    root = sys.argv[-1]
    only = os.environ.get("ONLY")
    if only in MEASURED_ONLY and "OUT" not in os.environ:
        sys.exit(f"{only} is not for the repository: give OUT=DIR")
    for name, (path, azimuth, elevation, emission_strength) in (MODELS | MEASURED_ONLY).items():
        if (only and name != only) or (not only and name in MEASURED_ONLY):
            continue
        build(name, os.path.join(root, path), azimuth, elevation, emission_strength)


main()
