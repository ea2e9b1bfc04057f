//! Benchmarks printed as figures (never timed assertions): the light-tree
//! build (`lightcuts bench tree`).

pub mod rays;
pub mod tree;
