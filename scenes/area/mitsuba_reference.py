"""Mitsuba 3's reference for softbox.toml: its path tracer with max_depth 2
(direct light only, as lightcuts computes), a box filter, the same camera,
spheres, floor, softbox and sky.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/area/mitsuba_reference.py llvm_ad_rgb 16384 mitsuba-16384.exr

A fourth argument sets max_depth (default 2, direct light only): 8 is
this renderer's path method at max_depth 7 (mitsuba-depth8-16384.exr).

(Debian 12's libLLVM 15 crashes Dr.Jit's llvm backend; `apt-get install
libllvm19` gives one that works. `scalar_rgb` needs no LLVM and is slower.)

How the two scenes correspond:
- The softbox: Mitsuba's `rectangle` spans [-1, 1]^2 of its local xy plane
  and emits towards its local +z; its to_world maps x to u / 2, y to v / 2
  and z to the unit u x v, about the rectangle's centre, so it covers the
  TOML's parallelogram and emits to the same side (u x v). It reflects
  nothing (black, as a TOML area light's own material).
- The metals: glTF's metal of base colour 1 has Fresnel 1 at every angle,
  as Mitsuba's roughconductor with material "none" and reflectance 1;
  both GGX with alpha = roughness^2. Mitsuba's masking is the separable
  Smith G1(wi) G1(wo), glTF's the height-correlated form: they differ by
  well under 1% at these roughnesses except at grazing.
- The floor: Lambert, albedo 0.5, in both. The sky: a constant 0.05.
- The spheres are analytic here and 256-segment meshes with smooth normals
  in the TOML.
"""
import sys
import time

import mitsuba as mi
import numpy as np

variant, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
depth = int(sys.argv[4]) if len(sys.argv) > 4 else 2
mi.set_variant(variant)

T = mi.ScalarTransform4f
corner = np.array([-2.63937, 2.624969, 1.047966])
u = np.array([1.345346, 0, 1.47988])
v = np.array([-0.466606, -1.249938, 0.424187])
normal = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
frame = np.identity(4)
frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = u / 2, v / 2, normal, corner + (u + v) / 2


def metal(roughness):
    return {'type': 'roughconductor', 'material': 'none', 'distribution': 'ggx',
            'alpha': roughness * roughness, 'sample_visible': True,
            'specular_reflectance': {'type': 'rgb', 'value': [1, 1, 1]}}


scene = mi.load_dict({
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': depth},
    'sensor': {'type': 'perspective', 'fov': 30, 'fov_axis': 'y',
               'to_world': T().look_at(origin=[0, 1.2, 5], target=[0, 0.6, 0], up=[0, 1, 0]),
               'sampler': {'type': 'independent', 'sample_count': spp},
               'film': {'type': 'hdrfilm', 'width': 160, 'height': 120,
                        'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    'sky': {'type': 'constant', 'radiance': {'type': 'rgb', 'value': [0.05, 0.05, 0.05]}},
    'softbox': {'type': 'rectangle', 'to_world': T(frame.tolist()),
                'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}},
                'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': [8, 8, 8]}}},
    'floor': {'type': 'rectangle', 'to_world': T().rotate([1, 0, 0], -90).scale([6, 6, 1]),
              'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0.5, 0.5, 0.5]}}},
    'rough_010': {'type': 'sphere', 'center': [-1.25, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.1)},
    'rough_025': {'type': 'sphere', 'center': [0, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.25)},
    'rough_045': {'type': 'sphere', 'center': [1.25, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.45)},
})
start = time.time()
image = mi.render(scene)
mi.Bitmap(image).write(out)
print(f'{variant}, {spp} spp: {time.time() - start:.2f} s')
