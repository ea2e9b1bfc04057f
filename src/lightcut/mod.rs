//! Lightcuts ([LC05] sec. 4): per shading point, a cut through the light
//! trees whose every cluster's error bound is at most `error` times the total
//! estimate, or `max_cut` nodes.

pub mod bounds;
pub mod cut;
