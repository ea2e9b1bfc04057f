//! A fast 64-bit content hash (SplitMix's mixer over 8-byte words): names a
//! file's bytes in cache keys and EXR attributes. Not cryptographic.

/// The hash of `bytes`.
#[must_use]
pub fn hash_bytes(bytes: &[u8]) -> u64 {
    bytes.chunks(8).fold(0x243f_6a88_85a3_08d3, |h, c| {
        let mut word = [0u8; 8];
        word[..c.len()].copy_from_slice(c);
        super::sampling::mix64(h ^ u64::from_le_bytes(word))
    })
}

/// The hash of a file's bytes.
pub fn hash_file(path: &std::path::Path) -> std::io::Result<u64> {
    Ok(hash_bytes(&std::fs::read(path)?))
}

/// One hash of several (a scene's input files, in order), as 16 hex digits.
#[must_use]
pub fn combined_hex(hashes: impl IntoIterator<Item = u64>) -> String {
    let bytes: Vec<u8> = hashes.into_iter().flat_map(u64::to_le_bytes).collect();
    format!("{:016x}", hash_bytes(&bytes))
}

#[cfg(test)]
mod tests {
    #[test]
    fn one_byte_changes_the_hash() {
        assert_ne!(super::hash_bytes(b"lightcuts"), super::hash_bytes(b"lightcutz"));
        assert_ne!(super::hash_bytes(b""), super::hash_bytes(b"\0"));
    }
}
