//! Every random stream a pass draws from, in one list: what keys it, what
//! it draws, and a test that no two consumers can ever be handed the same
//! stream (docs/design.md §3.1, "Random streams").
//!
//! A stream is an [`Rng`] keyed by a few integers ([`Rng::from_key`]): the
//! seed, the pixel, the sample index, the path's bounce, and a tag that
//! tells the consumer apart. Two consumers share a stream when some
//! values of their fields give the same key, and then what one draws is
//! what the other draws: correlated noise, or a biased estimate. Each
//! stream's layout here says which values each position of its key can
//! take, so that [`Stream::can_share`] decides it for every pair.
//!
//! The keys are those the renderer has always used, so that images are
//! unchanged; a new consumer adds a variant, its layout and its tag.

use super::sampling::Rng;

/// What one position of a stream's key holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// Any value (the seed).
    Any,
    /// A value below the bound: a pixel coordinate (an image has fewer
    /// than 2^27 pixels), a sample index (below `MAX_SPP`, 2^20), a
    /// bounce, a light group or a light's index.
    Below(u64),
    /// The stream's tag, this value only.
    Tag(u64),
}

/// The most any counted field of a key can be (pixels, samples, bounces,
/// indices: each fits in 32 bits).
const COUNT: Field = Field::Below(1 << 32);
/// A sample index (below `MAX_SPP`).
const SAMPLE: Field = Field::Below(1 << 20);

/// Every stream of a pass. What one camera sample consumes is, in order:
/// [`Stream::CameraJitter`] (and its pixel's [`Stream::Lens`] and
/// [`Stream::Shutter`] rotations), then at each vertex of its path
/// [`Stream::PixelSample`], the direct-light method's streams
/// ([`Stream::Stochastic`], [`Stream::ReuseBlock`]; [`Stream::Gather`] per
/// pixel), [`Stream::Sun`], [`Stream::Emitter`] and [`Stream::Path`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// (seed, x, y, sample): the sample's point in its pixel, two floats.
    CameraJitter,
    /// (seed, x, y): the pixel's rotation of its lens points, two floats.
    Lens,
    /// (seed, x, y): the pixel's shift of its shutter times, one float.
    Shutter,
    /// (seed, x, y, bounce): the key a vertex's draws are stratified by
    /// over the pixel's samples (`PixelSample`), one integer.
    PixelSample,
    /// (seed, x, y, sample, bounce): a stochastic cut's draws, as many as
    /// its cut has nodes.
    Stochastic,
    /// (seed, block x, block y, block edge): the rotation of a reuse
    /// block's stratified set, one integer.
    ReuseBlock,
    /// (seed, x, y, bounce, group, sun): the rotation of a sun disc's
    /// directions over the pixel's samples, six floats.
    Sun,
    /// (seed, x, y, bounce): the rotation of the continuous emitters'
    /// draws over the pixel's samples, six floats.
    Emitter,
    /// (seed, x, y, bounce): the rotation of the environment's draws over
    /// the pixel's samples where it is one light beside the trees, six
    /// floats.
    Environment,
    /// (seed, x, y, sample, bounce): the path's choice of lobe, its
    /// direction and Russian roulette, five floats; without the path
    /// method, the first of them alone, at glass: its mirror or its
    /// transmission (docs/design.md §5.8).
    Path,
    /// (seed, x, y): the multidimensional cut's salt for its gather
    /// clusters' representatives, one integer.
    Gather,
    /// (seed, path): a VPL light path's source, directions and roulette.
    Vpl,
}

impl Stream {
    /// Every stream, for the test that no two can share a key.
    pub const ALL: [Self; 12] = [
        Self::CameraJitter,
        Self::Lens,
        Self::Shutter,
        Self::PixelSample,
        Self::Stochastic,
        Self::ReuseBlock,
        Self::Sun,
        Self::Emitter,
        Self::Environment,
        Self::Path,
        Self::Gather,
        Self::Vpl,
    ];

    /// The stream's key, position by position.
    #[must_use]
    pub fn layout(self) -> &'static [Field] {
        use Field::{Any, Tag};
        match self {
            Self::CameraJitter => &[Any, COUNT, COUNT, SAMPLE],
            Self::Lens => &[Any, COUNT, COUNT, Tag(0x1e45_0ff0_c5a3)],
            Self::Shutter => &[Any, COUNT, COUNT, Tag(0x5407_7e55)],
            Self::PixelSample => &[Any, COUNT, COUNT, COUNT, Tag(0x91c5_e15a)],
            Self::Stochastic => &[Any, COUNT, COUNT, COUNT, COUNT, Tag(0x5107_c4a5)],
            Self::ReuseBlock => &[Any, COUNT, COUNT, COUNT, Tag(0x4e05_e0b1)],
            Self::Sun => &[Any, COUNT, COUNT, COUNT, Tag(0x50d1_5c00), COUNT, COUNT],
            Self::Emitter => &[Any, COUNT, COUNT, COUNT, Tag(0xe4f1_5a3b)],
            Self::Environment => &[Any, COUNT, COUNT, COUNT, Tag(0xe4f1_5a3c)],
            Self::Path => &[Any, COUNT, COUNT, COUNT, COUNT, Tag(0xba7_4ce5)],
            Self::Gather => &[Any, COUNT, COUNT, Tag(0x6a7b_e412_0d05_c3e1)],
            Self::Vpl => &[Any, Tag(0x1b5a), COUNT],
        }
    }

    /// The stream of `fields` (the layout's positions but its tag, if it
    /// has one, in order).
    ///
    /// # Panics
    /// When `fields` does not fill the layout (a programming error).
    #[must_use]
    pub fn rng(self, fields: &[u64]) -> Rng {
        let layout = self.layout();
        let wanted = layout.iter().filter(|f| !matches!(f, Field::Tag(_))).count();
        assert_eq!(fields.len(), wanted, "{self:?} is keyed by {wanted} fields");
        let mut key = [0u64; 8];
        let mut given = fields.iter();
        for (slot, field) in key.iter_mut().zip(layout) {
            *slot = match field {
                Field::Tag(tag) => *tag,
                _ => *given.next().unwrap_or(&0),
            };
        }
        Rng::from_key(&key[..layout.len()])
    }

    /// Whether some key of `self` is also a key of `other`: of one length,
    /// and every position able to hold one value in both.
    #[must_use]
    pub fn can_share(self, other: Self) -> bool {
        let (a, b) = (self.layout(), other.layout());
        a.len() == b.len() && a.iter().zip(b).all(|(&x, &y)| overlap(x, y))
    }
}

/// Whether one value can be in both fields.
fn overlap(a: Field, b: Field) -> bool {
    match (a, b) {
        (Field::Any, _) | (_, Field::Any) | (Field::Below(_), Field::Below(_)) => true,
        (Field::Tag(t), Field::Below(n)) | (Field::Below(n), Field::Tag(t)) => t < n,
        (Field::Tag(t), Field::Tag(u)) => t == u,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_two_consumers_can_share_a_stream() {
        for (i, &a) in Stream::ALL.iter().enumerate() {
            assert!(a.can_share(a), "{a:?} shares its own keys");
            for &b in &Stream::ALL[i + 1..] {
                assert!(!a.can_share(b), "{a:?} and {b:?} can be handed the same stream");
            }
        }
    }

    #[test]
    fn the_check_finds_a_shared_stream() {
        // A tag below what a counted field holds is a value that field can
        // take: the camera's jitter at sample 0x55 would be this stream.
        let small = [Field::Any, COUNT, COUNT, Field::Tag(0x55)];
        assert!(small.iter().zip(Stream::CameraJitter.layout()).all(|(&x, &y)| overlap(x, y)));
        assert!(!overlap(Field::Tag(1), Field::Tag(2)));
        assert!(!overlap(Field::Tag(1 << 20), SAMPLE));
        assert!(overlap(Field::Tag((1 << 20) - 1), SAMPLE));
    }

    #[test]
    fn a_stream_is_its_key_with_the_tag_in_place() {
        let mut sun = Stream::Sun.rng(&[1, 2, 3, 4, 5, 6]);
        assert_eq!(sun.next_u64(), Rng::from_key(&[1, 2, 3, 4, 0x50d1_5c00, 5, 6]).next_u64());
        let mut jitter = Stream::CameraJitter.rng(&[9, 8, 7, 6]);
        assert_eq!(jitter.next_u64(), Rng::from_key(&[9, 8, 7, 6]).next_u64());
        assert_ne!(Stream::Lens.rng(&[9, 8, 7]).next_u64(), Stream::Shutter.rng(&[9, 8, 7]).next_u64());
    }

    /// No stream key is written outside this list: every `Rng::from_key` of
    /// the renderer's passes goes through [`Stream::rng`].
    #[test]
    fn every_pass_stream_is_in_the_list() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        for dir in ["render", "lightcut"] {
            let mut files = Vec::new();
            let mut stack = vec![src.join(dir)];
            while let Some(d) = stack.pop() {
                for entry in std::fs::read_dir(d).unwrap() {
                    let path = entry.unwrap().path();
                    if path.is_dir() {
                        stack.push(path);
                    } else if path.extension().is_some_and(|e| e == "rs") && !path.ends_with("tests.rs") {
                        files.push(path);
                    }
                }
            }
            assert!(files.len() > 5, "found the files of src/{dir}");
            for file in files {
                let text = std::fs::read_to_string(&file).unwrap();
                let code = text.split("#[cfg(test)]").next().unwrap();
                assert!(!code.contains("Rng::from_key("), "{} keys a stream outside the list", file.display());
                assert!(!code.contains("_STREAM: u64"), "{} tags a stream outside the list", file.display());
            }
        }
    }
}
