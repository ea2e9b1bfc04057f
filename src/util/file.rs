//! Reading the files a scene names without trusting them: only regular
//! files (a FIFO would block forever, `/dev/zero` never ends, `/dev/urandom`
//! neither) and never more bytes than a stated limit.

use std::io::Read;
use std::path::Path;

/// The most bytes any one file a scene names may hold (4 GiB): larger than
/// any texture or buffer a production asset carries, small enough that a
/// file the limit lets through fits in this machine's memory.
pub const MAX_FILE_BYTES: u64 = 1 << 32;

/// Opens `path` for reading when it is a regular file (symbolic links
/// followed); anything else is refused before it is opened, since opening a
/// FIFO blocks until a writer comes.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    let not_regular = || std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a regular file");
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path)?;
    // Replaced between the two looks: still refused.
    if !file.metadata()?.is_file() {
        return Err(not_regular());
    }
    Ok(file)
}

/// The bytes of the regular file `path`, refused when it holds more than
/// `limit` bytes (checked before reading, and while reading, for a file that
/// grows).
pub fn read_regular(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let file = open_regular(path)?;
    let length = file.metadata()?.len();
    let too_big = |length: u64| {
        std::io::Error::new(std::io::ErrorKind::InvalidData, format!("holds {length} bytes, more than {limit}"))
    };
    if length > limit {
        return Err(too_big(length));
    }
    let mut bytes = Vec::with_capacity(length as usize);
    file.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(too_big(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The first `count` bytes of the regular file `path` (a glTF buffer reads
/// no more than its `byteLength`); an error when it holds fewer.
pub fn read_regular_prefix(path: &Path, count: u64) -> std::io::Result<Vec<u8>> {
    let file = open_regular(path)?;
    let length = file.metadata()?.len();
    if length < count {
        return Err(std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            format!("holds {length} bytes, fewer than the {count} declared"),
        ));
    }
    let mut bytes = Vec::with_capacity(count as usize);
    file.take(count).read_to_end(&mut bytes)?;
    if (bytes.len() as u64) < count {
        return Err(std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "ended before its declared length"));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_fifos_and_directories_are_refused_and_limits_hold() {
        let dir = tempfile::tempdir().unwrap();
        for path in ["/dev/zero", "/dev/urandom"] {
            let e = read_regular(Path::new(path), 16).unwrap_err();
            assert_eq!(e.to_string(), "not a regular file", "{path}");
        }
        assert!(read_regular(dir.path(), 16).is_err());
        let fifo = dir.path().join("x.gltf");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success());
        // Would block forever if it were opened.
        assert_eq!(read_regular(&fifo, 16).unwrap_err().to_string(), "not a regular file");
        let file = dir.path().join("f");
        std::fs::write(&file, [7u8; 100]).unwrap();
        assert_eq!(read_regular(&file, 100).unwrap().len(), 100);
        assert!(read_regular(&file, 99).unwrap_err().to_string().contains("more than 99"));
        assert_eq!(read_regular_prefix(&file, 10).unwrap(), [7u8; 10]);
        assert!(read_regular_prefix(&file, 101).is_err());
    }
}
