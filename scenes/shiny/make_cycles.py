"""Cycles' reference for scenes/shiny.toml, built with Blender (the `bpy`
module, Blender 5.0.1): the same camera, floor, backdrop, spheres, 2,304
point lights, softbox and sky, direct light only (max_bounces 0), a box
filter one pixel wide, no denoising, 160x120.

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/shiny/make_cycles.py

SAMPLES (default 4096), OUT (default cycles-SAMPLES.exr here) and SEED
(default 0, the reference's: another seed gives an estimate independent
of it, as when timing Cycles at fewer samples against it) are read from
the environment.

How the two scenes correspond:
- Axes: Blender is Z up; the TOML's (x, y, z) is Blender's (x, -z, y).
- Materials: the Principled BSDF with the TOML's base colour, metallic
  and roughness, single-scattering GGX (glTF's BRDF has no multiple
  scattering), IOR 1.5 (glTF's f0 = 0.04), as Blender's glTF importer
  maps glTF's material. Cycles layers the dielectric's diffuse under its
  specular by albedo scaling where glTF weighs it by 1 - max(F): the
  dielectrics differ by that, the metals not at all.
- The point lights: Blender's point lamp of W watts has W / (4 pi) W/sr;
  radius 0, no soft falloff (true point lights).
- The softbox: a rectangle of the TOML's corners whose Emission is the
  TOML's radiance on its front (u x v) and black on its back (Cycles'
  emissive meshes emit from both sides; a TOML area light from one), and
  which reflects nothing.
- The spheres: UV spheres of 96 segments and 48 rings, smooth shaded (the
  TOML's are 96-segment meshes with smooth normals).
- The sky: a world of constant colour (0.10, 0.12, 0.16), strength 1.
"""

import math
import os

import bpy
from mathutils import Matrix, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLES = int(os.environ.get("SAMPLES", "4096"))
OUT = os.environ.get("OUT", os.path.join(HERE, f"cycles-{SAMPLES}.exr"))
SEED = int(os.environ.get("SEED", "0"))


def blender(p):
    """The TOML's (x, y, z), y up, as Blender's Z-up coordinates."""
    x, y, z = p
    return Vector((x, -z, y))


def principled(name, base, metallic, roughness):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    node = material.node_tree.nodes["Principled BSDF"]
    node.distribution = "GGX"
    node.inputs["Base Color"].default_value = (*base, 1.0)
    node.inputs["Metallic"].default_value = metallic
    node.inputs["Roughness"].default_value = roughness
    node.inputs["IOR"].default_value = 1.5
    return material


def parallelogram(name, corner, u, v, material):
    corner, u, v = blender(corner), blender(u), blender(v)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([corner, corner + u, corner + u + v, corner + v], [], [(0, 1, 2, 3)])
    obj = bpy.data.objects.new(name, mesh)
    obj.data.materials.append(material)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def sphere(name, centre, radius, material):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=radius, location=blender(centre))
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(material)


def emitter(radiance):
    """Emission of `radiance` (W/(m^2 sr)) on the front face only."""
    material = bpy.data.materials.new("softbox")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.remove(nodes["Principled BSDF"])
    emission = nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*radiance, 1.0)
    geometry = nodes.new("ShaderNodeNewGeometry")
    front = nodes.new("ShaderNodeMath")
    front.operation = "SUBTRACT"
    front.inputs[0].default_value = 1.0
    links.new(geometry.outputs["Backfacing"], front.inputs[1])
    links.new(front.outputs["Value"], emission.inputs["Strength"])
    links.new(emission.outputs["Emission"], nodes["Material Output"].inputs["Surface"])
    material.cycles.emission_sampling = "FRONT"
    return material


def point(name, location, intensity):
    """A true point light of `intensity` (W/sr, per channel)."""
    peak = max(intensity)
    data = bpy.data.lights.new(name, "POINT")
    data.energy = 4.0 * math.pi * peak
    data.color = tuple(c / peak for c in intensity)
    data.shadow_soft_size = 0.0
    data.use_soft_falloff = False
    obj = bpy.data.objects.new(name, data)
    obj.location = blender(location)
    bpy.context.scene.collection.objects.link(obj)


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    parallelogram("floor", (-8, 0, 8), (16, 0, 0), (0, 0, -16), principled("floor", (0.55, 0.55, 0.55), 0.0, 0.55))
    parallelogram("backdrop", (-8, 0, -4), (16, 0, 0), (0, 6, 0), principled("backdrop", (0.35, 0.4, 0.5), 0.0, 0.8))
    sphere("gold", (-2.4, 0.9, 0.0), 0.9, principled("gold", (1.0, 0.78, 0.34), 1.0, 0.25))
    sphere("chrome", (0.0, 1.0, -0.6), 1.0, principled("chrome", (0.55, 0.56, 0.55), 1.0, 0.08))
    sphere("copper", (2.3, 0.8, 0.2), 0.8, principled("copper", (0.95, 0.64, 0.54), 1.0, 0.45))
    sphere("plastic", (-1.0, 0.5, 1.8), 0.5, principled("plastic", (0.7, 0.08, 0.06), 0.0, 0.2))
    sphere("rubber", (1.2, 0.45, 1.9), 0.45, principled("rubber", (0.08, 0.15, 0.55), 0.0, 0.7))
    parallelogram("softbox", (-6.5, 1.0, 3.0), (0, 0, -2), (0, 2, 0), emitter((6.0, 4.8, 3.6)))
    corner, u, v, count = Vector((-5.0, 5.0, -3.0)), Vector((10.0, 0, 0)), Vector((0, 0, 8.0)), 48
    for i in range(count):
        for j in range(count):
            position = corner + (i + 0.5) / count * u + (j + 0.5) / count * v
            point(f"grid_{i}_{j}", position, (0.006, 0.0062, 0.0068))

    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.angle_y = math.radians(40.0)
    camera.data.sensor_fit = "VERTICAL"
    eye, target = blender((0.0, 3.2, 8.5)), blender((0.0, 0.8, 0.0))
    camera.location = eye
    camera.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera

    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.10, 0.12, 0.16, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    scene.world = world

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = SAMPLES
    scene.cycles.seed = SEED
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 0
    scene.cycles.use_light_tree = True
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 1.0
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.render.resolution_x = 160
    scene.render.resolution_y = 120
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = OUT
    bpy.ops.render.render(write_still=True)


main()
