"""Mitsuba 3's reference for scenes/shiny.toml: its path tracer with
max_depth 2 (direct light only, as lightcuts computes), a box filter, the
same camera, floor, backdrop, spheres, 2,304 point lights, softbox and sky,
and glTF's metallic-roughness BRDF written as a Mitsuba BSDF in Python
(below), so that both renderers integrate the same function.

    pip install mitsuba numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1 \\
        python3 scenes/shiny/mitsuba_reference.py llvm_ad_rgb 8192 mitsuba-8192.exr

A fourth and fifth argument set the resolution (default 160 120), a
sixth the sampler's seed (default 0: the reference's; another seed for an
estimate independent of the reference, as when timing Mitsuba at fewer
samples against it).

How the two scenes correspond:
- The BRDF: glTF 2.0's Appendix B, as src/shading/pbr.rs computes it
  (docs/design.md section 5.3): GGX with alpha = roughness^2, the
  height-correlated Smith visibility, Schlick's Fresnel with f0 = 0.04 for
  the dielectric and the base colour for the metal, the dielectric's
  diffuse weighted by 1 - max(F). Mitsuba has no such BSDF (its
  `principled` has Disney's diffuse and a different specular layer), so
  `GltfBsdf` evaluates it and samples it: the visible normals of the GGX
  lobe with probability 1 for a metal and 1/2 for a dielectric, else the
  cosine. Any such mixture is unbiased; it only moves the noise.
- The point lights: `point` emitters of the TOML's intensity (W/sr) at the
  cell centres of the grid, as `type = "grid"` places them. Mitsuba picks
  an emitter by `sampling_weight`: 1/2,304 each for the grid's, 1 for the
  softbox and 1 for the sky, about their shares of the light.
- The softbox: a `rectangle` mapped onto the TOML's parallelogram and
  emitting towards u x v (+x), black to what lights it (as a TOML area
  light's own material).
- The floor and backdrop: rectangles mapped onto the TOML's quads, facing
  u x v (up, and towards the camera).
- The spheres are analytic here and 96-segment meshes with smooth normals
  in the TOML.
- The sky: a constant radiance (0.10, 0.12, 0.16).
"""
import sys
import time

import drjit as dr
import mitsuba as mi
import numpy as np

variant, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
width = int(sys.argv[4]) if len(sys.argv) > 4 else 160
height = int(sys.argv[5]) if len(sys.argv) > 5 else 120
seed = int(sys.argv[6]) if len(sys.argv) > 6 else 0
mi.set_variant(variant)


class GltfBsdf(mi.BSDF):
    """glTF 2.0's metallic-roughness BRDF (Appendix B), reflection only."""

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.base = mi.Color3f(props['base'])
        self.metallic = mi.Float(props['metallic'])
        roughness = props['roughness']
        self.alpha = roughness * roughness
        self.specular_probability = 1.0 if props['metallic'] >= 1.0 else 0.5
        flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [flags]
        self.m_flags = flags

    def distribution(self):
        return mi.MicrofacetDistribution(mi.MicrofacetType.GGX, self.alpha, True)

    def f_cos(self, wi, wo):
        nv, nl = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
        h = dr.normalize(wi + wo)
        a2 = self.alpha * self.alpha
        d = self.distribution().eval(h)
        nv_c = dr.maximum(nv, 1e-4)
        vis = 0.5 / (nl * dr.sqrt(nv_c * nv_c * (1 - a2) + a2) + nv_c * dr.sqrt(nl * nl * (1 - a2) + a2))
        x = dr.maximum(1.0 - dr.clip(dr.dot(wi, h), 0.0, 1.0), 0.0)
        w = x * x * x * x * x
        f_d = 0.04 + (1.0 - 0.04) * w
        f_m = self.base + (1.0 - self.base) * w
        dielectric = self.base / dr.pi * (1.0 - f_d) + f_d * d * vis
        metal = f_m * d * vis
        f = dielectric * (1.0 - self.metallic) + metal * self.metallic
        return dr.select((nv > 0) & (nl > 0), f * nl, 0.0)

    def pdf_of(self, wi, wo):
        nl = mi.Frame3f.cos_theta(wo)
        h = dr.normalize(wi + wo)
        specular = self.distribution().pdf(wi, h) / (4.0 * dr.abs(dr.dot(wo, h)))
        diffuse = mi.warp.square_to_cosine_hemisphere_pdf(wo)
        p = self.specular_probability
        pdf = p * specular + (1.0 - p) * diffuse
        return dr.select((mi.Frame3f.cos_theta(wi) > 0) & (nl > 0), pdf, 0.0)

    def sample(self, ctx, si, sample1, sample2, active):
        wi = si.wi
        m, _ = self.distribution().sample(wi, sample2)
        specular_wo = mi.reflect(wi, m)
        diffuse_wo = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(sample1 < self.specular_probability, specular_wo, diffuse_wo)
        bs = mi.BSDFSample3f()
        bs.wo = wo
        bs.pdf = self.pdf_of(wi, wo)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
        bs.sampled_component = mi.UInt32(0)
        value = self.f_cos(wi, wo)
        ok = active & (bs.pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        return (bs, dr.select(ok, value / dr.select(ok, bs.pdf, 1.0), 0.0))

    def eval(self, ctx, si, wo, active):
        return self.f_cos(si.wi, wo)

    def pdf(self, ctx, si, wo, active):
        return self.pdf_of(si.wi, wo)

    def eval_pdf(self, ctx, si, wo, active):
        return self.f_cos(si.wi, wo), self.pdf_of(si.wi, wo)

    def traverse(self, callback):
        pass

    def to_string(self):
        return 'GltfBsdf'


mi.register_bsdf('gltf', lambda props: GltfBsdf(props))

T = mi.ScalarTransform4f


def parallelogram(corner, u, v):
    """The to_world of a `rectangle` ([-1, 1]^2 of local xy, facing +z)
    onto corner + s u + t v, s and t in [0, 1], facing u x v."""
    corner, u, v = (np.array(a, dtype=float) for a in (corner, u, v))
    normal = np.cross(u, v) / np.linalg.norm(np.cross(u, v))
    frame = np.identity(4)
    frame[:3, 0], frame[:3, 1], frame[:3, 2], frame[:3, 3] = u / 2, v / 2, normal, corner + (u + v) / 2
    return T(frame.tolist())


def gltf(base, metallic, roughness):
    return {'type': 'gltf', 'base': mi.ScalarColor3f(base), 'metallic': metallic, 'roughness': roughness}


scene = {
    'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': 2},
    'sensor': {'type': 'perspective', 'fov': 40, 'fov_axis': 'y',
               'to_world': T().look_at(origin=[0, 3.2, 8.5], target=[0, 0.8, 0], up=[0, 1, 0]),
               'sampler': {'type': 'independent', 'sample_count': spp},
               'film': {'type': 'hdrfilm', 'width': width, 'height': height,
                        'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    'sky': {'type': 'constant', 'radiance': {'type': 'rgb', 'value': [0.10, 0.12, 0.16]}, 'sampling_weight': 1.0},
    'softbox': {'type': 'rectangle', 'to_world': parallelogram([-6.5, 1, 3], [0, 0, -2], [0, 2, 0]),
                'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}},
                'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': [6.0, 4.8, 3.6]},
                            'sampling_weight': 1.0}},
    'floor': {'type': 'rectangle', 'to_world': parallelogram([-8, 0, 8], [16, 0, 0], [0, 0, -16]),
              'bsdf': gltf([0.55, 0.55, 0.55], 0.0, 0.55)},
    'backdrop': {'type': 'rectangle', 'to_world': parallelogram([-8, 0, -4], [16, 0, 0], [0, 6, 0]),
                 'bsdf': gltf([0.35, 0.4, 0.5], 0.0, 0.8)},
    'gold': {'type': 'sphere', 'center': [-2.4, 0.9, 0.0], 'radius': 0.9, 'bsdf': gltf([1.0, 0.78, 0.34], 1.0, 0.25)},
    'chrome': {'type': 'sphere', 'center': [0.0, 1.0, -0.6], 'radius': 1.0, 'bsdf': gltf([0.55, 0.56, 0.55], 1.0, 0.08)},
    'copper': {'type': 'sphere', 'center': [2.3, 0.8, 0.2], 'radius': 0.8, 'bsdf': gltf([0.95, 0.64, 0.54], 1.0, 0.45)},
    'plastic': {'type': 'sphere', 'center': [-1.0, 0.5, 1.8], 'radius': 0.5, 'bsdf': gltf([0.7, 0.08, 0.06], 0.0, 0.2)},
    'rubber': {'type': 'sphere', 'center': [1.2, 0.45, 1.9], 'radius': 0.45, 'bsdf': gltf([0.08, 0.15, 0.55], 0.0, 0.7)},
}
# The grid: 48 x 48 point lights at the cell centres of corner + s u + t v.
corner, u, v, count = np.array([-5.0, 5.0, -3.0]), np.array([10.0, 0, 0]), np.array([0, 0, 8.0]), 48
for i in range(count):
    for j in range(count):
        position = corner + (i + 0.5) / count * u + (j + 0.5) / count * v
        scene[f'point_{i}_{j}'] = {'type': 'point', 'position': position.tolist(),
                                   'intensity': {'type': 'rgb', 'value': [0.006, 0.0062, 0.0068]},
                                   'sampling_weight': 1.0 / (count * count)}

scene = mi.load_dict(scene)
start = time.time()
image = mi.render(scene, seed=seed)
mi.Bitmap(image).write(out)
print(f'{variant}, {spp} spp, {width}x{height}: {time.time() - start:.2f} s')
