"""Mitsuba 3's reference for cornell.toml with the path method: its path
tracer at max_depth D + 1 (Mitsuba counts the segment to the light as a
depth, so its 3 is this renderer's max_depth 2: direct light and one
bounce), a box filter, the same camera, walls, blocks and light.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/cornell/mitsuba_reference.py llvm_ad_rgb 3 16384 mitsuba-depth3.exr

How the two scenes correspond:
- The walls and blocks: the same OBJ files, Lambertian (Mitsuba's
  `diffuse`), made two-sided as this renderer's surfaces are.
- The light: Mitsuba's `rectangle` spans [-1, 1]^2 of its local xy plane
  and emits towards its local +z; its to_world maps x to u / 2, y to v / 2
  and z to the unit u x v about the centre, so it covers the TOML's
  parallelogram and emits downwards. It reflects nothing.
- Not matched: cornell.toml's `distance_clamp` of 2 cm (1/d^2 is held at
  its value at 2 cm); no shading point here is that close to a light of
  any power.
"""
import os
import sys
import time

import mitsuba as mi
import numpy as np

variant, depth, spp, out = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
width = int(sys.argv[5]) if len(sys.argv) > 5 else 64
mi.set_variant(variant)
here = os.path.dirname(os.path.abspath(__file__))

T = mi.ScalarTransform4f
corner = np.array([0.343, 0.5487, 0.227])
u = np.array([0.0, 0.0, 0.105])
v = np.array([-0.130, 0.0, 0.0])
normal = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
frame = np.identity(4)
frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = u / 2, v / 2, normal, corner + (u + v) / 2


def lambert(rgb):
    return {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': rgb}}}


scene = mi.load_dict({
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': depth},
    'sensor': {'type': 'perspective', 'fov': 39.3, 'fov_axis': 'y',
               'to_world': T().look_at(origin=[0.278, 0.273, -0.800], target=[0.278, 0.273, 0.0], up=[0, 1, 0]),
               'sampler': {'type': 'independent', 'sample_count': spp},
               'film': {'type': 'hdrfilm', 'width': width, 'height': width,
                        'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    'white': {'type': 'obj', 'filename': os.path.join(here, 'cornell_white.obj'), 'bsdf': lambert([0.73, 0.73, 0.73])},
    'red': {'type': 'obj', 'filename': os.path.join(here, 'cornell_red.obj'), 'bsdf': lambert([0.63, 0.065, 0.05])},
    'green': {'type': 'obj', 'filename': os.path.join(here, 'cornell_green.obj'), 'bsdf': lambert([0.14, 0.45, 0.091])},
    'light': {'type': 'rectangle', 'to_world': T(frame.tolist()),
              'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}},
              'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': [17, 12, 4]}}},
})
start = time.time()
image = mi.render(scene)
mi.Bitmap(image).write(out)
print(f'{variant}, max_depth {depth}, {spp} spp: {time.time() - start:.2f} s')
