"""Exports lobby.blend as USD with Blender's own exporter (File > Export >
Universal Scene Description), as an artist would: lights, cameras and
UsdPreviewSurface materials on, its world not written as a dome light (the
lobby's references, cycles_2048.exr and the glTF export, have a black
world), textures copied beside it.

    python3 -m venv venv && venv/bin/pip install bpy==5.0.1
    venv/bin/python scenes/lobby/make_usd.py

Writes scenes/lobby/lobby.usdc and scenes/lobby/textures/checker.png.
"""

import os

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))

bpy.ops.wm.open_mainfile(filepath=os.path.join(HERE, "lobby.blend"))
bpy.ops.wm.usd_export(
    filepath=os.path.join(HERE, "lobby.usdc"),
    export_lights=True,
    export_cameras=True,
    export_materials=True,
    generate_preview_surface=True,
    generate_materialx_network=False,
    export_textures_mode="NEW",
    relative_paths=True,
    convert_world_material=False,
)
