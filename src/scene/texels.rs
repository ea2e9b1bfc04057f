//! Texels as compactly as they can be kept exactly (docs/design.md §5.3,
//! "Textures in memory"): 8-bit codes read through a table, half floats,
//! or f32. An image reader keeps an 8-bit image as its codes from the
//! start, so a texture never holds (nor is decoded through) three f32 a
//! texel it does not need; what a lookup reads is the same f32 either way.

use glam::Vec3;

/// Linear RGB texels, each kept in the most compact form that holds its
/// value exactly.
#[derive(Debug, Clone, PartialEq)]
pub enum Texels {
    /// 8-bit codes, each channel read through `table` (an encoding's
    /// decoding of k/255: sRGB's, or linear's): 3 bytes a texel.
    Codes { codes: Vec<[u8; 3]>, table: &'static [f32; 256] },
    /// Half floats (an OpenEXR's half channels): 6 bytes a texel.
    Half(Vec<[half::f16; 3]>),
    /// Anything else (16-bit and float data, generated texels): 12 bytes.
    Float(Vec<Vec3>),
}

/// How an image's colour values are encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// sRGB-encoded colours (base colour, emission), decoded to linear.
    Srgb,
    /// Linear data (glTF's metallic-roughness texture), read as is.
    Linear,
}

impl Encoding {
    /// A value k / max of the image decoded to linear.
    #[must_use]
    pub fn decode(self, value: f32) -> f32 {
        match self {
            Self::Srgb => crate::util::color::srgb_to_linear(value),
            Self::Linear => value,
        }
    }
}

/// The decoding of 8-bit code k in `encoding`, computed as the image
/// readers decode a code (k as f32 / 255, then decoded), so that a code
/// stands for exactly the f32 a reader of f32 texels would have made.
#[must_use]
pub fn table(encoding: Encoding) -> &'static [f32; 256] {
    static TABLES: std::sync::OnceLock<[[f32; 256]; 2]> = std::sync::OnceLock::new();
    let tables = TABLES.get_or_init(|| {
        let code = |k: usize| f32::from(k as u8) / 255.0;
        [std::array::from_fn(|k| crate::util::color::srgb_to_linear(code(k))), std::array::from_fn(code)]
    });
    match encoding {
        Encoding::Srgb => &tables[0],
        Encoding::Linear => &tables[1],
    }
}

/// The code whose value in `table` is `v` exactly, if there is one.
fn exact_code(table: &[f32; 256], v: f32) -> Option<u8> {
    let k = table.partition_point(|&t| t < v);
    (k < 256 && table[k].to_bits() == v.to_bits()).then_some(k as u8)
}

/// The codes in `encoding` of `texel(0)`, ..., `texel(count - 1)`, if
/// every channel of each is a code's value exactly.
fn exact_codes(encoding: Encoding, count: usize, texel: impl Fn(usize) -> Vec3) -> Option<Texels> {
    let table = table(encoding);
    let code = |v: f32| exact_code(table, v);
    let codes: Option<Vec<[u8; 3]>> =
        (0..count).map(texel).map(|t| Some([code(t.x)?, code(t.y)?, code(t.z)?])).collect();
    Some(Texels::Codes { codes: codes?, table })
}

/// The code whose value in `table` is nearest `v`.
fn nearest_code(table: &[f32; 256], v: f32) -> u8 {
    let k = table.partition_point(|&t| t < v).min(255);
    // The code below may be nearer (the table increases).
    if k > 0 && (v - table[k - 1]).abs() <= (table[k] - v).abs() {
        (k - 1) as u8
    } else {
        k as u8
    }
}

impl Texels {
    /// 8-bit codes decoded as `encoding` says.
    #[must_use]
    pub fn codes(codes: Vec<[u8; 3]>, encoding: Encoding) -> Self {
        Self::Codes { codes, table: table(encoding) }
    }

    /// The most compact exact form of `texels`.
    #[must_use]
    pub fn compact(texels: Vec<Vec3>) -> Self {
        for encoding in [Encoding::Srgb, Encoding::Linear] {
            if let Some(codes) = exact_codes(encoding, texels.len(), |k| texels[k]) {
                return codes;
            }
        }
        let half = |v: f32| -> Option<half::f16> {
            let h = half::f16::from_f32(v);
            (h.to_f32().to_bits() == v.to_bits()).then_some(h)
        };
        let halves: Option<Vec<[half::f16; 3]>> =
            texels.iter().map(|t| Some([half(t.x)?, half(t.y)?, half(t.z)?])).collect();
        match halves {
            Some(halves) => Self::Half(halves),
            None => Self::Float(texels),
        }
    }

    /// The encoding of its 8-bit codes (None for floats).
    #[must_use]
    pub fn encoding(&self) -> Option<Encoding> {
        match self {
            Self::Codes { table, .. } if std::ptr::eq(*table, table_linear()) => Some(Encoding::Linear),
            Self::Codes { .. } => Some(Encoding::Srgb),
            _ => None,
        }
    }

    /// The texels `texel(0)`, ..., `texel(count - 1)` in their most
    /// compact exact form, made without holding them as f32 when they are
    /// all codes in `codes_in` (a texture made from an 8-bit image by a map
    /// that keeps its codes, such as a channel chosen or a factor of 1):
    /// what decoding an image to codes saves is not spent again here.
    #[must_use]
    pub fn collect(count: usize, codes_in: Option<Encoding>, texel: impl Fn(usize) -> Vec3) -> Self {
        if let Some(codes) = codes_in.and_then(|encoding| exact_codes(encoding, count, &texel)) {
            return codes;
        }
        Self::compact((0..count).map(texel).collect())
    }

    /// `texels` (a coarser MIP level of `self`) in `self`'s encoding,
    /// each value rounded to the nearest one it can hold: a level of 8-bit
    /// codes stays 3 bytes a texel, as a GPU keeps an 8-bit texture's MIP
    /// levels.
    #[must_use]
    pub fn encoded_like(&self, texels: Vec<Vec3>) -> Self {
        match self {
            Self::Codes { table, .. } => {
                let code = |v: f32| nearest_code(table, v);
                let codes = texels.iter().map(|t| [code(t.x), code(t.y), code(t.z)]).collect();
                Self::Codes { codes, table }
            }
            Self::Half(_) => Self::Half(texels.iter().map(|t| t.to_array().map(half::f16::from_f32)).collect()),
            Self::Float(_) => Self::Float(texels),
        }
    }

    /// The same texels with their colours decoded from sRGB: what a
    /// texture read as linear data reads when a material says it is sRGB
    /// encoded. 8-bit codes only change their table, which decodes the
    /// same code through sRGB (the readers' own arithmetic, so the values
    /// are those of decoding the image as sRGB in the first place).
    #[must_use]
    pub fn decoded_from_srgb(&self) -> Self {
        let decode = |t: &Vec3| -> Vec3 { t.to_array().map(crate::util::color::srgb_to_linear).into() };
        match self {
            Self::Codes { codes, table: linear } if std::ptr::eq(*linear, table_linear()) => {
                Self::codes(codes.clone(), Encoding::Srgb)
            }
            _ => Self::Float((0..self.len()).map(|k| decode(&self.get(k))).collect()),
        }
    }

    /// The linear value of texel `index`.
    #[must_use]
    pub fn get(&self, index: usize) -> Vec3 {
        match self {
            Self::Codes { codes, table } => {
                let [r, g, b] = codes[index];
                Vec3::new(table[r as usize], table[g as usize], table[b as usize])
            }
            Self::Half(halves) => {
                let [r, g, b] = halves[index];
                Vec3::new(r.to_f32(), g.to_f32(), b.to_f32())
            }
            Self::Float(texels) => texels[index],
        }
    }

    /// How many texels.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Codes { codes, .. } => codes.len(),
            Self::Half(halves) => halves.len(),
            Self::Float(texels) => texels.len(),
        }
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The texels as f32 (an environment map's radiance).
    #[must_use]
    pub fn into_floats(self) -> Vec<Vec3> {
        match self {
            Self::Float(texels) => texels,
            other => (0..other.len()).map(|k| other.get(k)).collect(),
        }
    }

    /// 3 for 8-bit codes, 6 for half floats, 12 for f32.
    #[must_use]
    pub fn bytes_per_texel(&self) -> usize {
        match self {
            Self::Codes { .. } => 3,
            Self::Half(_) => 6,
            Self::Float(_) => 12,
        }
    }
}

fn table_linear() -> &'static [f32; 256] {
    table(Encoding::Linear)
}

/// An image's alpha channel (linear coverage, 0 to 1): 8-bit codes (k /
/// 255) or f32.
#[derive(Debug, Clone, PartialEq)]
pub enum Coverage {
    Codes(Vec<u8>),
    Float(Vec<f32>),
}

impl Coverage {
    /// The coverage of texel `index`.
    #[must_use]
    pub fn get(&self, index: usize) -> f32 {
        match self {
            Self::Codes(codes) => table_linear()[codes[index] as usize],
            Self::Float(values) => values[index],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texels_are_kept_in_the_most_compact_exact_form() {
        let srgb = |k: u8| crate::util::color::srgb_to_linear(f32::from(k) / 255.0);
        let cases: [(Vec<Vec3>, usize); 4] = [
            // An 8-bit sRGB image as the readers decode it.
            ((0..=255u8).map(|k| Vec3::new(srgb(k), srgb(255 - k), srgb(k / 2))).collect(), 3),
            // 8-bit linear data (a metallic-roughness map).
            ((0..=255u8).map(|k| Vec3::splat(f32::from(k) / 255.0)).collect(), 3),
            // Half floats (an OpenEXR's), beyond 1.
            ((0..256).map(|k| Vec3::new(k as f32 * 0.25, 1000.0, 0.5)).collect(), 6),
            // Anything else.
            ((0..256).map(|k| Vec3::splat(k as f32 * 0.123_456_7)).collect(), 12),
        ];
        for (texels, bytes) in cases {
            let compact = Texels::compact(texels.clone());
            assert_eq!(compact.bytes_per_texel(), bytes);
            assert_eq!(compact.len(), texels.len());
            for (i, t) in texels.iter().enumerate() {
                assert_eq!(compact.get(i).to_array().map(f32::to_bits), t.to_array().map(f32::to_bits));
            }
        }
    }

    #[test]
    fn a_map_that_keeps_the_codes_keeps_them_and_any_other_falls_back_to_the_exact_form() {
        let codes: Vec<[u8; 3]> = (0..=255u8).map(|k| [k, 255 - k, k / 3]).collect();
        let image = Texels::codes(codes.clone(), Encoding::Linear);
        assert_eq!(image.encoding(), Some(Encoding::Linear));
        // A channel chosen (green into all three): still codes.
        let green = Texels::collect(256, image.encoding(), |k| Vec3::splat(image.get(k).y));
        assert_eq!(green, Texels::codes(codes.iter().map(|c| [c[1]; 3]).collect(), Encoding::Linear));
        // Times 0.3: no code holds most of those values.
        let scaled = Texels::collect(256, image.encoding(), |k| image.get(k) * 0.3);
        assert_eq!(scaled.bytes_per_texel(), 12);
        for k in 0..256 {
            assert_eq!(scaled.get(k), image.get(k) * 0.3);
        }
    }

    #[test]
    fn codes_read_as_srgb_are_the_codes_decoded_from_srgb() {
        let codes: Vec<[u8; 3]> = (0..=255u8).map(|k| [k, 255 - k, 7]).collect();
        let linear = Texels::codes(codes.clone(), Encoding::Linear);
        let srgb = linear.decoded_from_srgb();
        assert_eq!(srgb, Texels::codes(codes, Encoding::Srgb));
        assert_eq!(srgb.encoding(), Some(Encoding::Srgb));
        for k in 0..256 {
            let expected = linear.get(k).to_array().map(crate::util::color::srgb_to_linear);
            assert_eq!(srgb.get(k).to_array().map(f32::to_bits), expected.map(f32::to_bits));
        }
        // Floats are decoded value by value.
        let floats = Texels::Float(vec![Vec3::new(0.5, 0.25, 1.0)]);
        assert_eq!(
            floats.decoded_from_srgb().get(0),
            Vec3::new(0.5, 0.25, 1.0).to_array().map(crate::util::color::srgb_to_linear).into()
        );
    }
}
