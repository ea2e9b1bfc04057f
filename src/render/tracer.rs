//! What every part of a camera path's shading reads: the scene's geometry
//! and lights, the continuous emitters' sampling, and the steps from a ray
//! to a lit vertex that the path loop, next-event estimation and the
//! direct-light methods share (the first hit past culled faces, the vertex
//! with its pixel sample, the moving lights).

use glam::DVec3;

use super::emitter_sampling::EmitterSampling;
use crate::embree::{Hit, Ray};
use crate::light::Lights;
use crate::lightcut::CutResult;
use crate::shading::{BatchBuffers, Bsdf, Geometry, LightBatch, Lobes, SurfacePoint};
use crate::util::sampling::PixelSample;
use crate::util::streams::Stream;

/// The random stream of a camera sample's shading points: (seed, pixel x,
/// pixel y, sample index), and the bounce is added per point.
pub type SampleKey = [u64; 4];

/// Most culled back faces a camera or mirror ray passes through before it
/// is taken to see nothing (a bound on a hostile stack of coplanar faces).
const MAX_CULLED_FACES: usize = 64;

/// The scene as a pass's camera paths see it.
pub struct Tracer<'a> {
    pub geometry: &'a Geometry<'a>,
    /// The lights of each light group (one entry when the scene names none).
    pub lights: &'a [Lights],
    /// Whether radiance is also split by light group: only when the scene
    /// names groups.
    pub split_groups: bool,
    /// The continuous emitters (environment, area lights) as sharp lobes
    /// sample them, when the scene has any.
    pub emitters: Option<&'a EmitterSampling<'a>>,
    /// Samples per pixel (what a vertex's draws are stratified over).
    pub spp: u32,
    /// The camera's pixel footprint, which filters the textures a camera
    /// path reads (docs/design.md §5.3, "MIP maps"); None reads them
    /// unfiltered.
    pub footprint: Option<crate::scene::PixelFootprint>,
}

/// A vertex's BSDF when its glossy lobe is too sharp for the emitters'
/// stand-in lights, with the emitters' sampling that lights that lobe.
pub type SharpLobe<'a> = Option<(&'a EmitterSampling<'a>, Bsdf)>;

impl<'a> Tracer<'a> {
    /// Number of light groups the radiance is split into (0: no split).
    #[must_use]
    pub fn group_slots(&self) -> usize {
        if self.split_groups {
            self.lights.len()
        } else {
            0
        }
    }

    /// The first surface `ray` sees: back faces that cull are passed
    /// through (moving the ray's start past them), up to
    /// `MAX_CULLED_FACES` of them.
    pub fn first_hit(&self, ray: &mut Ray) -> Option<Hit> {
        for _ in 0..MAX_CULLED_FACES {
            let hit = self.geometry.embree.intersect(ray)?;
            if !self.geometry.culls(ray, &hit) {
                return Some(hit);
            }
            // Past the culled triangle: the next float after its distance.
            ray.t_near = f32::from_bits(hit.t.to_bits() + 1).max(hit.t * (1.0 + 1e-6));
        }
        None
    }

    /// The shading point where `ray`, the `depth`-th ray of the camera path
    /// of `sample`, hit, and the emitters' sampling with the point's BSDF
    /// when its glossy lobe is too sharp for their stand-in lights.
    pub fn vertex(&self, ray: &Ray, hit: &Hit, sample: SampleKey, depth: u32) -> (SurfacePoint<'a>, SharpLobe<'a>) {
        let mut sp = self.geometry.surface_seen(ray, hit, self.footprint.as_ref());
        // What the point draws (the stochastic cut's lights, points on
        // triangle lights) is stratified over the pixel's samples
        // (docs/design.md §10.8); keyed by the bounce too.
        sp.sample = Some(self.pixel_sample(sample, depth));
        // A glossy lobe too sharp for some emitter's stand-in lights:
        // they light the diffuse lobe, and the glossy one's light from
        // the continuous emitters is sampled (by every method alike).
        let sharp = self.emitters.and_then(|e| e.sharp_lobe(&sp).map(|bsdf| (e, bsdf)));
        if sharp.is_some() {
            sp.emitter_lobes = Lobes::DIFFUSE;
        }
        (sp, sharp)
    }

    /// The material index of the mesh `hit` is on.
    #[must_use]
    pub fn material_of(&self, hit: &Hit) -> usize {
        self.geometry.scene.meshes[self.geometry.mesh_of(hit)].material
    }

    /// The pixel sample of a camera path's `depth`-th vertex: its pixel's
    /// key (the seed, the pixel and the bounce) and its index among the
    /// pixel's samples.
    #[must_use]
    pub fn pixel_sample(&self, [seed, x, y, s]: SampleKey, depth: u32) -> PixelSample {
        let pixel = Stream::PixelSample.rng(&[seed, x, y, u64::from(depth)]).next_u64();
        PixelSample { pixel, index: s as u32, count: self.spp.max(1) }
    }

    /// The light of the moving lights (in no tree: docs/design.md §13.6)
    /// at `sp`, each where it is at the point's time with a shadow ray of
    /// its own, times `strength`: counted into `found` (each group's share
    /// credited to its slot); returns the radiance, which the caller adds.
    pub fn moving_light(
        &self,
        sp: &SurfacePoint<'_>,
        strength: DVec3,
        buffers: &mut BatchBuffers,
        found: &mut CutResult,
    ) -> DVec3 {
        let mut radiance = DVec3::ZERO;
        for (g, group) in self.lights.iter().enumerate().filter(|(_, group)| !group.moving.is_empty()) {
            let mut batch = LightBatch::new(&self.geometry.embree, sp, buffers);
            for light in &group.moving {
                batch.add(&light.at(sp.time));
            }
            let mut batch = batch.finish();
            batch.radiance *= strength;
            radiance += found.count_batch(g, &batch);
        }
        radiance
    }

    /// Whether any light group has moving lights.
    #[must_use]
    pub fn has_moving_lights(&self) -> bool {
        self.lights.iter().any(|group| !group.moving.is_empty())
    }
}
