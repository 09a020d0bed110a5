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

use crate::model::scene::VoxelType;
use crate::pixel::lane::Lane;
use crate::pixel::noise::lerp;

/// Largest accepted voxel count (2^28, i.e. 1 GiB of f32 voxels).
pub const MAX_VOXELS: u64 = 1 << 28;
/// Largest accepted size of one axis (2^24, so every voxel coordinate is exact in f32).
pub const MAX_DIM: u32 = 1 << 24;
/// Largest accepted |value| of an f32 voxel, so that differences of voxels stay finite.
pub const MAX_ABS_VOXEL: f32 = 1e30;
/// Errors from loading or building a 3D texture; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The scene names the file, but the host did not read it before the plan was built (a
    /// caller's mistake: `convshadow_io::read_plan_files` reads every file a scene names).
    #[error("{}: not read (the scene's files are read before the plan is built)", .path.display())]
    NotRead {
        /// The file.
        path: PathBuf,
    },
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
    /// An OpenVDB file that cannot be read, lacks the grid `texture.grid` names, or holds what
    /// the texture cannot (not a float grid, values beyond the f32 range, a box too large).
    #[error("{}: {message}", .path.display())]
    Vdb {
        /// The file.
        path: PathBuf,
        /// What is wrong, starting with the grid's name: "texture.grid `density`: …".
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
pub fn voxel_count(dims: [u32; 3]) -> Option<u64> {
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
pub(crate) fn axis<L: Lane>(u: L, dim: u32) -> (L::U, L::U, L) {
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
    /// Builds a texture from voxels in memory: dims each in [1, 2^24] with product ≤ 2^28 and
    /// the voxel count theirs, voxels finite with magnitude ≤ 1e30.
    pub fn from_voxels(dims: [u32; 3], voxels: Vec<f32>) -> Result<Texture3d, TextureError> {
        Texture3d::from_file_voxels(Path::new("<in-memory texture>"), dims, voxels)
    }

    /// [`Texture3d::from_voxels`] for voxels read from `path`, which errors name.
    pub fn from_file_voxels(
        path: &Path,
        dims: [u32; 3],
        voxels: Vec<f32>,
    ) -> Result<Texture3d, TextureError> {
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
        let (xs, rows) = ([x0, x1], [[r00, r01], [r10, r11]]);
        trilinear([fx, fy, fz], |i, j, k| {
            L::gather(&self.voxels, L::u_add(xs[i], rows[j][k]))
        })
    }
}

/// The trilinear blend of the eight corners `corner(i, j, k)` (i, j, k ∈ {0, 1}: the low or
/// high voxel along x, y, z) with the fractions `f`: lerps along x, then y, then z. The one
/// order every sampler shares (dense and bricked), so the same voxels give the same bits.
#[inline(always)]
pub(crate) fn trilinear<L: Lane>(f: [L; 3], corner: impl Fn(usize, usize, usize) -> L) -> L {
    let [fx, fy, fz] = f;
    let c00 = lerp(fx, corner(0, 0, 0), corner(1, 0, 0));
    let c10 = lerp(fx, corner(0, 1, 0), corner(1, 1, 0));
    let c01 = lerp(fx, corner(0, 0, 1), corner(1, 0, 1));
    let c11 = lerp(fx, corner(0, 1, 1), corner(1, 1, 1));
    let c0 = lerp(fy, c00, c10);
    let c1 = lerp(fy, c01, c11);
    lerp(fz, c0, c1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    use convshadow_testkit::TestRng;

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
