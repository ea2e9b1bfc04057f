#!/usr/bin/env python3
"""Mitsuba 3 renders a lightcuts TOML scene of point lights over quads,
boxes and spheres of Lambertian materials: the twin that ci/benchmarks.py
writes of grid10k (ci/pbrt-v4-peer.py's `write_lambertian_twin`, its Phong
lobes dropped). Direct light only: Mitsuba's `path` integrator at
max_depth 2, which picks one emitter a sample uniformly (Mitsuba has no
light tree) and traces one shadow ray, plus one BSDF sample (MIS).

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 ci/mitsuba-point-lights.py TWIN.toml SPP OUT.exr [WIDTHxHEIGHT] [SEED]

How the two scenes correspond:
- A point light of intensity I (W/sr) is Mitsuba's `point` of `intensity`
  I; a grid's lights sit at its cells' centres, as lightcuts places them.
- A quad (corner, u, v) is Mitsuba's `rectangle` ([-1, 1]^2 of its xy
  plane) mapped by u / 2, v / 2 and the unit u x v about its centre; a
  box is a `cube` ([-1, 1]^3) scaled to its half extents; a sphere is
  analytic here and a tessellated mesh in lightcuts.
- Every surface is `twosided` Lambertian of the material's albedo, as
  lightcuts shades both sides. The camera and a one-pixel box filter as
  ci/pbrt-v4-peer.py writes them for pbrt-v4.
"""

import importlib.util
import os
import sys
import time
import tomllib

import mitsuba as mi
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
PASS_SPP = 65536
spec = importlib.util.spec_from_file_location('pbrt_v4_peer', os.path.join(HERE, 'pbrt-v4-peer.py'))
peer = importlib.util.module_from_spec(spec)
spec.loader.exec_module(peer)


def scene_dict(scene, spp, width, height):
    T = mi.ScalarTransform4f
    camera = scene['camera']
    result = {
        'type': 'scene',
        'integrator': {'type': 'path', 'max_depth': 2},
        'sensor': {'type': 'perspective', 'fov': camera.get('fov_y', 45.0), 'fov_axis': 'y',
                   'to_world': T().look_at(origin=camera['eye'], target=camera['look_at'],
                                           up=camera.get('up', [0, 1, 0])),
                   'sampler': {'type': 'independent', 'sample_count': spp},
                   'film': {'type': 'hdrfilm', 'width': width, 'height': height,
                            'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    }
    materials = scene.get('materials', {})
    for k, shape in enumerate(scene.get('shapes', [])):
        bsdf = {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': {
            'type': 'rgb', 'value': materials[shape['material']]['albedo']}}}
        kind = shape['type']
        if kind == 'sphere':
            entry = {'type': 'sphere', 'center': shape['center'], 'radius': shape['radius']}
        elif kind == 'quad':
            corner, u, v = (np.array(shape[key], float) for key in ('corner', 'u', 'v'))
            normal = np.cross(u, v)
            matrix = np.eye(4)
            matrix[:3, 0], matrix[:3, 1] = u / 2, v / 2
            matrix[:3, 2] = normal / np.linalg.norm(normal)
            matrix[:3, 3] = corner + (u + v) / 2
            entry = {'type': 'rectangle', 'to_world': T(matrix)}
        elif kind == 'box':
            lo, hi = np.array(shape['min'], float), np.array(shape['max'], float)
            entry = {'type': 'cube', 'to_world': T().translate((lo + hi) / 2).scale((hi - lo) / 2)}
        else:
            sys.exit(f'mitsuba-point-lights: a {kind!r} shape has no twin here (quads, boxes and spheres only)')
        entry['bsdf'] = bsdf
        result[f'shape_{k}'] = entry
    for k, (position, intensity) in enumerate(peer.point_lights(scene)):
        result[f'light_{k}'] = {'type': 'point', 'position': [float(x) for x in position],
                                'intensity': {'type': 'rgb', 'value': intensity}}
    return result


def main():
    twin, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    width, height = map(int, (sys.argv[4] if len(sys.argv) > 4 else '160x120').split('x'))
    seed = int(sys.argv[5]) if len(sys.argv) > 5 else 0
    mi.set_variant('llvm_ad_rgb')
    # One pass holds at most 2^32 samples in Dr.Jit's llvm variant: more
    # samples are passes of PASS_SPP with seeds seed, seed + 1, ...,
    # averaged.
    passes = max(1, -(-spp // PASS_SPP))
    per_pass = spp // passes
    scene = mi.load_dict(scene_dict(tomllib.load(open(twin, 'rb')), per_pass, width, height))
    start = time.time()
    total = None
    for k in range(passes):
        image = np.array(mi.render(scene, seed=seed + k), dtype=np.float64)
        total = image if total is None else total + image
    mi.Bitmap((total / passes).astype(np.float32)).write(out)
    print(f'{passes * per_pass} spp: {time.time() - start:.2f} s')


if __name__ == '__main__':
    main()
