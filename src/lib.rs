//! lightcuts: a many-light renderer implementing Lightcuts [LC05] on Intel Embree.
//!
//! Layout: `embree` (the only `unsafe`), `scene` (file format), `light`
//! (light types), `light_tree` (agglomerative clustering), `lightcut` (per-point
//! cuts), `render` (integrator, tiles), `output` (EXR, PNG, comparison), `cli`.
#![deny(unsafe_code)]

pub mod bench;
pub mod cli;
pub mod embree;
pub mod interrupt;
pub mod light;
pub mod light_tree;
pub mod lightcut;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
