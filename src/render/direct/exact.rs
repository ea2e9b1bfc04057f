//! The exact method: every light, one shadow ray each ([LC05] eq. 1;
//! docs/design.md §5.5). The reference every other method is measured
//! against.

use glam::DVec3;

use super::{DirectLight, DirectWorker, Vertex};
use crate::lightcut::CutResult;
use crate::render::stats::ShadingStats;
use crate::render::tracer::Tracer;
use crate::shading::{BatchBuffers, LightBatch};

/// Every light of every group, the moving ones where they are at the
/// vertex's time.
pub struct Exact;

impl<'a> DirectLight<'a> for Exact {
    fn worker<'m>(&'m self) -> Box<dyn DirectWorker<'a> + 'm>
    where
        'a: 'm,
    {
        Box::new(ExactWorker::default())
    }
}

#[derive(Default)]
struct ExactWorker {
    batch: BatchBuffers,
}

impl<'a> DirectWorker<'a> for ExactWorker {
    fn light(&mut self, tracer: &Tracer<'a>, vertex: &Vertex<'_, 'a>, _: &mut ShadingStats) -> Option<CutResult> {
        let (sp, groups) = (vertex.sp, tracer.group_slots());
        // Every light, one shadow ray each, in batches; summed group by
        // group, in light order (omni, oriented, directional, spot)
        // within each: deterministic. Run in the CPU's best instruction
        // set (docs/design.md §3).
        let found = crate::util::simd::best(
            #[inline(always)]
            || {
                let mut found = CutResult::with_groups(groups);
                let mut radiance = DVec3::ZERO;
                for (g, group) in tracer.lights.iter().enumerate() {
                    let mut batch = LightBatch::new(&tracer.geometry.embree, sp, &mut self.batch);
                    group.for_each(
                        #[inline(always)]
                        |light| batch.add(&light),
                    );
                    for light in &group.moving {
                        batch.add(&light.at(sp.time));
                    }
                    radiance += found.count_batch(g, &batch.finish());
                }
                found.radiance = radiance;
                found
            },
        );
        Some(found)
    }
}
