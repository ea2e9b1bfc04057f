#!/usr/bin/env python3
"""Writes checker.png beside this script: 64 x 64 texels, 8 x 8 checks of
8 texels, light (sRGB 230) and dark (sRGB 40). scenes/checker.toml repeats
it 500 times across a floor 1 km wide, to measure texture aliasing far
from the camera (docs/notebook/measurements.md, "MIP maps").

    python3 scenes/checker/make_checker.py
"""
import os

import numpy as np
from PIL import Image

y, x = np.mgrid[0:64, 0:64]
checks = ((x // 8 + y // 8) % 2).astype(np.uint8)
grey = np.where(checks == 1, 230, 40).astype(np.uint8)
Image.fromarray(np.stack([grey] * 3, -1), "RGB").save(os.path.join(os.path.dirname(__file__), "checker.png"))
