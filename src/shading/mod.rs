//! Shading: the shading point a ray hit describes (`surface`, built by
//! `geometry` from Embree's hits) and the evaluation of one light at it,
//! with its shadow ray, singly or in batches (`direct`). Both render modes
//! and the light cuts above evaluate lights only through here.

pub mod bsdf;
pub mod direct;
pub mod evaluate;
pub mod fibre;
pub mod geometry;
pub mod lobes;
pub mod microfacet;
pub mod pbr;
pub mod refraction;
pub mod sheen;
pub mod surface;

pub use bsdf::{Bsdf, BsdfSample};
pub use direct::{light_sample, light_term, Lanes, LightEvaluator, LightTerm, MaterialLanes};
#[cfg(test)]
pub(crate) use evaluate::resample_and_trace_by;
pub use evaluate::{
    evaluate_and_trace, evaluate_into, resample_and_trace, trace_evaluations, BatchBuffers, BatchResult, Choices,
    Evaluations, LightBatch, SHADOW_BATCH, SHADOW_PACKET,
};
pub use geometry::{Geometry, GeometryError};
pub use lobes::Lobes;
pub use surface::{SurfaceKey, SurfacePoint};
