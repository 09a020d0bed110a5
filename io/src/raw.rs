//! Raw 3D textures: little-endian voxels, x fastest, then y, then z, with the dims and voxel type
//! the scene gives (`convshadow_common::pixel::texture3d` samples them).

use std::path::Path;

use convshadow_common::model::scene::VoxelType;
use convshadow_common::pixel::texture3d::{Texture3d, TextureError, voxel_count};

/// Loads a raw little-endian voxel file (x fastest, then y, then z); dims each in
/// [1, 2^24] and product ≤ 2^28, file size exactly product·bytes, f32 voxels finite with
/// magnitude ≤ 1e30, else an error naming the file and what was expected.
pub fn load_raw(path: &Path, dims: [u32; 3], voxel: VoxelType) -> Result<Texture3d, TextureError> {
    load_raw_cancellable(path, dims, voxel, None)
}

/// [`load_raw`], read and converted in chunks of 4 MiB, stopping with
/// [`TextureError::Interrupted`] when `cancel` is raised between two chunks.
pub fn load_raw_cancellable(
    path: &Path,
    dims: [u32; 3],
    voxel: VoxelType,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<Texture3d, TextureError> {
    let io = |source| TextureError::Io {
        path: path.to_path_buf(),
        source,
    };
    let n = voxel_count(dims).ok_or_else(|| TextureError::Dims {
        path: path.to_path_buf(),
        dims,
    })?;
    let expected = n * voxel.bytes();
    let size_error = |actual| TextureError::Size {
        path: path.to_path_buf(),
        dims,
        voxel,
        actual,
        expected,
    };
    // Check the size before reading, so a wrong multi-GB file is not read in.
    let actual = std::fs::metadata(path).map_err(io)?.len();
    if actual != expected {
        return Err(size_error(actual));
    }
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut voxels: Vec<f32> = Vec::new();
    voxels.try_reserve_exact(n as usize).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::OutOfMemory,
            format!("cannot allocate {n} voxels"),
        ))
    })?;
    // A multiple of every voxel size: no voxel straddles two chunks.
    const CHUNK: u64 = 4 << 20;
    let mut chunk = vec![0u8; CHUNK.min(expected) as usize];
    let mut left = expected;
    while left > 0 {
        if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
            return Err(TextureError::Interrupted {
                path: path.to_path_buf(),
            });
        }
        let bytes = &mut chunk[..CHUNK.min(left) as usize];
        std::io::Read::read_exact(&mut file, bytes).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                size_error(expected - left)
            } else {
                io(e)
            }
        })?;
        left -= bytes.len() as u64;
        match voxel {
            VoxelType::U8 => voxels.extend(bytes.iter().map(|&b| f32::from(b) / 255.0)),
            VoxelType::U16 => voxels.extend(
                bytes
                    .chunks_exact(2)
                    .map(|c| f32::from(u16::from_le_bytes([c[0], c[1]])) / 65535.0),
            ),
            VoxelType::F32 => voxels.extend(
                bytes
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            ),
        }
    }
    Texture3d::from_file_voxels(path, dims, voxels)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    /// A unique temp file path for this test process.
    fn temp_path(tag: &str) -> PathBuf {
        use std::sync::atomic::{AtomicU32, Ordering};
        static N: AtomicU32 = AtomicU32::new(0);
        let k = N.fetch_add(1, Ordering::Relaxed);
        std::env::temp_dir().join(format!(
            "convshadow-texture3d-{}-{}-{k}.raw",
            std::process::id(),
            tag
        ))
    }

    /// Writes a temp file, runs `f` on it, removes it.
    fn with_file<T>(tag: &str, bytes: &[u8], f: impl FnOnce(&Path) -> T) -> T {
        let p = temp_path(tag);
        std::fs::write(&p, bytes).unwrap();
        let r = f(&p);
        std::fs::remove_file(&p).unwrap();
        r
    }

    #[test]
    fn texture_loads_u8_u16_f32() {
        let dims = [3, 2, 2];
        let bytes: Vec<u8> = (0..12u8).map(|i| i * 20).collect();
        let t = with_file("u8", &bytes, |p| load_raw(p, dims, VoxelType::U8)).unwrap();
        assert_eq!(t.dims, dims);
        for (i, &v) in t.voxels.iter().enumerate() {
            assert_eq!(v, (i as f32 * 20.0) / 255.0);
        }
        assert_eq!(t.voxels[0], 0.0);
        let vals: Vec<u16> = (0..12).map(|i| [0, 1, 65535, 32768][i % 4]).collect();
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = with_file("u16", &bytes, |p| load_raw(p, dims, VoxelType::U16)).unwrap();
        assert_eq!(t.voxels[2], 1.0);
        assert_eq!(t.voxels[1], 1.0 / 65535.0);
        assert_eq!(t.voxels[3], 32768.0 / 65535.0);
        let vals: Vec<f32> = (0..12).map(|i| i as f32 * -0.25).collect();
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = with_file("f32", &bytes, |p| load_raw(p, dims, VoxelType::F32)).unwrap();
        assert_eq!(t.voxels, vals);
    }

    #[test]
    fn texture_load_errors() {
        let e = with_file("size", &[0u8; 1000], |p| {
            load_raw(p, [64, 64, 64], VoxelType::U16)
        })
        .unwrap_err();
        let msg = e.to_string();
        assert!(matches!(
            e,
            TextureError::Size {
                actual: 1000,
                expected: 524_288,
                ..
            }
        ));
        assert!(
            msg.contains("file is 1000 bytes, expected 64*64*64*2 = 524288 for u16"),
            "{msg}"
        );
        assert!(
            msg.contains("convshadow-texture3d-"),
            "names the file: {msg}"
        );

        let mut vals = [0.5f32; 8];
        vals[5] = f32::NAN;
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let e = with_file("nan", &bytes, |p| load_raw(p, [2, 2, 2], VoxelType::F32)).unwrap_err();
        assert!(
            matches!(
                e,
                TextureError::BadVoxel {
                    index: 5,
                    xyz: [1, 0, 1],
                    ..
                }
            ),
            "{e}"
        );
        assert!(
            e.to_string().contains("voxel 5 (x=1, y=0, z=1) is NaN"),
            "{e}"
        );
        for bad in [f32::INFINITY, f32::NEG_INFINITY, 1e31, -3e38] {
            let mut vals = vec![0.5f32; 8];
            vals[7] = bad;
            assert!(matches!(
                Texture3d::from_voxels([2, 2, 2], vals),
                Err(TextureError::BadVoxel { index: 7, .. })
            ));
        }
        for dims in [
            [0, 4, 4],
            [4, 0, 4],
            [4, 4, 0],
            [1 << 10, 1 << 10, 1 << 9],
            [1 << 25, 1, 1],
        ] {
            let e =
                with_file("dims", &[0u8; 64], |p| load_raw(p, dims, VoxelType::U8)).unwrap_err();
            assert!(matches!(e, TextureError::Dims { .. }), "{dims:?}: {e}");
            assert!(e.to_string().contains("convshadow-texture3d-"), "{e}");
        }
        // 2^28 voxels exactly is allowed by the dims check (the file is then too small).
        let e = with_file("max", &[0u8; 64], |p| {
            load_raw(p, [1 << 10, 1 << 10, 1 << 8], VoxelType::U8)
        })
        .unwrap_err();
        assert!(
            matches!(
                e,
                TextureError::Size {
                    expected: 268_435_456,
                    ..
                }
            ),
            "{e}"
        );
        let missing = temp_path("missing");
        let e = load_raw(&missing, [1, 1, 1], VoxelType::U8).unwrap_err();
        assert!(matches!(e, TextureError::Io { .. }));
        assert!(e.to_string().contains(&missing.display().to_string()));
        assert!(matches!(
            Texture3d::from_voxels([2, 2, 2], vec![0.0; 7]),
            Err(TextureError::Size { .. })
        ));
    }
}
