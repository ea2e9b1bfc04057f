"""Mitsuba 3's reference for scenes/atrium.toml: its path tracer at a given
max_depth, a box filter, the scene read from the TOML itself (camera,
quads, boxes, spheres, materials, area lights, the sun, the sky), so the
two stay one scene.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/atrium/mitsuba_reference.py llvm_ad_rgb SPP OUT.exr [MAX_DEPTH] [WIDTHxHEIGHT]

MAX_DEPTH defaults to 4, lightcuts' paths of 3 vertices (--indirect path
--max-depth 3: two bounces, as the scene's VPLs); WIDTHxHEIGHT to 160x120.
mitsuba-depth4-16384.exr was made with SPP 16384.

How the two scenes correspond:
- Materials: the TOML's diffuse + normalised Phong (f = k_d/pi + k_s (n+2)
  /(2 pi) cos^n alpha, alpha from the mirror direction of the view;
  docs/scene-format.md) has no Mitsuba plugin, so it is written here as a
  Python BSDF (`LightcutsPhong`): evaluated as the formula, sampled by a
  cosine lobe or the Phong lobe (pdf (n+1)/(2 pi) cos^n alpha), one-sample
  MIS between them. The chrome (k_d 0.02 plus a mirror layer of 0.85) is a
  blend of a Lambertian of 0.2 and a perfect conductor of reflectance
  0.85/0.9 at weight 0.9: 0.1 x 0.2 = 0.02 diffuse, 0.9 x 0.944 = 0.85
  mirror. Every material is two-sided, as lightcuts shades both sides.
- The floor's texture: lightcuts reads texel row (1 - v) height (v up the
  image, as glTF and OpenGL), Mitsuba row v height, so its texture
  transform is (6u, 1 - 4v) for the TOML's texture_scale [6, 4]. Both
  interpolate linear (decoded sRGB) values bilinearly.
- The sky: Mitsuba's lat-long map has u = atan2(x, -z) / 2pi, ours 0.5 +
  that, so its copy is the map turned by half its width, each pixel
  repeated 8 x 8 (lightcuts takes the nearest pixel, Mitsuba interpolates:
  bilinear between equal pixels is the nearest one except in a band of
  1/8 pixel); scale 0.25 as the TOML's.
- The sun: a directional light of the TOML's irradiance; its 0.27-degree
  disc is a point here (the penumbra is a few centimetres wide).
- The panels: a rectangle emits towards its local +z, which to_world maps
  to the unit u x v of the TOML's quad (down), black to the light falling
  on it as the TOML's area lights.
- The spheres are analytic here and meshes with smooth normals in the TOML;
  the TOML's distance_clamp bounds only virtual point lights' and lights'
  1/d^2 below 15 cm, which the panels' points reach only on the tops of
  the columns they touch.
"""
import os
import sys
import time
import tomllib

import drjit as dr
import mitsuba as mi
import numpy as np

variant, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
depth = int(sys.argv[4]) if len(sys.argv) > 4 else 4
width, height = map(int, (sys.argv[5] if len(sys.argv) > 5 else '160x120').split('x'))
mi.set_variant(variant)
here = os.path.dirname(os.path.abspath(__file__))
scenes = os.path.dirname(here)
with open(os.path.join(scenes, 'atrium.toml'), 'rb') as f:
    toml = tomllib.load(f)
T = mi.ScalarTransform4f


def luminance(c):
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]


class LightcutsPhong(mi.BSDF):
    """k_d / pi + k_s (n + 2) / (2 pi) max(0, r . wo)^n, r the mirror
    direction of the view (wi in Mitsuba's words)."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        kd = props['kd']
        # A nested texture arrives as one, a constant colour as a colour.
        self.kd = kd if isinstance(kd, mi.Texture) else mi.load_dict({'type': 'rgb', 'value': list(kd)})
        self.ks = mi.Color3f(props['ks'])
        self.n = float(props['exponent'])
        kd_weight, ks_weight = float(props['kd_weight']), luminance(props['ks'])
        self.p_diffuse = kd_weight / (kd_weight + ks_weight) if kd_weight + ks_weight > 0 else 1.0
        flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
        self.m_flags = flags
        self.m_components = [mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide,
                             mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide]

    def _cos_alpha(self, si, wo):
        r = mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z)
        return dr.maximum(dr.dot(r, wo), 0.0)

    def _eval_pdf(self, si, wo, active):
        cos_i, cos_o = mi.Frame3f.cos_theta(si.wi), mi.Frame3f.cos_theta(wo)
        valid = active & (cos_i > 0) & (cos_o > 0)
        cos_alpha = self._cos_alpha(si, wo)
        lobe = dr.power(cos_alpha, self.n)
        kd = self.kd.eval(si, valid)
        f = kd * dr.inv_pi + self.ks * ((self.n + 2) * dr.inv_two_pi) * lobe
        pdf = self.p_diffuse * cos_o * dr.inv_pi + (1 - self.p_diffuse) * (self.n + 1) * dr.inv_two_pi * lobe
        return dr.select(valid, f * cos_o, 0.0), dr.select(valid, pdf, 0.0)

    def eval(self, ctx, si, wo, active=True):
        return self._eval_pdf(si, wo, active)[0]

    def pdf(self, ctx, si, wo, active=True):
        return self._eval_pdf(si, wo, active)[1]

    def eval_pdf(self, ctx, si, wo, active=True):
        return self._eval_pdf(si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        r = mi.Vector3f(-si.wi.x, -si.wi.y, si.wi.z)
        diffuse = sample1 < self.p_diffuse
        cos_alpha = dr.power(sample2.x, 1.0 / (self.n + 1))
        sin_alpha = dr.safe_sqrt(1 - cos_alpha * cos_alpha)
        phi = dr.two_pi * sample2.y
        around_r = mi.Frame3f(r).to_world(mi.Vector3f(sin_alpha * dr.cos(phi), sin_alpha * dr.sin(phi), cos_alpha))
        wo = dr.select(diffuse, mi.warp.square_to_cosine_hemisphere(sample2), around_r)
        value, pdf = self._eval_pdf(si, wo, active)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo, bs.pdf, bs.eta = wo, pdf, 1.0
        bs.sampled_type = dr.select(diffuse, mi.UInt32(+mi.BSDFFlags.DiffuseReflection),
                                    mi.UInt32(+mi.BSDFFlags.GlossyReflection))
        bs.sampled_component = dr.select(diffuse, mi.UInt32(0), mi.UInt32(1))
        ok = active & (pdf > 0)
        return bs, dr.select(ok, value / dr.select(ok, pdf, 1.0), 0.0)

    def traverse(self, callback):
        pass

    def to_string(self):
        return 'LightcutsPhong'


mi.register_bsdf('lightcuts_phong', lambda props: LightcutsPhong(props))


def rgb(value):
    return {'type': 'rgb', 'value': list(value)}


def material(m):
    if 'mirror' in m:
        kd = luminance(m['albedo'])
        mirror = luminance(m['mirror'])
        w = 0.9
        return {'type': 'twosided', 'bsdf': {
            'type': 'blendbsdf', 'weight': w,
            'bsdf_0': {'type': 'diffuse', 'reflectance': rgb([a / (1 - w) for a in m['albedo']])},
            'bsdf_1': {'type': 'conductor', 'material': 'none',
                       'specular_reflectance': rgb([c / w for c in m['mirror']])}}} if kd + mirror > 0 else None
    if 'texture' in m:
        su, sv = m.get('texture_scale', [1, 1])
        kd = {'type': 'bitmap', 'filename': os.path.join(scenes, m['texture']), 'filter_type': 'bilinear',
              'wrap_mode': 'repeat', 'to_uv': T().translate([0, 1, 0]).scale([su, -sv, 1])}
        mean = np.array(mi.Bitmap(os.path.join(scenes, m['texture'])).convert(
            mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False), dtype=np.float64)
        kd_weight = luminance(mean.reshape(-1, 3).mean(axis=0))
    else:
        kd, kd_weight = rgb(m['albedo']), luminance(m['albedo'])
    if 'specular' not in m:
        return {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': kd}}
    return {'type': 'twosided', 'bsdf': {'type': 'lightcuts_phong', 'kd': kd, 'ks': m['specular'],
                                         'exponent': float(m['exponent']), 'kd_weight': kd_weight}}


def quad_frame(corner, u, v):
    corner, u, v = map(np.array, (corner, u, v))
    normal = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    frame = np.identity(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = u / 2, v / 2, normal, corner + (u + v) / 2
    return T(frame.tolist())


camera = toml['camera']
scene = {
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': depth},
    'sensor': {'type': 'perspective', 'fov': camera['fov_y'], 'fov_axis': 'y',
               'to_world': T().look_at(origin=camera['eye'], target=camera['look_at'], up=[0, 1, 0]),
               'sampler': {'type': 'independent', 'sample_count': spp},
               'film': {'type': 'hdrfilm', 'width': width, 'height': height,
                        'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
}
materials = {name: material(m) for name, m in toml['materials'].items()}
for i, shape in enumerate(toml['shapes']):
    bsdf = materials[shape['material']]
    if shape['type'] == 'quad':
        scene[f'shape{i}'] = {'type': 'rectangle', 'to_world': quad_frame(shape['corner'], shape['u'], shape['v']),
                              'bsdf': bsdf}
    elif shape['type'] == 'box':
        lo, hi = np.array(shape['min'], dtype=float), np.array(shape['max'], dtype=float)
        scene[f'shape{i}'] = {'type': 'cube', 'to_world': T().translate(((lo + hi) / 2).tolist()).scale(
            ((hi - lo) / 2).tolist()), 'bsdf': bsdf}
    elif shape['type'] == 'sphere':
        scene[f'shape{i}'] = {'type': 'sphere', 'center': shape['center'], 'radius': shape['radius'], 'bsdf': bsdf}
    else:
        raise SystemExit(f'atrium.toml: shapes[{i}].type {shape["type"]} is not translated here')
for i, light in enumerate(toml['lights']):
    if light['type'] == 'area':
        scene[f'light{i}'] = {'type': 'rectangle', 'to_world': quad_frame(light['corner'], light['u'], light['v']),
                              'bsdf': {'type': 'diffuse', 'reflectance': rgb([0, 0, 0])},
                              'emitter': {'type': 'area', 'radiance': rgb(light['radiance'])}}
    elif light['type'] == 'sun':
        d = np.array(light['direction'], dtype=float)
        scene[f'light{i}'] = {'type': 'directional', 'direction': (-d / np.linalg.norm(d)).tolist(),
                              'irradiance': rgb(light['irradiance'])}
    else:
        raise SystemExit(f'atrium.toml: lights[{i}].type {light["type"]} is not translated here')
environment = toml['environment']
ours = np.array(mi.Bitmap(os.path.join(scenes, environment['file'])), dtype=np.float32)[..., :3]
theirs = np.roll(ours, -ours.shape[1] // 2, axis=1).repeat(8, axis=0).repeat(8, axis=1)
scene['environment'] = {'type': 'envmap', 'bitmap': mi.Bitmap(np.ascontiguousarray(theirs)),
                        'scale': environment['scale']}

start = time.time()
image = mi.render(mi.load_dict(scene))
mi.Bitmap(image).write(out)
print(f'{variant}, {spp} spp, max_depth {depth}, {width}x{height}: {time.time() - start:.2f} s')
