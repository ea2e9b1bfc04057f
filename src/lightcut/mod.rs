//! Lightcuts ([LC05] sec. 4): per shading point, a cut through the light
//! trees whose every cluster's error bound is at most `error` times the total
//! estimate, or `max_cut` nodes. `bounds` holds the provable upper bounds of
//! the material and geometric terms over a cluster; `cut` the refinement
//! with representatives fixed when the tree is built ([LC05], "bounded");
//! `stochastic` the cut whose lights are drawn per sample ([SLC19]).

pub mod bounds;
pub mod cut;
pub mod stochastic;

pub use cut::{evaluate, CutResult, CutScratch, CutSettings, GroupError, EXHAUSTIVE_LIGHTS};
pub use stochastic::StochasticScratch;
