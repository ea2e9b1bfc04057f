//! Dependency-free helpers used by every layer: colour arithmetic and the
//! deterministic random numbers. Nothing here imports the rest of the crate.

pub mod color;
pub mod hash;
pub mod sampling;
