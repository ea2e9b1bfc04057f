#!/usr/bin/env python3
"""pbrt-v4 as the peer on many point lights: build it, render the same scene
in both renderers, print time to equal error.

Usage:
    cargo build --release
    python3 ci/pbrt-v4-peer.py PBRT_SRC [--build DIR] [--out DIR]
        [--scene scenes/grid10k.toml | --scene scattered]
        [--pbrt-spp 16,64,256,1024] [--ours 'SETTING;SETTING...']
        [--threads 2] [--skip-build | --build-only]

PBRT_SRC is pbrt-v4's source tree with its submodules (`git clone
--recursive https://github.com/mmp/pbrt-v4`). Not part of .ci/run: CI has no
pbrt-v4 sources. Needs, beyond what ci/setup.sh installs: cmake and
libopenexr-dev (`apt-get install cmake libopenexr-dev`) to build pbrt-v4,
and numpy (`pip install numpy`) for the error measure.
docs/notebook/measurements.md, "Against pbrt-v4 on many point lights", says what it
measured and how to read it.

What it does:
1. Builds pbrt-v4 (CPU only, Release) into --build, unless --skip-build.
   pbrt-v4's two generated sample tables (`bluenoise.cpp`, `pmj02tables.cpp`,
   each tens of megabytes) are absent from some snapshots of its repository:
   when one is, it is written as a zero table of the declared size and the
   `pmj02bn` sampler, the only one that reads them, is made to refuse to
   run. The default `zsobol` sampler, used here, never reads them.
   OpenEXR comes from the system (Debian's libopenexr-dev), as pbrt's CMake
   prefers.
2. Writes the scene twice, in this renderer's TOML and in pbrt-v4's format:
   the TOML scene's point lights (a `grid`, or `point` lights), its quads,
   boxes and spheres, and its camera. Materials are Lambertian of the
   scene's albedo (pbrt-v4 has no normalised Phong lobe, so the twin of a
   scene with `specular` drops it in both renderers alike). Direct light
   only: pbrt-v4's `path` integrator with `maxdepth 1` (one light sample
   and one BSDF sample at the first hit, combined by MIS) and its BVH light
   sampler (its default).
3. Renders a reference (this renderer's `--exact`: every light, one shadow
   ray each, at 16 samples per pixel, seed 1 where the renders under test
   use seed 0, so that no render shares its camera samples), then each setting of each renderer,
   timing whole processes (pbrt-v4's time includes parsing its 10,000 light
   statements; ours includes loading and the tree build), each the median
   of --repeat runs (default 1).
4. Measures each image's mean relative error in luminance on smooth pixels
   (those whose 3x3 neighbourhood in the reference varies by at most 5%:
   no silhouette, no hard shadow edge, where neither renderer's pixel
   sampling decides the error) against the reference, and prints, per
   renderer, the time its best setting needs for --target (default 1%)
   mean error: interpolated in log-log between the measured settings that
   bracket it, or extrapolated from the nearest one as error ~ 1/sqrt(time)
   (an unbiased estimator's rate) when none does.

pbrt-v4 is spectral (4 wavelengths a sample) and draws spheres as spheres
where this renderer tessellates them; the script prints the mean luminance
of pbrt-v4's most converged image against the reference, so that a
difference between the scenes would show.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
import tomllib

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# ---------------------------------------------------------------- building


def build(src, build_dir, jobs):
    util = os.path.join(src, 'src', 'pbrt', 'util')
    tables = {
        'bluenoise.cpp': ('bluenoise.h', 'uint16_t BlueNoiseTextures[NumBlueNoiseTextures]'
                          '[BlueNoiseResolution][BlueNoiseResolution]'),
        'pmj02tables.cpp': ('pmj02tables.h', 'uint32_t pmj02bnSamples[nPMJ02bnSets][nPMJ02bnSamples][2]'),
    }
    stubbed = False
    for name, (header, declaration) in tables.items():
        path = os.path.join(util, name)
        if os.path.exists(path):
            continue
        print(f'pbrt-v4: {name} is absent from the source tree: writing a zero table '
              f'(only the pmj02bn sampler reads it; it is made to refuse to run)', file=sys.stderr)
        with open(path, 'w') as f:
            f.write(f'// Written by lightcuts ci/pbrt-v4-peer.py: the generated table was absent.\n'
                    f'#include <pbrt/util/{header}>\nnamespace pbrt {{\n'
                    f'PBRT_CONST {declaration} = {{}};\n}}  // namespace pbrt\n')
        stubbed = True
    if stubbed:
        samplers = os.path.join(src, 'src', 'pbrt', 'samplers.cpp')
        text = open(samplers).read()
        marker = 'PMJ02BNSampler *PMJ02BNSampler::Create(const ParameterDictionary &parameters,\n' \
                 '                                       const FileLoc *loc, Allocator alloc) {\n'
        refusal = '    ErrorExit(loc, "pmj02bn: this build has no PMJ02BN tables (see ci/pbrt-v4-peer.py)");\n'
        if marker in text and refusal not in text:
            open(samplers, 'w').write(text.replace(marker, marker + refusal))
        elif refusal not in text:
            sys.exit('pbrt-v4: could not find PMJ02BNSampler::Create to make it refuse to run')
    subprocess.run(['cmake', '-S', src, '-B', build_dir, '-DCMAKE_BUILD_TYPE=Release',
                    '-DCMAKE_DISABLE_FIND_PACKAGE_Git=TRUE', '-DGLFW_BUILD_X11=OFF',
                    '-DGLFW_BUILD_WAYLAND=OFF', '-DBUILD_TESTING=OFF'], check=True)
    subprocess.run(['make', '-C', build_dir, f'-j{jobs}', 'pbrt_exe'], check=True)


# ----------------------------------------------------------------- scenes


def point_lights(scene):
    """Every point light of the scene, as (position, intensity W/sr)."""
    lights = []
    for light in scene.get('lights', []):
        kind = light.get('type', 'point')
        if kind == 'grid':
            corner, u, v = (np.array(light[k], float) for k in ('corner', 'u', 'v'))
            nu, nv = light['count']
            for j in range(nv):
                for k in range(nu):
                    # Cell centres, as the renderer places them.
                    lights.append((corner + u * (k + 0.5) / nu + v * (j + 0.5) / nv, light['intensity']))
        elif kind == 'point':
            lights.append((np.array(light['position'], float), light['intensity']))
        else:
            sys.exit(f'pbrt-v4-peer: a {kind!r} light has no twin here (point and grid lights only)')
    return lights


def quad_mesh(corner, u, v):
    corner, u, v = (np.array(x, float) for x in (corner, u, v))
    points = [corner, corner + u, corner + u + v, corner + v]
    return points, [0, 1, 2, 0, 2, 3]


def box_mesh(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    points = [np.array(p, float) for p in
              [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
               (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]]
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (0, 4, 7, 3), (1, 2, 6, 5)]
    return points, [i for a, b, c, d in faces for i in (a, b, c, a, c, d)]


def numbers(values):
    return ' '.join(f'{x:.9g}' for x in values)


def write_pbrt(scene, path, width, height, spp, image):
    camera = scene['camera']
    materials = scene.get('materials', {})
    lines = [
        '# Written by lightcuts ci/pbrt-v4-peer.py from a lightcuts scene.',
        # pbrt's camera space is left-handed: mirror x so that world +x is
        # on the image's right, as in a right-handed renderer.
        'Scale -1 1 1',
        f'LookAt {numbers(camera["eye"])}  {numbers(camera["look_at"])}  {numbers(camera.get("up", [0, 1, 0]))}',
        # The field of view of the shorter axis: the vertical one here.
        f'Camera "perspective" "float fov" [ {camera.get("fov_y", 45.0)} ]',
        f'Sampler "zsobol" "integer pixelsamples" [ {spp} ]',
        'Integrator "path" "integer maxdepth" [ 1 ] "string lightsampler" "bvh"',
        f'Film "rgb" "integer xresolution" [ {width} ] "integer yresolution" [ {height} ] '
        f'"string filename" "{image}" "bool savefp16" [ false ]',
        'PixelFilter "box" "float xradius" [ 0.5 ] "float yradius" [ 0.5 ]',
        'WorldBegin',
    ]
    for position, intensity in point_lights(scene):
        lines.append(f'LightSource "point" "rgb I" [ {numbers(intensity)} ] "point3 from" [ {numbers(position)} ]')
    for shape in scene.get('shapes', []):
        albedo = materials[shape['material']]['albedo']
        lines.append('AttributeBegin')
        lines.append(f'Material "diffuse" "rgb reflectance" [ {numbers(albedo)} ]')
        kind = shape['type']
        if kind == 'sphere':
            lines.append(f'Translate {numbers(shape["center"])}')
            lines.append(f'Shape "sphere" "float radius" [ {shape["radius"]} ]')
        elif kind in ('quad', 'box'):
            points, indices = (quad_mesh(shape['corner'], shape['u'], shape['v']) if kind == 'quad'
                               else box_mesh(shape['min'], shape['max']))
            lines.append(f'Shape "trianglemesh" "point3 P" [ {numbers(np.concatenate(points))} ] '
                         f'"integer indices" [ {" ".join(map(str, indices))} ]')
        else:
            sys.exit(f'pbrt-v4-peer: a {kind!r} shape has no twin here (quads, boxes and spheres only)')
        lines.append('AttributeEnd')
    with open(path, 'w') as f:
        f.write('\n'.join(lines) + '\n')


def write_lambertian_twin(toml_path, out_path):
    """The TOML scene with its Phong lobes dropped (`specular`, `exponent`),
    everything else as written."""
    kept = [line for line in open(toml_path)
            if not re.match(r'\s*(specular|exponent)\s*=', line)]
    with open(out_path, 'w') as f:
        f.write('# Written by ci/pbrt-v4-peer.py: ' + os.path.relpath(toml_path, ROOT)
                + ' with its specular lobes dropped (pbrt-v4 has no normalised Phong).\n')
        f.writelines(kept)
    # A relative mesh or texture path would now be read from out_path's
    # directory: refuse scenes that name files.
    scene = tomllib.load(open(out_path, 'rb'))
    if any('file' in s for s in scene.get('shapes', [])) or 'gltf' in scene or 'usd' in scene:
        sys.exit('pbrt-v4-peer: scenes that read other files are not written here')
    return scene


def write_scattered(out_path, seed=7):
    """A scene of grid10k's kind that nobody tuned to: 10,000 point lights
    scattered through a slab 2 to 5 m above a 16 x 16 m floor, their
    colours random and their intensities log-uniform over two decades
    (the same total power as grid10k's), and 25 spheres of random radii and
    albedos on a jittered 5 x 5 grid; grid10k's camera. Seeded: the same
    file every time."""
    rng = np.random.default_rng(seed)
    lines = ['# Written by ci/pbrt-v4-peer.py (write_scattered, seed %d).' % seed,
             '[film]', 'width = 640', 'height = 480', 'spp = 1', '',
             '[camera]', 'eye = [0.0, 5.5, 9.0]', 'look_at = [0.0, 0.5, 0.0]', 'fov_y = 45.0', '',
             '[materials.floor]', 'albedo = [0.75, 0.75, 0.75]', '']
    albedos = rng.uniform(0.1, 0.85, size=(25, 3))
    for k, albedo in enumerate(albedos):
        lines += [f'[materials.m{k}]', f'albedo = [{", ".join(f"{a:.4f}" for a in albedo)}]', '']
    lines += ['[[shapes]]', 'type = "quad"', 'corner = [-8.0, 0.0, 8.0]', 'u = [16.0, 0.0, 0.0]',
              'v = [0.0, 0.0, -16.0]', 'material = "floor"', '']
    for k in range(25):
        i, j = divmod(k, 5)
        radius = rng.uniform(0.2, 0.6)
        x = -4.0 + 2.0 * j + rng.uniform(-0.4, 0.4)
        z = -4.0 + 2.0 * i + rng.uniform(-0.4, 0.4)
        lines += ['[[shapes]]', 'type = "sphere"', f'center = [{x:.4f}, {radius:.4f}, {z:.4f}]',
                  f'radius = {radius:.4f}', f'material = "m{k}"', '']
    count = 10_000
    power = rng.uniform(0.0, 2.0, size=count)
    weights = 10.0 ** power
    # grid10k's total: 10,000 lights of 0.006 W/sr, spread over the colours.
    intensity = 0.006 * count * weights / weights.sum()
    colours = rng.uniform(0.3, 1.0, size=(count, 3))
    colours /= (colours @ np.array([0.2126, 0.7152, 0.0722]))[:, None]  # luminance 1
    positions = np.column_stack([rng.uniform(-6, 6, count), rng.uniform(2, 5, count), rng.uniform(-6, 6, count)])
    for p, c, w in zip(positions, colours, intensity):
        lines += ['[[lights]]', 'type = "point"', f'position = [{p[0]:.5f}, {p[1]:.5f}, {p[2]:.5f}]',
                  f'intensity = [{c[0] * w:.6g}, {c[1] * w:.6g}, {c[2] * w:.6g}]', '']
    with open(out_path, 'w') as f:
        f.write('\n'.join(lines))


# ------------------------------------------------------------- measuring


def luminance(path, scratch):
    """The image's luminance (Rec. 709 weights), its R, G, B read through
    oiiotool's text dump (no Python EXR reader needed)."""
    rgb_only = os.path.join(scratch, 'rgb-' + os.path.basename(path))
    subprocess.run(['oiiotool', path, '--ch', 'R,G,B', '-d', 'float', '-o', rgb_only], check=True)
    dump = subprocess.run(['oiiotool', '--dumpdata', rgb_only], check=True, capture_output=True, text=True).stdout
    pixels = {}
    for line in dump.splitlines():
        match = re.match(r'\s*Pixel \((\d+), (\d+)\): (\S+) (\S+) (\S+)$', line)
        if match:
            x, y = int(match[1]), int(match[2])
            pixels[(x, y)] = [float(match[k]) for k in (3, 4, 5)]
    width, height = max(x for x, _ in pixels) + 1, max(y for _, y in pixels) + 1
    rgb = np.array([[pixels[(x, y)] for x in range(width)] for y in range(height)])
    os.remove(rgb_only)
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def smooth_pixels(reference):
    """Pixels whose 3x3 neighbourhood in the reference varies by at most 5%."""
    padded = np.pad(reference, 1, mode='edge')
    windows = [padded[1 + dy:1 + dy + reference.shape[0], 1 + dx:1 + dx + reference.shape[1]]
               for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    lo, hi = np.min(windows, axis=0), np.max(windows, axis=0)
    return (lo > 0) & (hi <= 1.05 * lo)


def timed_with_output(command, repeat=1):
    """The whole process's wall time: the median of `repeat` runs (one
    slow or lucky run of a 0.1 s render must not decide a ratio); and the
    standard output of the last run."""
    times, stdout = [], ''
    for _ in range(repeat):
        start = time.monotonic()
        result = subprocess.run(command, capture_output=True, text=True)
        times.append(time.monotonic() - start)
        if result.returncode != 0:
            sys.exit(f'{" ".join(command)} failed:\n{result.stdout}\n{result.stderr}')
        stdout = result.stdout
    return sorted(times)[len(times) // 2], stdout


def timed(command, repeat=1):
    """timed_with_output's median wall time alone."""
    return timed_with_output(command, repeat)[0]


def time_for(points, target, unbiased):
    """The time to `target` error from (time, error) points of one
    renderer's settings of one kind: log-log between the bracketing pair; or,
    for an unbiased estimator, error ~ 1/sqrt(time) from the nearest point
    (a biased one, the bounded cut, has no such rate: None)."""
    points = sorted(points)
    for (t0, e0), (t1, e1) in zip(points, points[1:]):
        if min(e0, e1) <= target <= max(e0, e1) and e0 != e1:
            s = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0))), 'interpolated'
    if not unbiased:
        return None, 'not bracketed by the settings measured'
    t, e = min(points, key=lambda p: abs(math.log(p[1] / target)))
    return t * (e / target) ** 2, 'extrapolated as 1/sqrt(time)'


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('pbrt_src')
    parser.add_argument('--build', default='out/pbrt-v4-build')
    parser.add_argument('--out', default='out/pbrt-v4-peer')
    parser.add_argument('--scene', default='scenes/grid10k.toml',
                        help='a TOML scene, or `scattered` for write_scattered\'s')
    parser.add_argument('--resolution', default='160x120')
    parser.add_argument('--pbrt-spp', default='16,64,256,1024')
    parser.add_argument('--ours', default='--exact --spp 1;--stochastic --spp 1;--stochastic --spp 4;'
                        '--stochastic --spp 16;--bounded --spp 1;--bounded --error 0.01 --spp 1;'
                        '--bounded --error 0.005 --spp 1;--bounded --spp 16',
                        help='our settings, separated by ";"')
    parser.add_argument('--reference-spp', type=int, default=16)
    parser.add_argument('--threads', type=int, default=2)
    parser.add_argument('--target', type=float, default=0.01)
    parser.add_argument('--repeat', type=int, default=1, help='runs per setting, each timed by their median')
    parser.add_argument('--skip-build', action='store_true')
    parser.add_argument('--build-only', action='store_true')
    parser.add_argument('--lightcuts', default=os.path.join(ROOT, 'target', 'release', 'lightcuts'))
    args = parser.parse_args()
    os.chdir(ROOT)
    os.makedirs(args.out, exist_ok=True)
    if not args.skip_build:
        build(os.path.abspath(args.pbrt_src), os.path.abspath(args.build), args.threads)
    if args.build_only:
        return
    pbrt = os.path.join(args.build, 'pbrt')
    for binary, how in ((pbrt, 'build it: drop --skip-build'), (args.lightcuts, 'cargo build --release')):
        if not os.path.exists(binary):
            sys.exit(f'pbrt-v4-peer: {binary} does not exist ({how})')
    width, height = map(int, args.resolution.split('x'))

    if args.scene == 'scattered':
        generated = os.path.join(args.out, 'scattered.toml')
        write_scattered(generated)
        args.scene = generated
    name = os.path.splitext(os.path.basename(args.scene))[0]
    twin = os.path.join(args.out, f'{name}-lambertian.toml')
    scene = write_lambertian_twin(args.scene, twin)
    common = ['--resolution', args.resolution, '--threads', str(args.threads), '--quiet', '--aovs', 'none']

    reference = os.path.join(args.out, f'{name}-exact-{args.reference_spp}-seed1.exr')
    if not os.path.exists(reference):
        print(f'reference: --exact --spp {args.reference_spp} ...', file=sys.stderr)
        # Another seed than the renders under test: its camera samples are
        # not theirs, so that pixel sampling costs both renderers alike.
        timed([args.lightcuts, 'render', twin, '-o', reference, '--exact', '--spp', str(args.reference_spp),
               '--seed', '1'] + common)
    y_ref = luminance(reference, args.out)
    smooth = smooth_pixels(y_ref)

    def error(path):
        y = luminance(path, args.out)
        return float(np.mean(np.abs(y[smooth] - y_ref[smooth]) / y_ref[smooth])), float(y.mean() / y_ref.mean())

    rows = []
    for spp in map(int, args.pbrt_spp.split(',')):
        image = os.path.abspath(os.path.join(args.out, f'{name}-pbrt-{spp}.exr'))
        source = os.path.join(args.out, f'{name}-{spp}.pbrt')
        write_pbrt(scene, source, width, height, spp, image)
        seconds = timed([pbrt, '--nthreads', str(args.threads), source], args.repeat)
        rows.append(('pbrt-v4', f'path maxdepth 1, bvh, {spp} spp', seconds, *error(image)))
        print(rows[-1], file=sys.stderr)
    for setting in args.ours.split(';'):
        image = os.path.join(args.out, f'{name}-ours-{re.sub(r"[^a-z0-9]+", "", setting)}.exr')
        seconds = timed([args.lightcuts, 'render', twin, '-o', image] + setting.split() + common, args.repeat)
        rows.append(('lightcuts', setting, seconds, *error(image)))
        print(rows[-1], file=sys.stderr)

    print(f'{name} (Lambertian twin), {args.resolution}, {args.threads} threads, median of {args.repeat} runs; '
          f'reference: lightcuts '
          f'--exact --spp {args.reference_spp}; {int(smooth.sum())} smooth pixels of {smooth.size}')
    print()
    print('| renderer | setting | time (s) | mean error, smooth pixels | mean luminance / reference |')
    print('|---|---|---|---|---|')
    for renderer, setting, seconds, err, ratio in rows:
        print(f'| {renderer} | {setting} | {seconds:.2f} | {100 * err:.3f}% | {ratio:.4f} |')
    print()
    best = {}
    for renderer, setting, seconds, err, _ in rows:
        if '--exact' in setting:
            continue  # the check of pixel sampling's share, not a contender
        # One curve per renderer and mode, over its samples and thresholds.
        modes = [w for w in setting.split() if w in ('--bounded', '--stochastic', '--multidimensional')]
        kind = 'pbrt-v4' if renderer == 'pbrt-v4' else ' '.join(['lightcuts'] + (modes or ['(default mode)']))
        best.setdefault(kind, []).append((seconds, err))
    results = {}
    for kind, points in best.items():
        seconds, how = time_for(points, args.target, unbiased='--bounded' not in kind)
        if seconds is not None:
            results[kind] = seconds
        shown = 'none' if seconds is None else f'{seconds:.2f} s'
        print(f'time to {100 * args.target:g}% mean error: {kind}: {shown} ({how})')
    ours = min(v for k, v in results.items() if k.startswith('lightcuts'))
    theirs = min(v for k, v in results.items() if k.startswith('pbrt-v4'))
    print(f'best against best: pbrt-v4 / lightcuts = {theirs / ours:.1f}x')
    with open(os.path.join(args.out, f'{name}.json'), 'w') as f:
        json.dump({'rows': rows, 'time_to_target': results, 'target': args.target,
                   'smooth_pixels': int(smooth.sum())}, f, indent=1)


if __name__ == '__main__':
    main()
