#!/usr/bin/env python3
"""Speed at equal error against a peer: writes docs/benchmarks.md and the
README's table between its `<!-- benchmarks -->` markers.

    cargo build --release
    apt-get install libllvm19 && pip install mitsuba numpy
    python3 ci/benchmarks.py [--rows grid10k,softbox,...] [--repeat 3] [--write]

Without --write (or with --rows naming only some rows) it prints the
tables and writes nothing. Not part of .ci/run: it takes about ten
minutes and Mitsuba 3 from PyPI.

For each row, one render of lightcuts at the scene's default method and
the samples given below, and the peer (Mitsuba 3's `path` integrator,
`llvm_ad_rgb`) at several sample counts. Every image is measured against
the peer's committed 16,384-sample render where the scene has one
(scenes/*/mitsuba*.exr, made by the scripts beside them, which say how
the two scenes correspond): lightcuts' error then counts what little the
two renderers disagree on, as well as its noise. On grid10k each renderer
is measured against its own converged render, lightcuts' exact one (every
light, one shadow ray each, 16 samples, another seed) and Mitsuba's at
262,144 samples (another seed), so that neither is charged for where the
twins differ (analytic spheres there, tessellated here). The error is the mean
relative difference of 8x8-pixel block means of luminance (`lightcuts
compare --blocks 8`): it weighs noise and bias alike and is insensitive to
where each renderer puts its pixel samples; on grid10k the blocks across
silhouettes (found from the exact render's depth) are left out, where the
16-sample reference's own antialiasing would decide the error. The peer's time at our error
is interpolated in log-log between the two sample counts that bracket it,
or extrapolated from the nearest as error ~ 1/sqrt(time). Times are whole
processes (start-up, loading, the light tree, Mitsuba's JIT compilation),
each the median of --repeat runs, both renderers on every thread.
Mitsuba's renders use its default seed, as its 16,384-sample reference
does; should they share samples with it, the peer's error would read
lower than it is (by about 13% at 4,096 samples), never ours.
"""

import argparse
import datetime
import importlib.util
import json
import math
import os
import platform
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
spec = importlib.util.spec_from_file_location('pbrt_v4_peer', os.path.join(ROOT, 'ci', 'pbrt-v4-peer.py'))
peer_tools = importlib.util.module_from_spec(spec)
spec.loader.exec_module(peer_tools)
timed, timed_with_output = peer_tools.timed, peer_tools.timed_with_output


LLVM = '/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1'
MITSUBA = 'llvm_ad_rgb'

# name: (what it shows, our arguments, the peer's command for a
# sample count and an output, the peer's sample counts, the reference).
ROWS = {
    'grid10k': ('10,000 point lights on a grid over spheres (direct light; Lambertian twin)',
                ['{twin}', '--resolution', '160x120', '--spp', '16'],
                lambda spp, out: ['ci/mitsuba-point-lights.py', '{twin}', str(spp), out, '160x120'],
                (1024, 4096, 16384, 65536), '{exact}'),
    'softbox': ('three metals under a softbox and a dim sky (direct light)',
                ['scenes/area/softbox.toml', '--spp', '64'],
                lambda spp, out: ['scenes/area/mitsuba_reference.py', MITSUBA, str(spp), out],
                (64, 256, 1024, 4096), 'scenes/area/mitsuba-16384.exr'),
    'environment': ('three metals under an HDR sky (direct light)',
                    ['scenes/environment/spheres.toml', '--spp', '64'],
                    lambda spp, out: ['scenes/environment/mitsuba_reference.py', MITSUBA, str(spp), out],
                    (64, 256, 1024, 4096), 'scenes/environment/mitsuba-16384.exr'),
    'cornell': ('the Cornell box, paths of up to 7 vertices (6 bounces)',
                ['scenes/cornell.toml', '--resolution', '64x64', '--spp', '64', '--indirect', 'path',
                 '--max-depth', '7'],
                lambda spp, out: ['scenes/cornell/mitsuba_reference.py', MITSUBA, '8', str(spp), out],
                (16, 64, 256, 1024, 4096), 'scenes/cornell/mitsuba-depth8.exr'),
    'atrium': ('a courtyard under a sky, the sun and six panels, two bounces',
               ['scenes/atrium.toml', '--resolution', '160x120', '--spp', '16', '--indirect', 'path',
                '--max-depth', '3'],
               lambda spp, out: ['scenes/atrium/mitsuba_reference.py', MITSUBA, str(spp), out],
               (32, 128, 512, 2048), 'scenes/atrium/mitsuba-depth4-16384.exr'),
}


def block_error(lightcuts, image, reference):
    result = subprocess.run([lightcuts, 'compare', image, reference, '--blocks', '8', '--json'],
                            check=True, capture_output=True, text=True)
    return json.loads(result.stdout)['blocks']['mean_relative_error']


def stamp(lightcuts, repeat):
    commit = subprocess.run(['git', 'describe', '--always', '--dirty', '--abbrev=7'], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    cpu = next((line.split(':', 1)[1].strip() for line in open('/proc/cpuinfo') if line.startswith('model name')),
               platform.processor())
    memory = next(int(line.split()[1]) for line in open('/proc/meminfo') if line.startswith('MemTotal'))
    mitsuba = subprocess.run([sys.executable, '-c', 'import mitsuba; print(mitsuba.__version__)'],
                             capture_output=True, text=True).stdout.strip()
    version = subprocess.run([lightcuts, '--version'], capture_output=True, text=True).stdout.strip()
    return (f'Measured {datetime.date.today().isoformat()} at commit `{commit}` ({version}) '
            f'against Mitsuba {mitsuba} on {cpu}, {os.cpu_count()} threads, '
            f'{memory / 2 ** 20:.0f} GiB, median of {repeat} runs')


def run_row(name, args, out):
    what, ours, peer, peer_spp, reference = ROWS[name]
    twin = os.path.join(out, 'grid10k-lambertian.toml')
    exact = os.path.join(out, 'grid10k-exact-16-seed1.exr')
    if name == 'grid10k':
        peer_tools.write_lambertian_twin(os.path.join(ROOT, 'scenes', 'grid10k.toml'), twin)
        if not os.path.exists(exact):
            print('grid10k: the exact reference (about a minute) ...', file=sys.stderr)
            timed([args.lightcuts, 'render', twin, '-o', exact, '--exact', '--spp', '16', '--seed', '1',
                   '--resolution', '160x120', '--quiet'])
    fill = lambda word: word.format(twin=twin, exact=exact)
    reference = fill(reference)
    peer_reference = reference
    if name == 'grid10k':
        peer_reference = os.path.join(out, 'grid10k-mitsuba-262144-seed1.exr')
        if not os.path.exists(peer_reference):
            print('grid10k: Mitsuba\'s converged render (about three minutes) ...', file=sys.stderr)
            timed([sys.executable, 'ci/mitsuba-point-lights.py', twin, '262144', peer_reference, '160x120', '1'])
    image = os.path.join(out, f'{name}-lightcuts.exr')
    command = [args.lightcuts, 'render'] + [fill(w) for w in ours] + ['-o', image, '--aovs', 'none']
    seconds, log = timed_with_output(command, args.repeat)
    ours_row = (' '.join(fill(w) for w in ours).replace(out + '/', ''), seconds, block_error(args.lightcuts, image, reference))
    # The render's own summary: its lights, and its shadow rays a camera sample.
    lights = int(re.search(r'^  lights +(\d+)', log, re.M)[1])
    per_pixel = float(re.search(r'^  shadow rays +\d+ \(([\d.]+) per pixel\)', log, re.M)[1])
    our_spp = int(re.search(r'^  image .* (\d+) spp', log, re.M)[1])
    print(f'{name}: lightcuts {ours_row}', file=sys.stderr)
    points = []
    for spp in peer_spp:
        image = os.path.join(out, f'{name}-mitsuba-{spp}.exr')
        seconds = timed([sys.executable] + [fill(w) for w in peer(spp, image)], args.repeat)
        points.append((spp, seconds, block_error(args.lightcuts, image, peer_reference)))
        print(f'{name}: Mitsuba {points[-1]}', file=sys.stderr)
    peer_time, how = time_at([(t, e) for _, t, e in points], ours_row[2])
    return {'name': name, 'what': what, 'lights': lights, 'rays': per_pixel / our_spp, 'ours': ours_row, 'peer': points,
            'peer_time': peer_time, 'how': how,
            'reference': ' and '.join(f'`{r}`' for r in sorted({p.replace(out + '/', 'out/benchmarks/')
                                                                for p in (reference, peer_reference)}))}


def time_at(points, target):
    """The peer's time to `target` error from its (time, error) points:
    log-log between the two that bracket it; the cheapest setting's time
    when even that one is below the target (a process takes no less than
    its start-up, whatever its samples); or, beyond its best, the best
    one's time scaled as error ~ 1/sqrt(time), which charges the peer's
    start-up again and so favours lightcuts (said in the table)."""
    points = sorted(points)
    for (t0, e0), (t1, e1) in zip(points, points[1:]):
        if min(e0, e1) <= target <= max(e0, e1) and e0 != e1:
            s = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0))), 'interpolated'
    if all(e <= target for _, e in points):
        return points[0][0], 'its cheapest setting, already below our error'
    t, e = min(points, key=lambda p: p[1])
    return t * (e / target) ** 2, 'extrapolated from its best as 1/sqrt(time) (favours lightcuts)'


def ratio(row):
    r = row['peer_time'] / row['ours'][1]
    return f'**{r:.1f}x faster**' if r >= 1 else f'{1 / r:.1f}x slower'


def tables(rows, stamp_line):
    summary = ['| scene | lights | shadow rays a sample | lightcuts | error | Mitsuba 3 at that error | lightcuts is |',
               '|---|---|---|---|---|---|---|']
    for row in rows:
        summary.append(f'| {row["name"]}: {row["what"]} | {row["lights"]:,} | {row["rays"]:.1f} | '
                       f'{row["ours"][1]:.2f} s | {100 * row["ours"][2]:.2f}% | {row["peer_time"]:.2f} s | {ratio(row)} |')
    detail = ['| scene | renderer | setting | time (s) | 8x8 block error |', '|---|---|---|---|---|']
    for row in rows:
        detail.append(f'| {row["name"]} | lightcuts | `{row["ours"][0]}` | {row["ours"][1]:.2f} | '
                      f'{100 * row["ours"][2]:.3f}% |')
        for spp, seconds, err in row['peer']:
            detail.append(f'| {row["name"]} | Mitsuba 3 | {spp} spp | {seconds:.2f} | {100 * err:.3f}% |')
    references = [f'- {row["name"]}: {row["reference"]}; the peer\'s time at our error '
                  f'{row["how"]}' for row in rows]
    return '\n'.join(summary), '\n'.join(detail), '\n'.join(references), stamp_line


def write(summary, detail, references, stamp_line):
    doc = f"""# Benchmarks

Written by `python3 ci/benchmarks.py --write`; do not edit by hand. The
script's docstring says what it measures and how.

{stamp_line}.

## Speed at equal error against Mitsuba 3

{summary}

"lightcuts is" compares lightcuts' time with the time Mitsuba 3 needs for
the same error. On direct light from many point lights the light tree
wins; where one big emitter, a sky or bounced light dominates, a path
tracer's one light sample a vertex wins: the cut draws 10 to 50 shadow
rays a camera sample where a path tracer draws one a vertex
([notebook](notebook/measurements.md#indirect-light-by-paths)).

## Every setting measured

{detail}

References:

{references}
"""
    with open(os.path.join(ROOT, 'docs', 'benchmarks.md'), 'w') as f:
        f.write(doc)
    readme_path = os.path.join(ROOT, 'README.md')
    readme = open(readme_path).read()
    block = f'<!-- benchmarks -->\n{summary}\n\n*{stamp_line}: `ci/benchmarks.py`, [docs/benchmarks.md](docs/benchmarks.md).*\n<!-- /benchmarks -->'
    updated, count = re.subn(r'<!-- benchmarks -->.*?<!-- /benchmarks -->', lambda _: block, readme, flags=re.S)
    if count != 1:
        sys.exit('benchmarks: README.md has no <!-- benchmarks --> ... <!-- /benchmarks --> block')
    open(readme_path, 'w').write(updated)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rows', default=','.join(ROWS))
    parser.add_argument('--repeat', type=int, default=3)
    parser.add_argument('--out', default='out/benchmarks')
    parser.add_argument('--write', action='store_true')
    parser.add_argument('--lightcuts', default=os.path.join(ROOT, 'target', 'release', 'lightcuts'))
    args = parser.parse_args()
    os.chdir(ROOT)
    os.makedirs(args.out, exist_ok=True)
    os.environ.setdefault('DRJIT_LIBLLVM_PATH', LLVM)
    names = args.rows.split(',')
    for name in names:
        if name not in ROWS:
            sys.exit(f'benchmarks: no row {name!r} (rows: {", ".join(ROWS)})')
    rows = [run_row(name, args, args.out) for name in names]
    with open(os.path.join(args.out, 'rows.json'), 'w') as f:
        json.dump(rows, f, indent=1)
    summary, detail, references, stamp_line = tables(rows, stamp(args.lightcuts, args.repeat))
    print(stamp_line, summary, detail, references, sep='\n\n')
    if args.write:
        if set(names) != set(ROWS):
            sys.exit('benchmarks: --write needs every row (drop --rows)')
        write(summary, detail, references, stamp_line)


if __name__ == '__main__':
    main()
