"""What the Mitsuba 3 renders of the courtyard scenes share
(mitsuba_reference.py for spheres.toml, glass_mitsuba.py for
glass_peer.toml): the environment as Mitsuba reads it, the camera and film,
and the timed render.

The environment: Mitsuba's lat-long map has u = atan2(x, -z) / 2pi, ours
0.5 + that (docs/scene-format.md), so its copy is the map turned by half
its width. Mitsuba interpolates the map bilinearly and lightcuts takes the
nearest pixel, so its copy is also each pixel repeated 8 x 8: bilinear
between equal pixels is the nearest one except in a band of 1/8 pixel.
"""
import os
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def environment(mi):
    """courtyard.exr as Mitsuba's `envmap` that lights as ours does."""
    ours = np.array(mi.Bitmap(os.path.join(HERE, 'courtyard.exr')), dtype=np.float32)
    theirs = np.roll(ours, -ours.shape[1] // 2, axis=1).repeat(8, axis=0).repeat(8, axis=1)
    return {'type': 'envmap', 'bitmap': mi.Bitmap(theirs)}


def sensor(mi, spp):
    """The TOMLs' camera (eye [0, 1.2, 5], looking at [0, 0.6, 0], 30 degrees
    vertical) on a 160 x 120 film with a box filter."""
    look = mi.ScalarTransform4f().look_at(origin=[0, 1.2, 5], target=[0, 0.6, 0], up=[0, 1, 0])
    return {'type': 'perspective', 'fov': 30, 'fov_axis': 'y', 'to_world': look,
            'sampler': {'type': 'independent', 'sample_count': spp},
            'film': {'type': 'hdrfilm', 'width': 160, 'height': 120,
                     'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}}


def render(mi, scene, variant, spp, out):
    """Renders the scene dictionary to the EXR `out`, prints the time, and
    returns the image."""
    scene = mi.load_dict(scene)
    start = time.time()
    image = mi.render(scene)
    mi.Bitmap(image).write(out)
    print(f'{variant}, {spp} spp: {time.time() - start:.2f} s')
    return image
