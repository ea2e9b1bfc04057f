"""Renders Cycles' reference of the lobby with indirect light, for the path
method (docs/design.md §6.7): lobby.blend as committed, Cycles on the CPU
with max_bounces 7 (every kind of bounce up to 7, so the diffuse ones too:
Cycles' default diffuse_bounces of 4 is raised), which is lightcuts'
max_depth 8 (Cycles counts bounces after the camera's hit, lightcuts counts
path vertices); light tree on, adaptive sampling, denoising and both clamps
off, a box pixel filter one pixel wide, "Standard" view transform, the
resolution of lobby.toml.

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/lobby/make_cycles_indirect.py [SAMPLES] [BOUNCES] [OUT.exr] [SEED]

BOUNCES 0 is direct light only, as cycles_2048.exr; SEED (default 1) other
than a reference's gives an estimate independent of it (to time Cycles at
fewer samples against it).

Writes OUT.exr, by default scenes/lobby/cycles-bounces{BOUNCES}-{SAMPLES}.exr
(channels R, G, B, A; linear Rec. 709).
"""

import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    samples = int(sys.argv[1]) if len(sys.argv) > 1 else 2048
    bounces = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    bpy.ops.wm.open_mainfile(filepath=os.path.join(HERE, "lobby.blend"))
    scene = bpy.context.scene
    cycles = scene.cycles
    scene.render.engine = "CYCLES"
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
    cycles.caustics_reflective = True
    cycles.caustics_refractive = True
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.seed = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    scene.render.resolution_x = 160
    scene.render.resolution_y = 120
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.image_settings.exr_codec = "ZIP"
    default = os.path.join(HERE, f"cycles-bounces{bounces}-{samples}.exr")
    scene.render.filepath = os.path.abspath(sys.argv[3]) if len(sys.argv) > 3 else default
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    main()
