"""Builds scenes/environment/water_bottle/ and Cycles' reference of it with
Blender (the `bpy` module, Blender 5.0.1): the Khronos Water Bottle as
scenes/khronos/make.py exported it (CC0; its camera kept, its lights
removed), lit only by Blender's courtyard HDRI (courtyard.exr here, CC0),
exported again by Blender's glTF exporter; Cycles renders it with direct
light only (max_bounces 0), a box filter one pixel wide, no denoising.

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/environment/make_cycles.py

The environment's orientation: Cycles reads an equirectangular map at u =
0.5 - atan2(y, x) / 2pi of a Blender direction (Z up), which for the glTF
direction (X, Y, Z) = (x, z, -y) is 0.5 + atan2(Z, X) / 2pi; lightcuts reads
u = 0.5 + atan2(X, -Z) / 2pi (docs/scene-format.md), a quarter turn apart.
The world's Mapping node turns the lookup by -90 degrees about Z so that
both see the same map the same way (the background of the two renders is
compared by the test).
"""

import math
import os

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLES = int(os.environ.get("SAMPLES", "4096"))
ROTATION = float(os.environ.get("ROTATION", "-90"))
OUT = os.environ.get("OUT", os.path.join(HERE, "water_bottle"))


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.join(HERE, "..", "khronos", "water_bottle", "water_bottle.gltf"))
    for obj in list(bpy.data.objects):
        if obj.type == "LIGHT":
            bpy.data.objects.remove(obj)
    for material in bpy.data.materials:
        if material.use_nodes:
            for node in material.node_tree.nodes:
                if node.type == "BSDF_PRINCIPLED":
                    # glTF's BRDF has no multiple scattering.
                    node.distribution = "GGX"
    scene = bpy.context.scene
    scene.camera = next(obj for obj in bpy.data.objects if obj.type == "CAMERA")
    world = bpy.data.worlds.new("courtyard")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    texture = nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(os.path.join(HERE, "courtyard.exr"))
    texture.interpolation = "Closest"
    coordinates = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(ROTATION))
    links.new(coordinates.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 1.0
    scene.world = world
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
    scene.render.resolution_x = 160
    scene.render.resolution_y = 160
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    os.makedirs(OUT, exist_ok=True)
    bpy.ops.export_scene.gltf(
        filepath=os.path.join(OUT, "water_bottle.gltf"),
        export_format="GLTF_SEPARATE",
        export_cameras=True,
        export_lights=False,
    )
    scene.render.filepath = os.path.join(OUT, f"cycles_{SAMPLES}.exr")
    bpy.ops.render.render(write_still=True)


main()
