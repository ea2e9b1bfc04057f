#!/usr/bin/env python3
"""Writes one texture per format the renderer reads, each the same 16 x 16
picture: four 8 x 8 quadrants of known colour (the 8-bit values below; their
16-bit and float counterparts in the files that hold those).

    pip install Pillow numpy OpenEXR tifffile
    python3 scenes/textures/make_textures.py

The files are written by Pillow (PNG, JPEG, TGA, BMP, TIFF), by OpenEXR's own
Python binding (OpenEXR), by tifffile (float TIFF), and by hand for Radiance HDR (its uncompressed
scanlines, as Greg Ward's format allows), so that none of them comes from
the renderer's own readers. src/scene/image.rs's tests decode each and
compare the quadrants with these values; tests/textures.rs renders with them.
"""

import os

import numpy as np
import OpenEXR
import tifffile
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))

# Top-left, top-right, bottom-left, bottom-right: (R, G, B, A), 8 bit.
QUADRANTS = [(200, 30, 30, 255), (30, 200, 30, 128), (30, 30, 200, 64), (255, 255, 255, 0)]
# The float files' linear values (an HDR one above 1).
LINEAR = [(0.5, 0.1, 0.1), (0.1, 0.5, 0.1), (0.1, 0.1, 0.5), (4.0, 2.0, 1.0)]


def picture(values):
    """A 16 x 16 x channels array of the four quadrants' values."""
    a = np.zeros((16, 16, len(values[0])), dtype=np.asarray(values).dtype)
    for k, v in enumerate(values):
        y, x = divmod(k, 2)
        a[8 * y : 8 * y + 8, 8 * x : 8 * x + 8] = v
    return a


def path(name):
    return os.path.join(HERE, name)


def main():
    rgba = picture(QUADRANTS).astype(np.uint8)
    rgb = Image.fromarray(np.ascontiguousarray(rgba[:, :, :3]))
    Image.fromarray(rgba).save(path("rgba8.png"))
    # 16 bit: v * 257, so that v / 255 is exact. Pillow writes 16-bit PNG
    # only as grey ("I;16"): the grey file holds the red channel.
    grey16 = (rgba[:, :, 0].astype(np.uint16) * 257)
    Image.fromarray(grey16).save(path("grey16.png"))
    Image.fromarray(grey16).save(path("grey16.tif"))
    rgb.convert("P", palette=Image.Palette.ADAPTIVE, colors=4).save(path("palette.png"))
    rgb.save(path("baseline.jpg"), quality=100, subsampling=0)
    rgb.save(path("progressive.jpg"), quality=100, subsampling=0, progressive=True)
    # Pillow's CMYK is C = 255 - R, M = 255 - G, Y = 255 - B, K = 0; it
    # writes the Adobe marker (inverted CMYK), as Photoshop does.
    rgb.convert("CMYK").save(path("cmyk.jpg"), quality=100, subsampling=0)
    Image.fromarray(rgba).save(path("rgba8.tga"), compression="tga_rle")
    rgb.save(path("rgb8.bmp"))
    rgb.save(path("rgb8.tif"))
    # Float TIFF, RGB: by tifffile (Pillow writes float TIFF as grey only).
    linear = picture(LINEAR).astype(np.float32)
    tifffile.imwrite(path("float32.tif"), linear, photometric="rgb")
    for name, kind in [("half.exr", OpenEXR.HALF), ("float.exr", OpenEXR.FLOAT)]:
        channels = {c: linear[:, :, k].astype(np.float16 if kind == OpenEXR.HALF else np.float32) for k, c in enumerate("RGB")}
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        with OpenEXR.File(header, channels) as f:
            f.write(path(name))
    write_hdr(path("radiance.hdr"), linear)


def write_hdr(name, linear):
    """A Radiance HDR of `linear`, RGBE per texel, uncompressed scanlines."""
    height, width, _ = linear.shape
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
    out += f"-Y {height} +X {width}\n".encode()
    for row in linear:
        for r, g, b in row:
            m = max(r, g, b)
            if m < 1e-32:
                out += bytes(4)
                continue
            mantissa, exponent = np.frexp(m)
            scale = mantissa * 256.0 / m
            out += bytes([int(r * scale), int(g * scale), int(b * scale), int(exponent + 128)])
    with open(name, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    main()
