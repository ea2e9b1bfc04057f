//! lightcuts: a many-light renderer implementing Lightcuts [LC05] on Intel Embree.
//!
//! The modules are layers, each using only the ones listed before it
//! (`tests/layers.rs` checks it):
//!
//! - `util`: colour and deterministic random numbers (no dependencies);
//! - `embree`: the only `unsafe`, a safe wrapper over our C shim;
//! - `scene`: scene files, validation, meshes, materials, textures, images;
//! - `light`: light kinds, and the emitters that become lights;
//! - `light_tree`: the trees' layout and their parallel agglomerative build;
//! - `shading`: the shading point, one light's contribution, shadow-ray batches;
//! - `lightcut`: per-point cuts (bounds, refinement);
//! - `render`: integrator, tiles on rayon, film, VPLs (progress by callback);
//! - `output`: EXR, previews, plots, image comparison;
//! - `cli`: the command line, progress display, benchmarks, exit codes.
#![deny(unsafe_code)]

pub mod util;

pub mod embree;

pub mod scene;

pub mod light;

pub mod light_tree;

pub mod shading;

pub mod lightcut;

pub mod render;

pub mod output;

pub mod cli;
