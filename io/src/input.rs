//! Reading input files safely: only regular files (a FIFO would block forever, `/dev/zero` would
//! grow memory without bound), and never more bytes than a limit.

use std::io::{self, Read};
use std::path::Path;

/// Largest scene file read (a scene is a few kilobytes of TOML).
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// Largest mesh file read, in any format (an OBJ of about 40 million triangles; the LDI of such a
/// mesh needs more memory than the default budget of most machines anyway). A glTF file's
/// buffers in other files are each read up to this size too.
pub const MAX_MESH_BYTES: u64 = 4 << 30;

/// Largest OBJ file read: [`MAX_MESH_BYTES`].
pub const MAX_OBJ_BYTES: u64 = MAX_MESH_BYTES;

/// Refuses anything but a regular file (after following links), before opening it: opening a
/// FIFO for reading blocks until a writer appears.
pub fn check_regular(path: &Path) -> io::Result<u64> {
    let meta = std::fs::metadata(path)?;
    if meta.is_dir() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "is a folder, not a file",
        ));
    }
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a regular file (a device, FIFO or socket)",
        ));
    }
    Ok(meta.len())
}

/// The bytes of the regular file `path`, refused when it has more than `limit` bytes (checked
/// before reading), and never more than the size it had then: the memory budget counted that
/// size, so a file that grows while read, or one of `/proc`'s, whose size reads 0 whatever they
/// hold, is refused instead of read without bound.
pub fn read_limited(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let len = check_regular(path)?;
    let too_big = |n: u64| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("the file has {n} bytes, more than the {limit} bytes read at most"),
        )
    };
    if len > limit {
        return Err(too_big(len));
    }
    let file = std::fs::File::open(path)?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(len as usize)
        .map_err(|e| io::Error::new(io::ErrorKind::OutOfMemory, e.to_string()))?;
    file.take(len + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > len {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "the file holds more than the {len} bytes its size said when checked (it grew \
                 while read, or is a /proc-like file whose size is not its length)"
            ),
        ));
    }
    Ok(bytes)
}

/// [`read_limited`] as UTF-8 text.
pub fn read_text_limited(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read_limited(path, limit)?).map_err(|_| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_oversized_files_are_refused() {
        let e = read_limited(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let e = read_limited(Path::new("/"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("folder"), "{e}");
        let dir = std::env::temp_dir().join(format!("cs-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("big.txt");
        std::fs::write(&f, [b'x'; 100]).unwrap();
        // /proc files say 0 bytes and hold more: never read past the size checked.
        let e = read_limited(Path::new("/proc/self/status"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("more than the 0 bytes"), "{e}");
        assert!(read_limited(&f, 99).is_err());
        assert_eq!(read_limited(&f, 100).unwrap().len(), 100);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
