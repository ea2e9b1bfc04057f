"""Mitsuba 3's render of glass_peer.toml (with --rough, of
rough_glass_peer.toml): its volumetric path tracer with paths of up to 64
bounces, the same camera, spheres and environment.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/environment/glass_mitsuba.py [--rough] llvm_ad_rgb 16384 glass-mitsuba.exr \\
        [OURS.exr BESIDE.png]

With OURS.exr (lightcuts' render of glass_peer.toml), BESIDE.png shows it
on the left of Mitsuba's, both clamped to [0, 1] and sRGB-encoded.

How the two scenes correspond:
- The environment and the camera: mitsuba_courtyard.py.
- The glass: Mitsuba's `dielectric` (IOR 1.5 inside, 1 outside) uses the
  exact Fresnel equations, lightcuts glTF's Schlick form at the cosine on
  the air's side (docs/design.md §5.8): at IOR 1.5 they agree at normal
  incidence (0.04) and differ by up to about 0.01 in reflectance between
  60 and 85 degrees.
- The green sphere's inside is a homogeneous medium of no scattering and
  sigma_a = -ln(attenuation colour) / attenuation distance per channel,
  which keeps c^(d / 0.5) of the light over d metres: KHR_materials_volume's
  Beer-Lambert law.
- Rough glass: Mitsuba's `roughdielectric` with GGX of alpha = roughness^2
  (0.09 and 0.36), its visible normals drawn as lightcuts draws them
  (Walter et al. 2007's BTDF, docs/design.md §5.8), with the exact Fresnel
  equations where lightcuts has Schlick's form.
- The spheres are analytic here and 512-segment meshes with smooth normals
  in the TOML.
"""
import math
import sys

import mitsuba as mi
import numpy as np

import mitsuba_courtyard as courtyard

rough = sys.argv[1] == '--rough'
args = sys.argv[2:] if rough else sys.argv[1:]
variant, spp, out = args[0], int(args[1]), args[2]
mi.set_variant(variant)
colour, distance = [0.2, 0.8, 0.3], 0.5
sigma_a = [-math.log(c) / distance for c in colour]
# Mitsuba's RGB inputs are reflectances within [0, 1]: the density is one
# scaled by its largest channel.
scale = max(sigma_a)
glass = {'type': 'dielectric', 'int_ior': 1.5, 'ext_ior': 1.0}


def rough_glass(alpha):
    return {'type': 'roughdielectric', 'distribution': 'ggx', 'alpha': alpha, 'int_ior': 1.5, 'ext_ior': 1.0}


def spheres():
    """The two spheres of the scene asked for."""
    if rough:
        return {'frosted': {'type': 'sphere', 'center': [-0.65, 0.6, 0], 'radius': 0.55, 'bsdf': rough_glass(0.09)},
                'rougher': {'type': 'sphere', 'center': [0.65, 0.6, 0], 'radius': 0.55, 'bsdf': rough_glass(0.36)}}
    return {'clear': {'type': 'sphere', 'center': [-0.65, 0.6, 0], 'radius': 0.55, 'bsdf': glass},
            'green': {'type': 'sphere', 'center': [0.65, 0.6, 0], 'radius': 0.55, 'bsdf': glass,
                      'interior': {'type': 'homogeneous', 'albedo': 0.0, 'scale': scale,
                                   'sigma_t': {'type': 'rgb', 'value': [s / scale for s in sigma_a]}}}}


image = courtyard.render(mi, {
    'type': 'scene',
    'integrator': {'type': 'volpath', 'max_depth': 65},
    'sensor': courtyard.sensor(mi, spp),
    'environment': courtyard.environment(mi),
    **spheres(),
}, variant, spp, out)
if len(args) > 4:
    ours = np.array(mi.Bitmap(args[3]), dtype=np.float32)[:, :, :3]
    both = np.concatenate([ours, np.array(image, dtype=np.float32)], axis=1).clip(0, 1)
    mi.Bitmap(both).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True).write(args[4])
