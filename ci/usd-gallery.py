#!/usr/bin/env python3
"""Renders the USD Working Group's public assets (github.com/usd-wg/assets,
Apache-2.0) straight from their files and sets each render beside the
asset's own screenshot (usdview, Storm or usdrecord, committed with the
asset): the gallery in the README (docs/images/usd-wg-gallery.png).

    python3 ci/usd-gallery.py ASSETS BIN OUT.png [WORK_DIR]

ASSETS is a checkout of usd-wg/assets; BIN the lightcuts binary. The
StandardShaderBall is CC BY 4.0 (its folder's LICENCE), the rest Apache-2.0. Each
asset renders with the renderer's own framing where the stage has no
camera, lit by a grey environment and a sun (the screenshots are lit by
each viewer's own default light). Exits non-zero if any render fails.
"""
import os
import subprocess
import sys
import tempfile

from PIL import Image, ImageDraw

# (label, stage, screenshot, extra flags): the public stages that did not
# load before (texture paths, .mtlx references, primvar readers, TGA and EXR
# textures, subdivision surfaces), each with the screenshot its folder
# carries.
ASSETS = [
    ("Teapot.usd", "full_assets/Teapot/Teapot.usd", "full_assets/Teapot/screenshots/UtahTeapot.png", []),
    (
        "Creases_SpinningPyramids.usda",
        "full_assets/SubdivisionSurfaces/Creases_SpinningPyramids.usda",
        "full_assets/SubdivisionSurfaces/media/Creases_SpinningPyramids_Storm.jpg",
        ["--resolution", "426x240"],
    ),
    (
        "subdiv_catmullClark.usda",
        "test_assets/schemaTests/usdGeom/meshes/subdiv_catmullClark/subdiv_catmullClark.usda",
        "test_assets/schemaTests/usdGeom/meshes/subdiv_catmullClark/screenshots/subdiv_catmullClark_usdrecord_22.08.png",
        [],
    ),
    (
        "RoughnessTest.usdz (TGA)",
        "test_assets/RoughnessTest/RoughnessTest.usdz",
        "test_assets/RoughnessTest/screenshots/usdview-20.08.png",
        [],
    ),
    (
        "TextureFileFormatTests",
        "test_assets/TextureFileFormatTests/all_files.usda",
        "test_assets/TextureFileFormatTests/screenshots/all_files.png",
        [],
    ),
    (
        "StandardShaderBall (EXR)",
        "full_assets/StandardShaderBall/standard_shader_ball_scene.usda",
        "full_assets/StandardShaderBall/thumbnails/standard_shader_ball_scene.png",
        [],
    ),
    (
        "vehicleVariants.usda",
        "full_assets/Vehicles/USD_Mini_Car_Kit/assets/vehicles/vehicleVariants.usda",
        "full_assets/Vehicles/USD_Mini_Car_Kit/assets/vehicles/thumbnails/vehicleVariants.png",
        [],
    ),
    (
        "OpenChessSet (.mtlx skipped)",
        "full_assets/OpenChessSet/chess_set.usda",
        "full_assets/OpenChessSet/teaser.png",
        [],
    ),
]

HEIGHT = 240
WIDTH = 320
LABEL = 18


def render(binary, assets, stage, flags, work):
    out = os.path.join(work, os.path.basename(stage) + ".png")
    command = [
        binary, "render", os.path.join(assets, stage), "-o", out[:-4] + ".exr", "--png", out,
        "--environment", "0.6,0.6,0.6", "--sun", "30,45", "-q",
    ] + (flags if "--resolution" in flags else flags + ["--resolution", f"{WIDTH}x{HEIGHT}"])
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{stage}: exit {result.returncode}\n{result.stderr}")
    return Image.open(out).convert("RGB")


def fit(image):
    scale = HEIGHT / image.height
    return image.resize((max(1, round(image.width * scale)), HEIGHT), Image.LANCZOS)


def main():
    assets, binary, output = sys.argv[1], sys.argv[2], sys.argv[3]
    work = sys.argv[4] if len(sys.argv) > 4 else tempfile.mkdtemp()
    os.makedirs(work, exist_ok=True)
    pairs = []
    for label, stage, screenshot, flags in ASSETS:
        ours = fit(render(binary, assets, stage, flags, work))
        theirs = fit(Image.open(os.path.join(assets, screenshot)).convert("RGB"))
        pairs.append((label, ours, theirs))
        print(f"rendered {label}")
    row_width = max(o.width + t.width for _, o, t in pairs)
    columns = 2
    rows = (len(pairs) + columns - 1) // columns
    sheet = Image.new("RGB", (columns * (row_width + 8), rows * (HEIGHT + LABEL + 8)), "white")
    draw = ImageDraw.Draw(sheet)
    for i, (label, ours, theirs) in enumerate(pairs):
        x, y = (i % columns) * (row_width + 8), (i // columns) * (HEIGHT + LABEL + 8)
        draw.text((x + 2, y + 3), f"{label}: lightcuts | its screenshot", fill="black")
        sheet.paste(ours, (x, y + LABEL))
        sheet.paste(theirs, (x + ours.width, y + LABEL))
    sheet.save(output)
    print(f"wrote {output}")


if __name__ == "__main__":
    main()
