//! Helpers used by every layer: colour arithmetic, deterministic random
//! numbers, a content hash and four-lane maths. Nothing here imports the
//! rest of the crate.

pub mod color;
pub mod hash;
pub mod sampling;
pub mod simd;
