//! Helpers used by every layer: colour arithmetic, deterministic random
//! numbers, a content hash, four-lane maths, triangles' normals and areas,
//! reading untrusted files and catching a library's panic quietly. Nothing here imports the rest of the crate.

pub mod color;
pub mod file;
pub mod hash;
pub mod panic;
pub mod sampling;
pub mod simd;
pub mod streams;
pub mod triangle;
