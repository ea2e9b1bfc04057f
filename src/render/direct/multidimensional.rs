//! The multidimensional method: one cut per pixel ([MDLC06];
//! docs/design.md §13) through (gather cluster, light cluster) pairs. A
//! path's vertices are not lit one by one: each joins the pixel's gather
//! points with its path's throughput, and the pixel's end lights them all
//! at once.

use glam::DVec3;

use super::{timed_cut, DirectLight, DirectWorker, Vertex};
use crate::light_tree::LightTrees;
use crate::lightcut::multidimensional::{GatherPoint, GatherScratch};
use crate::lightcut::{self, CutResult, CutSettings};
use crate::render::stats::ShadingStats;
use crate::render::tracer::Tracer;
use crate::shading::BatchBuffers;

/// Multidimensional lightcuts over a pixel's gather points.
pub struct Multidimensional<'a> {
    pub trees: &'a LightTrees,
    pub settings: CutSettings,
}

impl<'a> DirectLight<'a> for Multidimensional<'_> {
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm,
    {
        Box::new(MultidimensionalWorker {
            method: self,
            gathered: Vec::new(),
            gather: GatherScratch::default(),
            batch: BatchBuffers::default(),
        })
    }
}

struct MultidimensionalWorker<'m, 't, 'a> {
    method: &'m Multidimensional<'t>,
    /// The gather points of the pixel being shaded.
    gathered: Vec<GatherPoint<'a>>,
    gather: GatherScratch,
    batch: BatchBuffers,
}

impl<'a> DirectWorker<'a> for MultidimensionalWorker<'_, '_, 'a> {
    /// The vertex joins the pixel's gather points; its light comes at the
    /// pixel's end.
    fn light(&mut self, _: &Tracer<'a>, vertex: &Vertex<'_, 'a>, _: &mut ShadingStats) -> Option<CutResult> {
        self.gathered.push(GatherPoint { sp: vertex.sp.clone(), strength: vertex.throughput });
        None
    }

    /// The direct light of the pixel's gather points, summed with their
    /// strengths.
    fn finish_pixel(
        &mut self,
        tracer: &Tracer<'a>,
        pixel: [u64; 3],
        groups: &mut [DVec3],
        stats: &mut ShadingStats,
    ) -> Option<DVec3> {
        let Multidimensional { trees, settings } = self.method;
        let (points, embree) = (&self.gathered, &tracer.geometry.embree);
        let gather = &mut self.gather;
        let mut found = timed_cut(stats, || {
            lightcut::multidimensional::evaluate(trees, points, embree, settings, pixel, gather, groups.len())
        });
        let mut moving = DVec3::ZERO;
        if tracer.has_moving_lights() {
            for point in points {
                moving += tracer.moving_light(&point.sp, point.strength, &mut self.batch, &mut found.cut);
            }
        }
        found.cut.radiance += moving;
        stats.record_point(found.cut.nodes, found.cut.shadow_rays);
        stats.gather_points += points.len() as u64;
        stats.gather_nodes += found.gather_nodes;
        let mut radiance = DVec3::ZERO;
        found.cut.add_scaled_to(DVec3::ONE, &mut radiance, groups);
        self.gathered.clear();
        Some(radiance)
    }
}
