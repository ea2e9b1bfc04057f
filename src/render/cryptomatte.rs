//! Cryptomatte (Psyop's specification, v1.1.0): ID mattes for every object
//! and material. A pixel's camera samples vote for the names of what they
//! first hit; the IDs with the largest coverage are written in rank order,
//! two (ID, coverage) pairs per RGBA layer, `{type}00` to `{type}02` (six
//! ranks). IDs are MurmurHash3_x86_32 of the name (seed 0), converted to a
//! float with the exponent clamped to [1, 254] so that no ID is a NaN, an
//! Inf or a denormal. The header names each type's key, hash, conversion and
//! manifest (name to ID, as 8 hex digits of the float's bits).

use std::collections::BTreeMap;

/// Ranks written per type: the specification's suggested default (three
/// layers of two ranks each).
pub const RANKS: usize = 6;

/// The two Cryptomatte types the renderer writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CryptoType {
    /// Mattes per object: a shape (its `name`, or `shapes[i]`), an emitter,
    /// or a glTF node.
    Object,
    /// Mattes per material name.
    Material,
}

impl CryptoType {
    pub const ALL: [Self; 2] = [Self::Object, Self::Material];

    /// The type's name, which is also its layers' prefix.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Object => "CryptoObject",
            Self::Material => "CryptoMaterial",
        }
    }

    /// The channel names of its ranks, in rank order: `{type}00.R` (ID of
    /// rank 0), `.G` (its coverage), `.B` (ID of rank 1), `.A`, then `01`, `02`.
    #[must_use]
    pub fn channels(self) -> Vec<String> {
        (0..RANKS / 2)
            .flat_map(|layer| ["R", "G", "B", "A"].map(move |c| format!("{}{layer:02}.{c}", self.name())))
            .collect()
    }

    /// The metadata key: the first 7 hex digits of the hash of the type's
    /// name (the specification's suggestion, as Blender and Arnold do).
    #[must_use]
    pub fn key(self) -> String {
        format!("{:08x}", murmur3_32(self.name().as_bytes(), 0))[..7].to_string()
    }

    /// The header attributes for the type: name, hash, conversion and
    /// the manifest of `names` (each name once).
    #[must_use]
    pub fn header(self, names: &[String]) -> Vec<(String, String)> {
        let key = self.key();
        let manifest: BTreeMap<&str, String> =
            names.iter().map(|n| (n.as_str(), format!("{:08x}", id_of(n).to_bits()))).collect();
        let manifest = serde_json::to_string(&manifest).expect("a map of strings serialises");
        [
            ("name", self.name().to_string()),
            ("hash", "MurmurHash3_32".to_string()),
            ("conversion", "uint32_to_float32".to_string()),
            ("manifest", manifest),
        ]
        .into_iter()
        .map(|(field, value)| (format!("cryptomatte/{key}/{field}"), value))
        .collect()
    }
}

/// MurmurHash3_x86_32 (Austin Appleby's public-domain reference).
#[must_use]
pub fn murmur3_32(data: &[u8], seed: u32) -> u32 {
    const C1: u32 = 0xcc9e_2d51;
    const C2: u32 = 0x1b87_3593;
    let mut h = seed;
    let mut blocks = data.chunks_exact(4);
    for block in &mut blocks {
        let mut k = u32::from_le_bytes([block[0], block[1], block[2], block[3]]);
        k = k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
        h ^= k;
        h = h.rotate_left(13).wrapping_mul(5).wrapping_add(0xe654_6b64);
    }
    let tail = blocks.remainder();
    if !tail.is_empty() {
        let mut k = 0u32;
        for (i, &byte) in tail.iter().enumerate() {
            k |= u32::from(byte) << (8 * i);
        }
        h ^= k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
    }
    h ^= data.len() as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// The specification's `uint32_to_float32`: the hash's bits as a float,
/// with the exponent clamped to [1, 254].
#[must_use]
pub fn hash_to_float(hash: u32) -> f32 {
    let mantissa = hash & ((1 << 23) - 1);
    let exponent = ((hash >> 23) & 0xff).clamp(1, 254);
    f32::from_bits((hash & (1 << 31)) | (exponent << 23) | mantissa)
}

/// A name's ID as the pixels hold it.
#[must_use]
pub fn id_of(name: &str) -> f32 {
    hash_to_float(murmur3_32(name.as_bytes(), 0))
}

/// One pixel's votes: each ID's summed sample weight.
#[derive(Debug, Clone, Default)]
pub struct Coverage {
    votes: Vec<(f32, f64)>,
}

impl Coverage {
    pub fn clear(&mut self) {
        self.votes.clear();
    }

    /// A camera sample of weight `weight` whose first hit is named by `id`.
    pub fn add(&mut self, id: f32, weight: f64) {
        match self.votes.iter_mut().find(|(v, _)| v.to_bits() == id.to_bits()) {
            Some((_, w)) => *w += weight,
            None => self.votes.push((id, weight)),
        }
    }

    /// The first [`RANKS`] (ID, coverage) pairs, largest coverage first
    /// (ties: the smaller ID bits first, so the order is deterministic);
    /// ranks without an ID are (0, 0), as the specification's empty sample.
    #[must_use]
    pub fn ranks(&mut self) -> [(f32, f32); RANKS] {
        self.votes.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.to_bits().cmp(&b.0.to_bits())));
        let mut out = [(0.0, 0.0); RANKS];
        for (slot, (id, weight)) in out.iter_mut().zip(&self.votes) {
            *slot = (*id, *weight as f32);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn murmur3_matches_the_reference_vectors() {
        // Published test vectors of MurmurHash3_x86_32.
        assert_eq!(murmur3_32(b"", 0), 0);
        assert_eq!(murmur3_32(b"", 1), 0x514e_28b7);
        assert_eq!(murmur3_32(b"", 0xffff_ffff), 0x81f1_6f39);
        assert_eq!(murmur3_32(b"\xff\xff\xff\xff", 0), 0x7629_3b50);
        assert_eq!(murmur3_32(b"!Ce\x87", 0), 0xf55b_516b);
        assert_eq!(murmur3_32(b"!Ce", 0), 0x7e4a_8634);
        assert_eq!(murmur3_32(b"!C", 0), 0xa0f7_b07a);
        assert_eq!(murmur3_32(b"!", 0), 0x7266_1cf4);
        assert_eq!(murmur3_32(b"Hello, world!", 1234), 0xfaf6_cdb3);
        assert_eq!(murmur3_32(b"The quick brown fox jumps over the lazy dog", 0x9747_b28c), 0x2fa8_26cd);
    }

    #[test]
    fn ids_match_the_manifests_in_the_specification() {
        // The specification's example manifests: name -> the ID's float bits.
        for (name, hex) in [("bunny", "13851a76"), ("default", "42c9679f"), ("bunny_porcelain_mat", "b24b26d4")] {
            assert_eq!(format!("{:08x}", id_of(name).to_bits()), hex, "{name}");
        }
    }

    #[test]
    fn converted_ids_are_never_nan_inf_or_denormal() {
        for hash in [0, 1, 0x7f80_0000, 0x7fff_ffff, 0xff80_0001, 0x8000_0000, 0x0000_0001, u32::MAX] {
            let f = hash_to_float(hash);
            assert!(f.is_normal(), "{hash:#x} -> {f}");
        }
    }

    #[test]
    fn ranks_order_by_coverage_and_pad_with_zero() {
        let mut c = Coverage::default();
        let (a, b) = (id_of("a"), id_of("b"));
        c.add(a, 0.25);
        c.add(b, 0.5);
        c.add(a, 0.125);
        let ranks = c.ranks();
        assert_eq!(ranks[0], (b, 0.5));
        assert_eq!(ranks[1], (a, 0.375));
        assert!(ranks[2..].iter().all(|&r| r == (0.0, 0.0)));
        assert_eq!(CryptoType::Object.channels()[..2], ["CryptoObject00.R", "CryptoObject00.G"]);
        assert_eq!(CryptoType::Material.channels().len(), 12);
    }

    #[test]
    fn the_header_names_key_hash_conversion_and_manifest() {
        let header = CryptoType::Object.header(&["bunny".into(), "default".into()]);
        let key = CryptoType::Object.key();
        assert_eq!(key.len(), 7);
        let get = |f: &str| header.iter().find(|(k, _)| *k == format!("cryptomatte/{key}/{f}")).unwrap().1.clone();
        assert_eq!(get("name"), "CryptoObject");
        assert_eq!(get("hash"), "MurmurHash3_32");
        assert_eq!(get("conversion"), "uint32_to_float32");
        assert_eq!(get("manifest"), r#"{"bunny":"13851a76","default":"42c9679f"}"#);
    }
}
