//! Raw 3D textures as a volumetric detail function: loading, validation and a trilinear sampler
//! that is bit-exact between the scalar and the 8-lane SIMD path (and portable to WGSL).
//!
//! Sampling convention (the OpenGL one): voxel `i` of an axis with `dim` voxels has its centre at
//! `u = (i + 0.5) / dim`; coordinates outside the centres clamp to the edge voxel. Per axis:
//! `g = u*dim - 0.5`, `g = g > 0 ? g : 0` (NaN → 0), `g = g < dim-1 ? g : dim-1`,
//! `i0 = floor(g)`, `f = g - i0`, `i1 = i0 < dim-1 ? i0 + 1 : dim-1`. Interpolation is
//! `a + f*(b - a)` along x (four rows), then y (two), then z, lower corner first; the same code
//! (generic over the lane type) serves both paths.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::lane::Lane;
use crate::noise::lerp;

/// Largest accepted voxel count (2^28, i.e. 1 GiB of f32 voxels).
pub const MAX_VOXELS: u64 = 1 << 28;
/// Largest accepted size of one axis (2^24, so every voxel coordinate is exact in f32).
pub const MAX_DIM: u32 = 1 << 24;
/// Largest accepted |value| of an f32 voxel, so that differences of voxels stay finite.
pub const MAX_ABS_VOXEL: f32 = 1e30;

/// Voxel format of a raw 3D texture file (little-endian, x fastest, then y, then z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VoxelType {
    /// Unsigned 8-bit, normalised by 1/255.
    U8,
    /// Unsigned 16-bit little-endian, normalised by 1/65535.
    U16,
    /// IEEE f32 little-endian, used as stored (must be finite).
    F32,
}

impl VoxelType {
    /// Bytes per voxel.
    pub fn bytes(self) -> u64 {
        match self {
            VoxelType::U8 => 1,
            VoxelType::U16 => 2,
            VoxelType::F32 => 4,
        }
    }
}

impl fmt::Display for VoxelType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            VoxelType::U8 => "u8",
            VoxelType::U16 => "u16",
            VoxelType::F32 => "f32",
        })
    }
}

/// Errors from loading or building a 3D texture; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// Loading was cancelled (a signal raised the cancel flag).
    #[error("{}: interrupted while loading the 3D texture", .path.display())]
    Interrupted {
        /// The file.
        path: PathBuf,
    },
    /// A light's pattern image cannot be used (unreadable, not an image, bad size or values).
    #[error("{}: {message}", .path.display())]
    Pattern {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// The file could not be read.
    #[error("{}: cannot read 3D texture: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Dimensions zero, an axis above [`MAX_DIM`], or more than [`MAX_VOXELS`] voxels.
    #[error(
        "{}: 3D texture dims {}x{}x{} invalid: expected each dim >= 1 and <= {MAX_DIM}, \
         and at most {MAX_VOXELS} voxels",
        .path.display(), .dims[0], .dims[1], .dims[2]
    )]
    Dims {
        /// The file.
        path: PathBuf,
        /// The dims given.
        dims: [u32; 3],
    },
    /// The file (or voxel buffer) size does not match the dims and voxel type.
    #[error(
        "{}: file is {actual} bytes, expected {}*{}*{}*{} = {expected} for {voxel}",
        .path.display(), .dims[0], .dims[1], .dims[2], .voxel.bytes()
    )]
    Size {
        /// The file.
        path: PathBuf,
        /// The dims given.
        dims: [u32; 3],
        /// The voxel type given.
        voxel: VoxelType,
        /// Size found.
        actual: u64,
        /// Size expected.
        expected: u64,
    },
    /// An f32 voxel is NaN, infinite, or larger in magnitude than [`MAX_ABS_VOXEL`].
    #[error(
        "{}: voxel {index} (x={}, y={}, z={}) is {value}, expected a finite f32 with \
         magnitude <= {MAX_ABS_VOXEL:e}",
        .path.display(), .xyz[0], .xyz[1], .xyz[2]
    )]
    BadVoxel {
        /// The file.
        path: PathBuf,
        /// Linear voxel index.
        index: u64,
        /// Voxel coordinates.
        xyz: [u32; 3],
        /// The offending value.
        value: f32,
    },
    /// A NIfTI file that is not NIfTI-1, is truncated, or has values the texture cannot hold.
    #[error("{}: {message}", .path.display())]
    Nifti {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// A 3D texture normalised to f32 in [0, 1] (u8/255, u16/65535; f32 as stored, must be finite).
///
/// `voxels.len()` must equal the product of `dims` (the constructors guarantee it; sampling a
/// hand-built inconsistent texture panics on the bounds check).
#[derive(Clone, PartialEq)]
pub struct Texture3d {
    /// Voxel counts along x, y, z.
    pub dims: [u32; 3],
    /// Voxels, x fastest, then y, then z.
    pub voxels: Vec<f32>,
}

impl fmt::Debug for Texture3d {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Texture3d")
            .field("dims", &self.dims)
            .field("voxels", &format_args!("[{} f32]", self.voxels.len()))
            .finish()
    }
}

/// Voxel count of valid dims, or `None`.
fn voxel_count(dims: [u32; 3]) -> Option<u64> {
    if dims.iter().any(|&d| d == 0 || d > MAX_DIM) {
        return None;
    }
    let n = dims.iter().map(|&d| u64::from(d)).product::<u64>();
    (n <= MAX_VOXELS).then_some(n)
}

/// Checks that every voxel is finite and within [`MAX_ABS_VOXEL`].
fn check_voxels(path: &Path, dims: [u32; 3], voxels: &[f32]) -> Result<(), TextureError> {
    match voxels
        .iter()
        .position(|v| v.is_nan() || v.abs() > MAX_ABS_VOXEL)
    {
        None => Ok(()),
        Some(i) => {
            let (dx, dy) = (dims[0] as usize, dims[1] as usize);
            Err(TextureError::BadVoxel {
                path: path.to_path_buf(),
                index: i as u64,
                xyz: [
                    (i % dx) as u32,
                    (i / dx % dy) as u32,
                    (i / (dx * dy)) as u32,
                ],
                value: voxels[i],
            })
        }
    }
}

/// One axis of the sampler: (lower index, upper index, fraction).
#[inline(always)]
fn axis<L: Lane>(u: L, dim: u32) -> (L::U, L::U, L) {
    let zero = L::splat(0.0);
    let hi = L::splat(dim.saturating_sub(1) as f32);
    let g = u * L::splat(dim as f32) - L::splat(0.5);
    let g = L::select(g.gt(zero), g, zero);
    let g = L::select(g.lt(hi), g, hi);
    let fl = g.floor();
    let f = g - fl;
    let fl1 = L::select(fl.lt(hi), fl + L::splat(1.0), hi);
    (fl.trunc_u32(), fl1.trunc_u32(), f)
}

impl Texture3d {
    /// Builds a texture from voxels in memory, with the same checks as [`Texture3d::load_raw`].
    pub fn from_voxels(dims: [u32; 3], voxels: Vec<f32>) -> Result<Texture3d, TextureError> {
        let path = Path::new("<in-memory texture>");
        let n = voxel_count(dims).ok_or_else(|| TextureError::Dims {
            path: path.to_path_buf(),
            dims,
        })?;
        if voxels.len() as u64 != n {
            return Err(TextureError::Size {
                path: path.to_path_buf(),
                dims,
                voxel: VoxelType::F32,
                actual: voxels.len() as u64 * 4,
                expected: n * 4,
            });
        }
        check_voxels(path, dims, &voxels)?;
        Ok(Texture3d { dims, voxels })
    }

    /// Loads a raw little-endian voxel file (x fastest, then y, then z); dims each in
    /// [1, 2^24] and product ≤ 2^28, file size exactly product·bytes, f32 voxels finite with
    /// magnitude ≤ 1e30, else an error naming the file and what was expected.
    pub fn load_raw(
        path: &Path,
        dims: [u32; 3],
        voxel: VoxelType,
    ) -> Result<Texture3d, TextureError> {
        Texture3d::load_raw_cancellable(path, dims, voxel, None)
    }

    /// [`Texture3d::load_raw`], read and converted in chunks of 4 MiB, stopping with
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
        check_voxels(path, dims, &voxels)?;
        Ok(Texture3d { dims, voxels })
    }

    /// Trilinear sample at normalised coordinates u in [0, 1]³ (voxel centres at (i+0.5)/dim),
    /// clamp-to-edge (NaN coordinates read the first voxel), per lane. Interpolation written as
    /// a + t*(b - a) in a fixed order.
    pub fn sample<L: Lane>(&self, p: [L; 3]) -> L {
        let [u, v, w] = p;
        let [dx, dy, dz] = self.dims;
        let (x0, x1, fx) = axis(u, dx);
        let (y0, y1, fy) = axis(v, dy);
        let (z0, z1, fz) = axis(w, dz);
        let sy = L::u_splat(dx);
        let sz = L::u_splat(dx.wrapping_mul(dy));
        let row = |y: L::U, z: L::U| L::u_add(L::u_mul(y, sy), L::u_mul(z, sz));
        let (r00, r10, r01, r11) = (row(y0, z0), row(y1, z0), row(y0, z1), row(y1, z1));
        let at = |x: L::U, r: L::U| L::gather(&self.voxels, L::u_add(x, r));
        let c00 = lerp(fx, at(x0, r00), at(x1, r00));
        let c10 = lerp(fx, at(x0, r10), at(x1, r10));
        let c01 = lerp(fx, at(x0, r01), at(x1, r01));
        let c11 = lerp(fx, at(x0, r11), at(x1, r11));
        let c0 = lerp(fy, c00, c10);
        let c1 = lerp(fy, c01, c11);
        lerp(fz, c0, c1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    use crate::hash::TestRng;

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

    /// Voxel value linear in the index: v(i,j,k) = c + a·(i, j, k).
    fn linear_texture(dims: [u32; 3], c: f32, a: [f32; 3]) -> Texture3d {
        let mut v = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    v.push(c + a[0] * i as f32 + a[1] * j as f32 + a[2] * k as f32);
                }
            }
        }
        Texture3d::from_voxels(dims, v).unwrap()
    }

    #[test]
    fn texture_loads_u8_u16_f32() {
        let dims = [3, 2, 2];
        let bytes: Vec<u8> = (0..12u8).map(|i| i * 20).collect();
        let t = with_file("u8", &bytes, |p| {
            Texture3d::load_raw(p, dims, VoxelType::U8)
        })
        .unwrap();
        assert_eq!(t.dims, dims);
        for (i, &v) in t.voxels.iter().enumerate() {
            assert_eq!(v, (i as f32 * 20.0) / 255.0);
        }
        assert_eq!(t.voxels[0], 0.0);
        let vals: Vec<u16> = (0..12).map(|i| [0, 1, 65535, 32768][i % 4]).collect();
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = with_file("u16", &bytes, |p| {
            Texture3d::load_raw(p, dims, VoxelType::U16)
        })
        .unwrap();
        assert_eq!(t.voxels[2], 1.0);
        assert_eq!(t.voxels[1], 1.0 / 65535.0);
        assert_eq!(t.voxels[3], 32768.0 / 65535.0);
        let vals: Vec<f32> = (0..12).map(|i| i as f32 * -0.25).collect();
        let bytes: Vec<u8> = vals.iter().flat_map(|v| v.to_le_bytes()).collect();
        let t = with_file("f32", &bytes, |p| {
            Texture3d::load_raw(p, dims, VoxelType::F32)
        })
        .unwrap();
        assert_eq!(t.voxels, vals);
    }

    #[test]
    fn texture_load_errors() {
        let e = with_file("size", &[0u8; 1000], |p| {
            Texture3d::load_raw(p, [64, 64, 64], VoxelType::U16)
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
        let e = with_file("nan", &bytes, |p| {
            Texture3d::load_raw(p, [2, 2, 2], VoxelType::F32)
        })
        .unwrap_err();
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
            let e = with_file("dims", &[0u8; 64], |p| {
                Texture3d::load_raw(p, dims, VoxelType::U8)
            })
            .unwrap_err();
            assert!(matches!(e, TextureError::Dims { .. }), "{dims:?}: {e}");
            assert!(e.to_string().contains("convshadow-texture3d-"), "{e}");
        }
        // 2^28 voxels exactly is allowed by the dims check (the file is then too small).
        let e = with_file("max", &[0u8; 64], |p| {
            Texture3d::load_raw(p, [1 << 10, 1 << 10, 1 << 8], VoxelType::U8)
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
        let e = Texture3d::load_raw(&missing, [1, 1, 1], VoxelType::U8).unwrap_err();
        assert!(matches!(e, TextureError::Io { .. }));
        assert!(e.to_string().contains(&missing.display().to_string()));
        assert!(matches!(
            Texture3d::from_voxels([2, 2, 2], vec![0.0; 7]),
            Err(TextureError::Size { .. })
        ));
    }

    /// Power-of-two dims, voxel values dyadic with few bits, and sample points whose g are
    /// dyadic with few bits: every operation of the sampler is exact, so the result must equal
    /// the linear function exactly (0 ulp).
    #[test]
    fn texture_linear_function_exact_on_dyadic_points() {
        let dims = [8, 16, 4];
        let (c, a) = (0.125f32, [1.0 / 64.0, 1.0 / 32.0, -1.0 / 128.0]);
        let t = linear_texture(dims, c, a);
        let mut rng = TestRng::new(11);
        for _ in 0..20_000 {
            // g in [0, dim-1] with 1/256 resolution; u = (g + 0.5)/dim exactly.
            let g: [f32; 3] = std::array::from_fn(|k| {
                let steps = (dims[k] - 1) * 256;
                (rng.next_u64() % u64::from(steps + 1)) as f32 / 256.0
            });
            let u: [f32; 3] = std::array::from_fn(|k| (g[k] + 0.5) / dims[k] as f32);
            let expect = c + a[0] * g[0] + a[1] * g[1] + a[2] * g[2];
            assert_eq!(t.sample(u), expect, "g = {g:?}");
        }
    }

    /// Arbitrary dims and points: error against the exact linear function (f64) is bounded by
    /// the rounding of g (|Δg_k| ≤ dim_k·2^-24 + 2^-24·(dim_k) ≤ 2·dim_k·2^-24, i.e. 2 ulp of
    /// dim_k) times the slope, plus the 7 lerps (each ≤ 1.5 ulp of a value ≤ 1 → 2^-24·1.5,
    /// with error propagation through the later lerps) — bounded by 16·2^-24 for values in
    /// [0, 1]. Measured errors are reported by the assertion message if exceeded.
    #[test]
    fn texture_linear_function_within_bound_at_interior_points() {
        let dims = [7, 13, 5];
        let (c, a) = (0.05f32, [0.03f32, 0.04, 0.07]);
        let t = linear_texture(dims, c, a);
        let mut rng = TestRng::new(12);
        let eps = f64::from(f32::EPSILON) / 2.0; // 2^-24
        let mut worst = 0.0f64;
        for _ in 0..100_000 {
            let u: [f32; 3] = std::array::from_fn(|k| {
                let d = dims[k] as f64;
                rng.float_range(0.5 / d, (d - 0.5) / d)
            });
            let g: [f64; 3] = std::array::from_fn(|k| f64::from(u[k]) * dims[k] as f64 - 0.5);
            let g: [f64; 3] = std::array::from_fn(|k| g[k].clamp(0.0, dims[k] as f64 - 1.0));
            // The linear function evaluated on exact f32 voxel values: v(i) itself has rounding
            // from building the texture in f32; account for it in the bound.
            let expect = f64::from(c)
                + f64::from(a[0]) * g[0]
                + f64::from(a[1]) * g[1]
                + f64::from(a[2]) * g[2];
            let bound: f64 = (0..3)
                .map(|k| f64::from(a[k]) * 2.0 * dims[k] as f64 * eps)
                .sum::<f64>()
                + 16.0 * eps;
            let err = (f64::from(t.sample(u)) - expect).abs();
            worst = worst.max(err / eps);
            assert!(err <= bound, "u = {u:?}: error {err:e} > bound {bound:e}");
        }
        assert!(worst > 0.0, "error bound test exercised no rounding");
    }

    #[test]
    fn texture_clamps_to_edge() {
        let dims = [4, 3, 2];
        let t = linear_texture(dims, 0.0, [0.1, 0.01, 0.001]);
        let v = |i: u32, j: u32, k: u32| t.voxels[(i + 4 * (j + 3 * k)) as usize];
        let outside = [-1e30f32, -5.0, -0.0, 0.0, 0.01, f32::NEG_INFINITY, f32::NAN];
        for &o in &outside {
            assert_eq!(t.sample([o, o, o]), v(0, 0, 0), "{o}");
            assert_eq!(t.sample([o, 0.5 / 3.0, 0.75]), v(0, 0, 1), "{o}");
        }
        for hi in [1.0f32, 1.0 - 0.4 / 4.0, 2.0, 1e30, f32::INFINITY] {
            assert_eq!(t.sample([hi, hi, hi]), v(3, 2, 1), "{hi}");
            assert_eq!(t.sample([hi, -hi, 0.25]), v(3, 0, 0), "{hi}");
        }
        // Exactly at centres: the voxel value.
        for k in 0..2 {
            for j in 0..3 {
                for i in 0..4 {
                    let u = [
                        (i as f32 + 0.5) / 4.0,
                        (j as f32 + 0.5) / 3.0,
                        (k as f32 + 0.5) / 2.0,
                    ];
                    assert_eq!(t.sample(u), v(i, j, k));
                }
            }
        }
        // A 1x1x1 texture is constant everywhere.
        let one = Texture3d::from_voxels([1, 1, 1], vec![0.625]).unwrap();
        for u in [-1.0f32, 0.0, 0.3, 1.0, 7.0, f32::NAN] {
            assert_eq!(one.sample([u, 0.5, -u]), 0.625);
        }
    }

    #[test]
    fn texture_scalar_and_simd_bit_identical() {
        let mut rng = TestRng::new(13);
        let dims = [9, 5, 17];
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let vox: Vec<f32> = (0..n).map(|_| rng.float_range(-2.0, 2.0)).collect();
        let t = Texture3d::from_voxels(dims, vox).unwrap();
        let flat =
            Texture3d::from_voxels([16, 1, 3], (0..48).map(|i| i as f32 / 47.0).collect()).unwrap();
        let specials = [
            0.0f32,
            -0.0,
            1.0,
            0.5,
            1e-30,
            -1e-30,
            1e6,
            -1e6,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1.0 / 9.0,
        ];
        for tex in [&t, &flat] {
            for _ in 0..(104_000 / 8 / 2) {
                let p: [[f32; 3]; 8] = std::array::from_fn(|_| {
                    std::array::from_fn(|_| match rng.next_u64() % 8 {
                        0 => specials[(rng.next_u64() % specials.len() as u64) as usize],
                        1 => rng.float_range(-3.0, 4.0),
                        _ => rng.float_range(0.0, 1.0),
                    })
                });
                let c = |k: usize| f32x8::new(std::array::from_fn(|i| p[i][k]));
                let v = tex.sample([c(0), c(1), c(2)]).to_array();
                for i in 0..8 {
                    let s = tex.sample(p[i]);
                    assert_eq!(s.to_bits(), v[i].to_bits(), "lane {i} at {:?}", p[i]);
                    assert!(s.is_finite());
                }
            }
        }
    }

    #[test]
    fn texture_voxel_type_deserializes_lowercase() {
        #[derive(serde::Deserialize)]
        struct K {
            k: Vec<VoxelType>,
        }
        let k: K = toml::from_str(r#"k = ["u8", "u16", "f32"]"#).unwrap();
        assert_eq!(k.k, vec![VoxelType::U8, VoxelType::U16, VoxelType::F32]);
    }
}
