//! What a pass counts: shadow rays, shading points, cut sizes and path
//! lengths, per pixel (the `lightcuts` AOV) and summed over the pass
//! (`render --stats`, the EXR header).

/// Buckets of the cut-size histogram: bucket k counts cuts of 2^k to
/// 2^(k+1) - 1 nodes (bucket 0: cuts of 0 or 1 node).
pub const CUT_HISTOGRAM_BUCKETS: usize = 24;

/// Counters for one shading point or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShadingStats {
    pub shadow_rays: u64,
    pub shading_points: u64,
    /// Sum of cut sizes over shading points (the exact mode's cut is every light).
    pub cut_nodes: u64,
    pub max_cut: u64,
    /// Shading points by cut size (see [`CUT_HISTOGRAM_BUCKETS`]).
    pub cut_histogram: [u64; CUT_HISTOGRAM_BUCKETS],
    /// Surfaces camera paths met (the camera's hit, mirrors' and the path
    /// method's bounces): per camera ray, the mean path length.
    pub path_vertices: u64,
    /// Rays that continued camera paths past a surface (mirrors' and the
    /// path method's bounces).
    pub bounce_rays: u64,
    /// Gather points and gather-tree nodes (the multidimensional mode:
    /// its "shading points" are pixels, its cut nodes (gather, light) pairs).
    pub gather_points: u64,
    pub gather_nodes: u64,
    /// Thread-time spent choosing cuts (in `lightcut::evaluate`, outside
    /// Embree's queries), nanoseconds; counted only while Embree's queries
    /// are timed (`render --stats`).
    pub cut_nanos: u64,
}

impl ShadingStats {
    pub fn add(&mut self, other: &Self) {
        self.shadow_rays += other.shadow_rays;
        self.shading_points += other.shading_points;
        self.cut_nodes += other.cut_nodes;
        self.max_cut = self.max_cut.max(other.max_cut);
        self.cut_nanos += other.cut_nanos;
        self.gather_points += other.gather_points;
        self.gather_nodes += other.gather_nodes;
        self.path_vertices += other.path_vertices;
        self.bounce_rays += other.bounce_rays;
        for (a, b) in self.cut_histogram.iter_mut().zip(&other.cut_histogram) {
            *a += b;
        }
    }

    /// Records one shading point: its cut of `nodes` nodes and its shadow rays.
    pub fn record_point(&mut self, nodes: u64, shadow_rays: u64) {
        self.shading_points += 1;
        self.shadow_rays += shadow_rays;
        self.cut_nodes += nodes;
        self.max_cut = self.max_cut.max(nodes);
        let bucket = (63 - nodes.max(1).leading_zeros()) as usize;
        self.cut_histogram[bucket.min(CUT_HISTOGRAM_BUCKETS - 1)] += 1;
    }
}
