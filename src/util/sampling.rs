//! Deterministic random numbers: every sample is a pure function of a seed
//! and integer coordinates (pixel, sample index, ...), so images do not depend
//! on thread count or tile order.

/// SplitMix64's finaliser: a bijective 64-bit mix (Steele et al. 2014).
#[must_use]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A small counter-based generator (SplitMix64). Streams made from different
/// keys are independent for rendering purposes.
#[derive(Debug, Clone)]
pub struct Rng {
    state: u64,
}

impl Rng {
    /// A stream keyed by a list of integers (e.g. seed, pixel x, pixel y, sample).
    #[must_use]
    pub fn from_key(key: &[u64]) -> Self {
        let mut state = 0x6a09_e667_f3bc_c909u64;
        for &k in key {
            state = mix64(state ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        }
        Self { state }
    }

    #[must_use]
    pub fn seeded(seed: u64) -> Self {
        Self::from_key(&[seed])
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.state)
    }

    /// Uniform in [0, 1): the top 24 bits, so the result is exactly
    /// representable and never rounds up to 1.0.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in [0, 1) with 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0)
    }

    /// Uniform in [lo, hi).
    pub fn range_f32(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Uniform integer in [0, n); n > 0.
    pub fn below(&mut self, n: u64) -> u64 {
        debug_assert!(n > 0);
        // Lemire's multiply-shift; the tiny bias is irrelevant here.
        ((u128::from(self.next_u64()) * u128::from(n)) >> 64) as u64
    }
}

/// Point `i` of `n` of a Hammersley set in the unit square ((i + 1/2) / n,
/// the base-2 radical inverse of i), shifted by `shift` modulo 1 (a
/// Cranley-Patterson rotation: a pixel's own shift keeps the set
/// stratified in each pixel without a pattern repeating across pixels).
/// Every power-of-two stratum of [0, 1)^2 of area 1/n holds one point when
/// n is a power of two.
#[must_use]
pub fn hammersley(i: u32, n: u32, shift: [f32; 2]) -> [f32; 2] {
    let u = (f64::from(i) + 0.5) / f64::from(n.max(1));
    let v = f64::from(i.reverse_bits()) * (1.0 / 4_294_967_296.0);
    [rotated(u, shift[0]), rotated(v, shift[1])]
}

/// `x + shift` modulo 1 (a Cranley-Patterson rotation of `x`), in [0, 1)
/// as f32.
fn rotated(x: f64, shift: f32) -> f32 {
    let y = (x + f64::from(shift)).fract() as f32;
    // f64 -> f32 may round up to 1.0.
    if y >= 1.0 {
        0.0
    } else {
        y
    }
}

/// Which sample of which pixel a shading point belongs to, so that what it
/// draws is stratified over the pixel's samples (docs/design.md §10.8):
/// each draw keyed by `key` (a cut node, a triangle light) gets a
/// uniform shift that is a hash of `pixel` and `key` (a Cranley-Patterson
/// rotation, one per key), and sample `index` of the pixel's `count` takes
/// its stratum of the rotated set. Each sample's number is uniform whatever
/// its index, so every sample's estimate stays unbiased; the pixel's
/// samples together cover each key's distribution evenly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelSample {
    /// The pixel's key (a hash of the seed, the pixel and the bounce).
    pub pixel: u64,
    /// The sample's index among the pixel's `count` (taken modulo `count`).
    pub index: u32,
    /// The pixel's samples (at least 1).
    pub count: u32,
}

impl PixelSample {
    /// A point that is its pixel's only sample.
    pub const ALONE: Self = Self { pixel: 0, index: 0, count: 1 };

    /// The key's uniform shift in [0, 1)^2 at this pixel, 53 and 24 bits.
    #[inline(always)]
    fn shift(self, key: u64) -> (f64, f32) {
        let h = mix64(self.pixel ^ mix64(key));
        ((h >> 11) as f64 * (1.0 / 9_007_199_254_740_992.0), (h & 0xff_ffff) as f32 * (1.0 / 16_777_216.0))
    }

    /// A number in [0, 1) for `key` from the sample's own uniform `xi`:
    /// frac((index + xi) / count + r), r the key's shift. The pixel's
    /// `count` samples put one number in each stratum of the rotated grid.
    #[inline(always)]
    #[must_use]
    pub fn number(self, key: u64, xi: f64) -> f64 {
        let count = self.count.max(1);
        let u = (f64::from(self.index % count) + xi) / f64::from(count) + self.shift(key).0;
        (u - u.floor()).clamp(0.0, ONE_BELOW)
    }

    /// Number `n` of `key`'s sequence at this pixel, for a key that only
    /// some of the pixel's samples reach, each taking the next number (the
    /// uses of a cut the pixel keeps for one surface, docs/design.md
    /// §10.10): the base-2 radical inverse of `n` (van der Corput's
    /// sequence) rotated by the key's shift. Any first n numbers of the
    /// sequence leave no gap wider than 2 / n, whichever samples took
    /// them, where the strata of [`PixelSample::number`] fall wherever the
    /// samples' indices do; each number is uniform whatever `n` (the shift
    /// is).
    #[inline(always)]
    #[must_use]
    pub fn in_turn(self, key: u64, n: u32) -> f64 {
        let u = f64::from(n.reverse_bits()) * (1.0 / 4_294_967_296.0) + self.shift(key).0;
        (u - u.floor()).clamp(0.0, ONE_BELOW)
    }

    /// A point in [0, 1)^2 for `key`: point `index` of the pixel's `count`
    /// of a Hammersley set rotated by the key's shift ([`hammersley`]).
    #[inline(always)]
    #[must_use]
    pub fn point(self, key: u64) -> [f32; 2] {
        let count = self.count.max(1);
        let (a, b) = self.shift(key);
        hammersley(self.index % count, count, [a as f32, b])
    }
}

/// The largest f64 below 1.
pub const ONE_BELOW: f64 = 1.0 - 1.0 / 9_007_199_254_740_992.0;

/// Roberts' R_6 generators: alpha_j = phi^-(j+1), phi the positive root of
/// x^7 = x + 1 (Roberts 2018, "The unreasonable effectiveness of
/// quasirandom sequences").
const R6: [f64; 6] = [
    0.898_653_712_628_699_2,
    0.807_578_495_221_344_7,
    0.725_733_412_969_759_6,
    0.652_183_025_943_971_5,
    0.586_086_697_577_969_2,
    0.526_688_986_700_735_6,
];

/// Point `i` of a Kronecker sequence in [0, 1)^6, (shift + i alpha) modulo
/// 1 with Roberts' R_6 generators: any n consecutive indices spread over
/// the cube with low discrepancy in every dimension and pair of them, so
/// that the n samples of a pixel, each taking point i = its index, cover
/// a shading point's directions evenly; the pixel's own random `shift`
/// (a Cranley-Patterson rotation) keeps every point uniform, the
/// estimate unbiased, and no pattern repeating across pixels.
#[must_use]
pub fn kronecker6(i: u32, shift: [f32; 6]) -> [f32; 6] {
    std::array::from_fn(|j| rotated(f64::from(i) * R6[j], shift[j]))
}

/// Time `i` of a pixel's camera samples in the shutter: the base-3 radical
/// inverse of i (Halton's second dimension, so that it does not line up
/// with the lens's base-2 Hammersley points of the same index), shifted by
/// `shift` modulo 1. Any n consecutive indices from 0 spread over [0, 1)
/// with at most a few strata of 1/n empty; a power of 3 fills each once.
#[must_use]
pub fn shutter_time(i: u32, shift: f32) -> f32 {
    let (mut i, mut inverse, mut scale) = (u64::from(i), 0.0f64, 1.0f64 / 3.0);
    while i > 0 {
        inverse += (i % 3) as f64 * scale;
        i /= 3;
        scale /= 3.0;
    }
    rotated(inverse, shift)
}

/// Shirley and Chiu's concentric map of the unit square onto the unit disc
/// (area-preserving, so uniform points stay uniform and strata stay compact).
#[must_use]
pub fn concentric_disc(u: [f32; 2]) -> [f32; 2] {
    let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0];
    }
    let quarter = std::f32::consts::FRAC_PI_4;
    let (r, theta) = if a.abs() > b.abs() { (a, quarter * (b / a)) } else { (b, 2.0 * quarter - quarter * (a / b)) };
    [r * theta.cos(), r * theta.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Any first n numbers of a key's sequence, shifted back, leave no gap
    /// wider than 2 / n on the circle [0, 1) (n / N, the strata of
    /// `number` taken by n consecutive indices of N, leave one of 1 - n / N);
    /// and number n is uniform over pixels for every n (64 bins within 5
    /// standard errors).
    #[test]
    fn a_sequence_taken_in_turn_spreads_and_each_number_is_uniform() {
        const PIXELS: u64 = 65_536;
        const BINS: usize = 64;
        const TAKEN: u32 = 24;
        let mut histograms = vec![[0u64; BINS]; TAKEN as usize];
        for pixel in 0..PIXELS {
            let sample = PixelSample { pixel: mix64(pixel), index: 0, count: 256 };
            let shift = sample.in_turn(7, 0);
            let mut points = Vec::new();
            for n in 0..TAKEN {
                let u = sample.in_turn(7, n);
                assert!((0.0..1.0).contains(&u), "{u}");
                histograms[n as usize][(u * BINS as f64) as usize] += 1;
                if pixel < 64 {
                    points.push((u - shift).rem_euclid(1.0));
                    points.sort_by(f64::total_cmp);
                    let gaps =
                        points.windows(2).map(|w| w[1] - w[0]).chain([1.0 - points[points.len() - 1] + points[0]]);
                    let widest = gaps.fold(0.0, f64::max);
                    let k = points.len() as f64;
                    assert!(widest <= 2.0 / k + 1e-12, "pixel {pixel}: the first {k} leave a gap of {widest}");
                }
            }
        }
        let expected = PIXELS as f64 / BINS as f64;
        for (n, histogram) in histograms.iter().enumerate() {
            for (bin, &count) in histogram.iter().enumerate() {
                let deviation = (count as f64 - expected) / expected.sqrt();
                assert!(deviation.abs() < 5.0, "number {n}, bin {bin}: {count} against {expected}");
            }
        }
    }

    #[test]
    fn hammersley_points_fill_every_stratum_once_and_map_into_the_disc() {
        for shift in [[0.0, 0.0], [0.37, 0.91]] {
            // 64 points: one in each cell of an 8 x 8 grid (a (0, 6, 2)-net
            // shifted keeps one point per elementary interval of 1/64 in
            // each 1 x 1/64 column, and 8 x 8 holds as well for the base set).
            let mut columns = [0u32; 64];
            for i in 0..64 {
                let [u, v] = hammersley(i, 64, shift);
                assert!((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v));
                columns[(u * 64.0) as usize] += 1;
                let [x, y] = concentric_disc([u, v]);
                assert!(x * x + y * y <= 1.0 + 1e-6);
            }
            assert!(columns.iter().all(|&c| c == 1), "{columns:?}");
        }
        let mut cells = [0u32; 64];
        for i in 0..64 {
            let [u, v] = hammersley(i, 64, [0.0, 0.0]);
            cells[(u * 8.0) as usize * 8 + (v * 8.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
        // The map preserves area: a quarter of uniform points fall within
        // radius 1/2.
        let mut rng = Rng::seeded(3);
        let inside = (0..40_000)
            .filter(|_| {
                let [x, y] = concentric_disc([rng.next_f32(), rng.next_f32()]);
                x * x + y * y < 0.25
            })
            .count();
        assert!((9_600..10_400).contains(&inside), "{inside}");
    }

    #[test]
    fn unit_floats_stay_in_range_and_look_uniform() {
        let mut rng = Rng::seeded(7);
        let mut buckets = [0u32; 10];
        for _ in 0..100_000 {
            let x = rng.next_f32();
            assert!((0.0..1.0).contains(&x));
            buckets[(x * 10.0) as usize] += 1;
        }
        for b in buckets {
            assert!((9_500..10_500).contains(&b), "bucket count {b}");
        }
    }

    #[test]
    fn keys_give_reproducible_distinct_streams() {
        let a = Rng::from_key(&[1, 2, 3]).next_u64();
        assert_eq!(a, Rng::from_key(&[1, 2, 3]).next_u64());
        assert_ne!(a, Rng::from_key(&[1, 3, 2]).next_u64());
        assert_ne!(a, Rng::from_key(&[1, 2]).next_u64());
    }

    #[test]
    fn shutter_times_of_a_power_of_three_fill_every_stratum_once() {
        for n in [3u32, 9, 27, 81, 243] {
            assert!((0..n).all(|i| (0.0..1.0).contains(&shutter_time(i, 0.37))));
            // Unshifted, the times are k / n for k = 0..n, each once: a
            // shift moves them all by the same amount, modulo 1.
            let mut shifted: Vec<f32> = (0..n).map(|i| (shutter_time(i, 0.37) - 0.37).rem_euclid(1.0)).collect();
            shifted.sort_by(f32::total_cmp);
            for (k, t) in shifted.iter().enumerate() {
                assert!((t * n as f32 - k as f32).abs() < 1e-3, "n {n}: point {k} at {t}");
            }
        }
        assert_eq!(shutter_time(1, 0.0), 1.0 / 3.0);
        assert_eq!(shutter_time(4, 0.0), 1.0 / 3.0 + 1.0 / 9.0);
    }
}
