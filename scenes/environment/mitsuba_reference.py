"""Mitsuba 3's reference for spheres.toml: its path tracer with max_depth 2
(direct light only, as lightcuts computes), 16,384 samples per pixel, a box
filter, the same camera, spheres, floor and environment.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/environment/mitsuba_reference.py llvm_ad_rgb 16384 mitsuba-16384.exr

(Debian 12's libLLVM 15 crashes Dr.Jit's llvm backend; `apt-get install
libllvm19` gives one that works. `scalar_rgb` needs no LLVM and is slower.)

How the two scenes correspond:
- The environment and the camera: mitsuba_courtyard.py.
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
import sys

import mitsuba as mi

import mitsuba_courtyard as courtyard

variant, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
mi.set_variant(variant)
T = mi.ScalarTransform4f


def metal(roughness):
    return {'type': 'roughconductor', 'material': 'none', 'distribution': 'ggx',
            'alpha': roughness * roughness, 'sample_visible': True,
            'specular_reflectance': {'type': 'rgb', 'value': [1, 1, 1]}}


courtyard.render(mi, {
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': 2},
    'sensor': courtyard.sensor(mi, spp),
    'environment': courtyard.environment(mi),
    'floor': {'type': 'rectangle', 'to_world': T().rotate([1, 0, 0], -90).scale([6, 6, 1]),
              'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0.5, 0.5, 0.5]}}},
    'rough_010': {'type': 'sphere', 'center': [-1.25, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.1)},
    'rough_025': {'type': 'sphere', 'center': [0, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.25)},
    'rough_045': {'type': 'sphere', 'center': [1.25, 0.55, 0], 'radius': 0.55, 'bsdf': metal(0.45)},
}, variant, spp, out)
