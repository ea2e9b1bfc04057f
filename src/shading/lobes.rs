//! Which lobes of a material a query covers (docs/design.md §5.3): the
//! cut's lights, the environment's sampling and the BSDF's sampling each
//! ask for some of them.

/// Which lobes of a material a query covers: its diffuse (Lambert) lobe
/// and its glossy one (Phong's, or the metallic-roughness specular lobe).
/// The lights of the environment light a shading point whose glossy lobe
/// is too sharp for them with its diffuse lobe alone; the rest is sampled
/// (docs/design.md §6.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lobes {
    pub diffuse: bool,
    pub glossy: bool,
}

impl Lobes {
    pub const ALL: Self = Self { diffuse: true, glossy: true };
    pub const DIFFUSE: Self = Self { diffuse: true, glossy: false };
    pub const GLOSSY: Self = Self { diffuse: false, glossy: true };
}
