#!/usr/bin/env python3
"""The bounded mode's texture aliasing on scenes/checker.toml, before and
after MIP maps (docs/notebook/measurements.md, "MIP maps"): renders the scene at
1 spp with `--texture-filter off` (each hit reads the image) and with the
default MIP filter, and a 256-spp reference reading the image (each
pixel's own average of the checks), then prints each one's relative RMSE
of luminance against the reference over the far floor (rows 168 to 220,
where checks are a pixel or less), the near floor (rows 220 to 360) and
the whole frame, with the render times.

    python3 ci/mip-aliasing.py target/release/lightcuts OUTDIR
"""
import json
import os
import subprocess
import sys
import time

import numpy as np
import OpenEXR


def luminance(path):
    rgba = OpenEXR.File(path).parts[0].channels["RGBA"].pixels.astype(np.float64)
    return 0.2126 * rgba[..., 0] + 0.7152 * rgba[..., 1] + 0.0722 * rgba[..., 2]


def main():
    binary, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    scene = os.path.join(os.path.dirname(__file__), "..", "scenes", "checker.toml")
    runs = {
        "reference (off, 256 spp)": ["--texture-filter", "off", "--spp", "256"],
        "off, 1 spp": ["--texture-filter", "off", "--spp", "1"],
        "mip, 1 spp": ["--spp", "1"],
    }
    images, seconds = {}, {}
    for name, flags in runs.items():
        path = os.path.join(out, name.split(",")[0].split(" ")[0] + flags[-1] + ".exr")
        start = time.monotonic()
        subprocess.run([binary, "render", scene, "--bounded", "-o", path, "--quiet", *flags], check=True,
                       stdout=subprocess.DEVNULL)
        seconds[name] = time.monotonic() - start
        images[name] = luminance(path)
    reference = images.pop("reference (off, 256 spp)")
    bands = {"far floor (rows 168-220)": (168, 220), "near floor (rows 220-360)": (220, 360), "frame": (0, 360)}
    figures = {}
    for name, image in images.items():
        figures[name] = {"seconds": round(seconds[name], 3)}
        for band, (a, b) in bands.items():
            r, t = reference[a:b], image[a:b]
            figures[name][band] = round(float(np.sqrt(np.mean((t - r) ** 2)) / r.mean()), 4)
    print(json.dumps(figures, indent=2))


if __name__ == "__main__":
    main()
