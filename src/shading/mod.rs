//! Shading: the shading point a ray hit describes (`surface`, built by
//! `geometry` from Embree's hits) and the evaluation of one light at it,
//! with its shadow ray, singly or in batches (`direct`). Both render modes
//! and the light cuts above evaluate lights only through here.

pub mod direct;
pub mod evaluate;
pub mod geometry;
pub mod pbr;
pub mod surface;

pub use direct::{light_sample, light_term, Lanes, LightEvaluator, LightTerm};
pub use evaluate::{
    evaluate_and_trace, evaluate_into, trace_evaluations, BatchBuffers, BatchResult, Choices, Evaluations, LightBatch,
    SHADOW_BATCH, SHADOW_PACKET,
};
pub use geometry::{Geometry, GeometryError};
pub use surface::SurfacePoint;
