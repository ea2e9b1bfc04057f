//! The bounded method: a lightcut ([LC05]; docs/design.md §9) through the
//! scene's light trees at every vertex, with reconstruction cuts
//! (docs/design.md §9.6) when its settings ask for them: full cuts only at
//! the corners of pixel blocks, the camera hits between them cut from
//! their corners' anchors.

use std::collections::HashMap;

use super::{timed_cut, DirectLight, DirectWorker, Frame, Vertex};
use crate::light_tree::LightTrees;
use crate::lightcut::reconstruction::{AnchorBlock, AnchorCut, ReconstructionScratch, ANCHORS};
use crate::lightcut::{self, CutResult, CutScratch, CutSettings};
use crate::render::stats::ShadingStats;
use crate::render::tracer::Tracer;
use crate::render::PixelBounds;
use crate::scene::Camera;
use crate::shading::{BatchBuffers, SurfaceKey, SurfacePoint};

/// Lightcuts with representatives fixed when the trees are built.
pub struct Bounded<'a> {
    pub trees: &'a LightTrees,
    pub settings: CutSettings,
}

impl<'a> DirectLight<'a> for Bounded<'_> {
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm,
    {
        Box::new(BoundedWorker {
            method: self,
            cut: CutScratch::default(),
            batch: BatchBuffers::default(),
            reconstruction: ReconstructionScratch::default(),
            anchors: Anchors::default(),
            anchor_camera: None,
        })
    }
}

struct BoundedWorker<'m, 't> {
    method: &'m Bounded<'t>,
    cut: CutScratch,
    batch: BatchBuffers,
    reconstruction: ReconstructionScratch,
    anchors: Anchors,
    /// The anchors' camera when the tile's camera moves over the shutter:
    /// the camera at the middle of it.
    anchor_camera: Option<Camera>,
}

impl<'a> DirectWorker<'a> for BoundedWorker<'_, '_> {
    /// Forgets the anchors: a tile makes its own as its pixels need them,
    /// so that they depend on the image alone (docs/design.md §9.6).
    fn start_tile(&mut self, _: &Tracer<'a>, frame: Frame<'_>, _: PixelBounds, _: &mut ShadingStats) -> u64 {
        self.anchors.clear();
        // An anchor's camera ray: through its corner's point of the film,
        // the lens's centre, at the middle of the shutter.
        self.anchor_camera = frame.camera.shutter_open().then(|| frame.camera.at(0.5));
        0
    }

    /// Makes pixel (x, y)'s anchors, the corners of its B x B pixel
    /// block, current. What an anchor costs counts in the pass's totals
    /// (`stats`), not in the pixel's AOVs: which pixel of a tile first
    /// needs an anchor depends on the tile, and the AOVs must not.
    fn start_pixel(
        &mut self,
        tracer: &Tracer<'a>,
        frame: Frame<'_>,
        (x, y): (u32, u32),
        stats: &mut ShadingStats,
    ) -> u64 {
        let block = self.method.settings.reconstruction_block;
        if block == 0 {
            return 0;
        }
        let (x0, y0) = (x / block * block, y / block * block);
        let corners = [(x0, y0), (x0 + block, y0), (x0, y0 + block), (x0 + block, y0 + block)];
        let camera = self.anchor_camera.take();
        let rays =
            self.set_anchors(tracer, camera.as_ref().unwrap_or(frame.camera), corners, frame.settings.seed, stats);
        self.anchor_camera = camera;
        rays
    }

    /// With reconstruction, a camera hit whose pixel's anchors fit it is
    /// cut from theirs; every other vertex is cut in full.
    fn light(&mut self, tracer: &Tracer<'a>, vertex: &Vertex<'_, 'a>, stats: &mut ShadingStats) -> Option<CutResult> {
        let (Bounded { trees, settings }, sp) = (self.method, vertex.sp);
        let (groups, embree) = (tracer.group_slots(), &tracer.geometry.embree);
        let anchors = if vertex.depth == 0 { self.anchors.fitting(vertex.material, sp) } else { None };
        let mut found = timed_cut(stats, || match anchors {
            Some(found) => {
                let block = &self.anchors.blocks[&found];
                let scratch = &mut self.reconstruction;
                lightcut::reconstruction::evaluate(trees, sp, embree, settings, block, scratch, groups)
            }
            None => lightcut::evaluate(trees, sp, embree, settings, &mut self.cut, groups),
        });
        let moving = tracer.moving_light(sp, glam::DVec3::ONE, &mut self.batch, &mut found);
        found.radiance += moving;
        Some(found)
    }
}

impl BoundedWorker<'_, '_> {
    /// Makes sure the anchors of the block corners `corners` are kept,
    /// each cut in full where `camera`'s ray through the corner first hits
    /// a lit surface, and makes them the current pixel's (None when one of
    /// them saw no surface). What the new anchors cost is counted in
    /// `stats` (each is a shading point). `seed` keys each anchor's point
    /// as it keys a camera sample's at the corner. Returns the camera rays
    /// cast.
    fn set_anchors(
        &mut self,
        tracer: &Tracer<'_>,
        camera: &Camera,
        corners: [(u32, u32); ANCHORS],
        seed: u64,
        stats: &mut ShadingStats,
    ) -> u64 {
        let mut camera_rays = 0;
        let mut found = [0usize; ANCHORS];
        let mut all = true;
        for (slot, &(cx, cy)) in found.iter_mut().zip(&corners) {
            let index = match self.anchors.corners.get(&(cx, cy)) {
                Some(&index) => index,
                None => {
                    camera_rays += 1;
                    let mut ray = camera.ray(cx as f32, cy as f32);
                    let anchor = tracer.first_hit(&mut ray).and_then(|hit| {
                        // The same point as a camera sample there would be.
                        let (sp, _) = tracer.vertex(&ray, &hit, [seed, u64::from(cx), u64::from(cy), 0], 0);
                        (!sp.material.unlit).then(|| self.anchor(tracer, tracer.material_of(&hit), &sp, stats))
                    });
                    let index = anchor.map(|a| {
                        self.anchors.anchors.push(a);
                        self.anchors.anchors.len() - 1
                    });
                    self.anchors.corners.insert((cx, cy), index);
                    index
                }
            };
            match index {
                Some(i) => *slot = i,
                None => all = false,
            }
        }
        let anchors = &mut self.anchors;
        anchors.current = all.then_some(found);
        if all && !anchors.blocks.contains_key(&found) {
            let block = AnchorBlock::merge(found.map(|i| &anchors.anchors[i].cut));
            anchors.blocks.insert(found, block);
        }
        camera_rays
    }

    /// A full cut at `sp`, kept as an anchor.
    fn anchor(
        &mut self,
        tracer: &Tracer<'_>,
        material: usize,
        sp: &SurfacePoint<'_>,
        stats: &mut ShadingStats,
    ) -> Anchor {
        let Bounded { trees, settings } = self.method;
        let mut cut = AnchorCut::default();
        let (groups, embree) = (tracer.group_slots(), &tracer.geometry.embree);
        let result = lightcut::cut::evaluate_anchor(trees, sp, embree, settings, &mut self.cut, groups, &mut cut);
        stats.record_point(result.nodes, result.shadow_rays);
        Anchor { surface: SurfaceKey::of(material, sp), cut }
    }
}

/// A full cut at a corner of a pixel block (reconstruction cuts,
/// docs/design.md §9.6): where it hit, and what it found.
struct Anchor {
    surface: SurfaceKey,
    cut: AnchorCut,
}

/// The anchors of a tile (keyed by their corners in image pixels), and the
/// four of the pixel being shaded.
#[derive(Default)]
struct Anchors {
    corners: HashMap<(u32, u32), Option<usize>>,
    anchors: Vec<Anchor>,
    /// Each block's anchors merged (by their indices), made when a pixel
    /// of the block is first shaded.
    blocks: HashMap<[usize; ANCHORS], AnchorBlock>,
    /// The pixel's block corners' anchors; None where a corner saw no
    /// surface (the pixel's points are then cut in full).
    current: Option<[usize; ANCHORS]>,
}

impl Anchors {
    /// Forgets every anchor (a new tile).
    fn clear(&mut self) {
        self.corners.clear();
        self.anchors.clear();
        self.blocks.clear();
        self.current = None;
    }

    /// The pixel's anchors, if all four are on the surface of `sp`
    /// (material `material`; `SurfaceKey::holds`).
    fn fitting(&self, material: usize, sp: &SurfacePoint<'_>) -> Option<[usize; ANCHORS]> {
        let current = self.current?;
        current.iter().all(|&i| self.anchors[i].surface.holds(material, sp)).then_some(current)
    }
}
