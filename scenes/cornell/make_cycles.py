"""Cycles' render of cornell.toml with the path method, for time to equal
error (docs/notebook/measurements.md, "Against Cycles on the Cornell box"): the
same OBJ walls and blocks, camera and light built in Blender from nothing,
Cycles on the CPU with BOUNCES bounces of every kind (Cycles counts the
bounces after the camera's hit, so its 6 is lightcuts' --max-depth 7 and
Mitsuba's max_depth 8), light tree on, adaptive sampling, denoising and
both clamps off, a box pixel filter one pixel wide, "Standard" view
transform.

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/cornell/make_cycles.py SAMPLES BOUNCES OUT.exr [WIDTH]

WIDTH defaults to 64 (a square image, as mitsuba_reference.py's).

How the two scenes correspond:
- The walls and blocks: the OBJ files read with their coordinates kept
  (Blender's up axis set to the files' y, so nothing is turned), a Diffuse
  BSDF of the TOML's albedo (Cycles' surfaces are two-sided, as ours).
- The light: a quad over the TOML's parallelogram (corner, u, v) emitting
  Emission of the TOML's radiance towards u x v (down); its back, facing
  the ceiling 0.1 mm above, is black, and it reflects nothing.
- The camera: the TOML's eye looking at look_at with +y up, a vertical
  field of view of 39.3 degrees.
- Not matched: cornell.toml's `distance_clamp` of 2 cm; no shading point
  is that close to the light.
"""

import math
import os
import sys

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
ALBEDO = {
    "white": (0.73, 0.73, 0.73),
    "red": (0.63, 0.065, 0.05),
    "green": (0.14, 0.45, 0.091),
}
CORNER = Vector((0.343, 0.5487, 0.227))
U = Vector((0.0, 0.0, 0.105))
V = Vector((-0.130, 0.0, 0.0))
RADIANCE = (17.0, 12.0, 4.0)


def diffuse(name, rgb):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*rgb, 1.0)
    out = nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return material


def light():
    corners = [CORNER, CORNER + U, CORNER + U + V, CORNER + V]
    mesh = bpy.data.meshes.new("light")
    # Wound so that its normal is u x v (down), as the TOML's area light.
    mesh.from_pydata([tuple(c) for c in corners], [], [(0, 1, 2, 3)])
    mesh.update()
    assert mesh.polygons[0].normal.dot(U.cross(V).normalized()) > 0.99
    obj = bpy.data.objects.new("light", mesh)
    bpy.context.scene.collection.objects.link(obj)
    material = bpy.data.materials.new("emitter")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    nodes.clear()
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*RADIANCE, 1.0)
    emission.inputs["Strength"].default_value = 1.0
    black = nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    out = nodes.new("ShaderNodeOutputMaterial")
    links = material.node_tree.links
    links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(emission.outputs["Emission"], mix.inputs[1])
    links.new(black.outputs["BSDF"], mix.inputs[2])
    links.new(mix.outputs["Shader"], out.inputs["Surface"])
    material.cycles.emission_sampling = "FRONT"
    obj.data.materials.append(material)


def main():
    samples, bounces, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    width = int(sys.argv[4]) if len(sys.argv) > 4 else 64
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    for name, rgb in ALBEDO.items():
        bpy.ops.wm.obj_import(
            filepath=os.path.join(HERE, f"cornell_{name}.obj"), forward_axis="Y", up_axis="Z"
        )
        material = diffuse(name, rgb)
        for obj in bpy.context.selected_objects:
            obj.data.materials.clear()
            obj.data.materials.append(material)
    light()
    camera = bpy.data.cameras.new("camera")
    camera.sensor_fit = "VERTICAL"
    camera.angle_y = math.radians(39.3)
    camera.clip_start = 1e-3
    eye, look_at = Vector((0.278, 0.273, -0.800)), Vector((0.278, 0.273, 0.0))
    obj = bpy.data.objects.new("camera", camera)
    obj.location = eye
    obj.rotation_euler = (look_at - eye).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(obj)
    scene.camera = obj
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world

    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.use_light_tree = True
    cycles.max_bounces = bounces
    cycles.diffuse_bounces = bounces
    cycles.glossy_bounces = bounces
    cycles.transmission_bounces = bounces
    cycles.transparent_max_bounces = bounces
    cycles.volume_bounces = 0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.seed = 1
    scene.render.resolution_x = width
    scene.render.resolution_y = width
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.abspath(out)
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
