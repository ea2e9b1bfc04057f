"""Mitsuba 3's reference for spheres.toml: its path tracer with max_depth 2
(direct light only, as lightcuts computes), 16,384 samples per pixel, a box
filter, the same camera, spheres, floor and environment.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/environment/mitsuba_reference.py llvm_ad_rgb 16384 mitsuba-16384.exr

(Debian 12's libLLVM 15 crashes Dr.Jit's llvm backend; `apt-get install
libllvm19` gives one that works. `scalar_rgb` needs no LLVM and is slower.)

How the two scenes correspond:
- The environment: Mitsuba's lat-long map has u = atan2(x, -z) / 2pi, ours
  0.5 + that (docs/scene-format.md), so its copy is the map turned by half
  its width. Mitsuba interpolates the map bilinearly and lightcuts takes the
  nearest pixel, so its copy is also each pixel repeated 8 x 8: bilinear
  between equal pixels is the nearest one except in a band of 1/8 pixel.
- The metals: glTF's metal of base colour 1 has Fresnel 1 at every angle,
  as Mitsuba's roughconductor with material "none" and reflectance 1;
  both GGX with alpha = roughness^2, sampled by visible normals. Mitsuba's
  masking is the separable Smith G1(wi) G1(wo), glTF's the height-correlated
  form: they differ by well under 1% at these roughnesses except at grazing.
- The floor: Lambert, albedo 0.5, in both (a Phong material with no
  specular in the TOML).
- The spheres are analytic here and 256-segment meshes with smooth normals
  in the TOML.
"""
import os
import sys
import time

import mitsuba as mi
import numpy as np

variant, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
mi.set_variant(variant)
here = os.path.dirname(os.path.abspath(__file__))
ours = np.array(mi.Bitmap(os.path.join(here, 'courtyard.exr')), dtype=np.float32)
theirs = np.roll(ours, -ours.shape[1] // 2, axis=1).repeat(8, axis=0).repeat(8, axis=1)

T = mi.ScalarTransform4f


def metal(roughness):
    return {'type': 'roughconductor', 'material': 'none', 'distribution': 'ggx',
            'alpha': roughness * roughness, 'sample_visible': True,
            'specular_reflectance': {'type': 'rgb', 'value': [1, 1, 1]}}


scene = mi.load_dict({
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': 2},
    'sensor': {'type': 'perspective', 'fov': 30, 'fov_axis': 'y',
               'to_world': T().look_at(origin=[0, 1.2, 5], target=[0, 0.6, 0], up=[0, 1, 0]),
               'sampler': {'type': 'independent', 'sample_count': spp},
               'film': {'type': 'hdrfilm', 'width': 160, 'height': 120,
                        'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    'environment': {'type': 'envmap', 'bitmap': mi.Bitmap(theirs)},
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
