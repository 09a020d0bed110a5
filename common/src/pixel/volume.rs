//! A material's 3D texture as the stages sample it: dense ([`Texture3d`], raw and NIfTI files)
//! or sparse in 8³ bricks ([`BrickedTexture3d`], OpenVDB grids).
//!
//! The bricked layout: the texture's box is cut into bricks of 8³ voxels; an index table with
//! one `u32` per brick (x fastest, then y, then z) gives the brick's slot in a pool of bricks
//! (512 voxels each, x fastest within the brick). Slot 0 is the background brick (every voxel
//! the grid's background), which every empty brick points to, so a read never branches. The
//! sampler is the dense one ([`Texture3d::sample`]: the same clamp, the same floor and
//! fraction, the same lerps in the same order) with each corner voxel fetched through the
//! table: on the same voxel values both give the same bits. `gpu/src/shaders/texture3d.wgsl`
//! mirrors it, with the table stored as exact f32 integers in the voxel buffer.

use std::sync::Arc;

use crate::pixel::lane::Lane;
use crate::pixel::texture3d::{Texture3d, axis, trilinear};

/// Voxels along each axis of a brick.
pub const BRICK: u32 = 8;
/// Voxels in a brick.
pub const BRICK_VOXELS: usize = 512;
/// The most bricks a pool may hold, the background brick included (2^23: every pool index,
/// `slot · 512 + voxel`, fits in a u32, and every slot is exact as an f32 on the GPU).
pub const MAX_BRICK_SLOTS: usize = 1 << 23;
/// The most entries the index table may have (2^28 bricks: 1 GiB of table).
pub const MAX_TABLE_BRICKS: u64 = 1 << 28;
/// The most voxels along one axis of a bricked texture (2^24, as for dense textures: every
/// voxel coordinate is exact in f32).
pub const MAX_BRICKED_DIM: u32 = 1 << 24;

/// A sparse 3D texture: an index table over 8³ bricks and a pool of the bricks that are not
/// background (see the module documentation).
#[derive(Clone, PartialEq)]
pub struct BrickedTexture3d {
    /// Voxels along x, y, z (each 1 to [`MAX_BRICKED_DIM`]).
    pub dims: [u32; 3],
    /// Bricks along x, y, z: `ceil(dims / 8)`.
    pub bricks: [u32; 3],
    /// Per brick (x fastest): its slot in `pool`; 0 is the background brick.
    pub table: Vec<u32>,
    /// The bricks' voxels, 512 per slot, voxel `(x, y, z)` of slot `s` at `512·s + x + 8·y +
    /// 64·z`.
    pub pool: Vec<f32>,
}

impl std::fmt::Debug for BrickedTexture3d {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BrickedTexture3d")
            .field("dims", &self.dims)
            .field("bricks", &self.bricks)
            .field("slots", &(self.pool.len() / BRICK_VOXELS))
            .finish()
    }
}

/// Bricks along each axis for `dims` voxels, and their count; `None` when a dim is 0 or above
/// [`MAX_BRICKED_DIM`] or the table would pass [`MAX_TABLE_BRICKS`].
pub fn brick_grid(dims: [u32; 3]) -> Option<([u32; 3], u64)> {
    if dims.iter().any(|&d| d == 0 || d > MAX_BRICKED_DIM) {
        return None;
    }
    let bricks = dims.map(|d| d.div_ceil(BRICK));
    let n = bricks.iter().map(|&b| u64::from(b)).product::<u64>();
    (n <= MAX_TABLE_BRICKS).then_some((bricks, n))
}

impl BrickedTexture3d {
    /// The bytes this texture holds: its table and its pool.
    pub fn bytes(&self) -> u64 {
        4 * (self.table.len() as u64 + self.pool.len() as u64)
    }

    /// The voxel at integer coordinates (each below its dim), through the table.
    pub fn voxel(&self, xyz: [u32; 3]) -> f32 {
        let b = xyz.map(|c| c / BRICK);
        let l = xyz.map(|c| c % BRICK);
        let brick = b[0] + self.bricks[0] * (b[1] + self.bricks[1] * b[2]);
        let slot = self.table[brick as usize] as usize;
        self.pool[slot * BRICK_VOXELS + (l[0] + BRICK * l[1] + BRICK * BRICK * l[2]) as usize]
    }

    /// Trilinear sample at normalised coordinates, exactly as [`Texture3d::sample`] on the same
    /// voxels: per axis the same `axis` split, then each of the eight corners read through the
    /// table (brick = index >> 3, voxel in brick = index & 7), lerps along x, y, z in the dense
    /// sampler's order.
    pub fn sample<L: Lane>(&self, p: [L; 3]) -> L {
        let [u, v, w] = p;
        let [dx, dy, dz] = self.dims;
        let (x0, x1, fx) = axis(u, dx);
        let (y0, y1, fy) = axis(v, dy);
        let (z0, z1, fz) = axis(w, dz);
        let seven = L::u_splat(BRICK - 1);
        // Per axis and corner: (the brick's table offset, the voxel's offset in the brick).
        let split = |i: L::U, stride: u32, shift: u32| {
            (
                L::u_mul(L::u_shr(i, 3), L::u_splat(stride)),
                L::u_shl(L::u_and(i, seven), shift),
            )
        };
        let sy = self.bricks[0];
        let sz = self.bricks[0].wrapping_mul(self.bricks[1]);
        let (bx0, lx0) = split(x0, 1, 0);
        let (bx1, lx1) = split(x1, 1, 0);
        let (by0, ly0) = split(y0, sy, 3);
        let (by1, ly1) = split(y1, sy, 3);
        let (bz0, lz0) = split(z0, sz, 6);
        let (bz1, lz1) = split(z1, sz, 6);
        let (bx, lx) = ([bx0, bx1], [lx0, lx1]);
        let (by, ly) = ([by0, by1], [ly0, ly1]);
        let (bz, lz) = ([bz0, bz1], [lz0, lz1]);
        trilinear([fx, fy, fz], |i, j, k| {
            let slot = L::u_gather(&self.table, L::u_add(L::u_add(bx[i], by[j]), bz[k]));
            let local = L::u_add(L::u_add(lx[i], ly[j]), lz[k]);
            L::gather(&self.pool, L::u_add(L::u_shl(slot, 9), local))
        })
    }
}

/// A material's 3D texture: dense or bricked.
#[derive(Clone, Debug, PartialEq)]
pub enum Volume {
    /// Every voxel stored (raw and NIfTI files).
    Dense(Texture3d),
    /// 8³ bricks through an index table (OpenVDB grids).
    Bricked(BrickedTexture3d),
}

impl Volume {
    /// Voxels along x, y, z.
    pub fn dims(&self) -> [u32; 3] {
        match self {
            Volume::Dense(t) => t.dims,
            Volume::Bricked(b) => b.dims,
        }
    }

    /// Trilinear sample at normalised coordinates (voxel centres at `(i + 0.5) / dim`,
    /// clamp-to-edge); see [`Texture3d::sample`] and [`BrickedTexture3d::sample`].
    #[inline]
    pub fn sample<L: Lane>(&self, p: [L; 3]) -> L {
        match self {
            Volume::Dense(t) => t.sample(p),
            Volume::Bricked(b) => b.sample(p),
        }
    }
}

impl From<Texture3d> for Volume {
    fn from(t: Texture3d) -> Volume {
        Volume::Dense(t)
    }
}

/// A shared dense texture as a [`Volume`].
pub fn dense(t: Texture3d) -> Arc<Volume> {
    Arc::new(Volume::Dense(t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use convshadow_testkit::TestRng;
    use wide::f32x8;

    /// The bricked copy of a dense texture: every brick that is not all `background` gets a
    /// slot, in brick order.
    fn bricked(t: &Texture3d, background: f32) -> BrickedTexture3d {
        let (bricks, n) = brick_grid(t.dims).unwrap();
        let mut table = vec![0u32; n as usize];
        let mut pool = vec![background; BRICK_VOXELS];
        for bz in 0..bricks[2] {
            for by in 0..bricks[1] {
                for bx in 0..bricks[0] {
                    let mut brick = [background; BRICK_VOXELS];
                    for (i, v) in brick.iter_mut().enumerate() {
                        let i = i as u32;
                        let xyz = [bx * 8 + i % 8, by * 8 + i / 8 % 8, bz * 8 + i / 64];
                        if (0..3).all(|a| xyz[a] < t.dims[a]) {
                            *v = t.voxels
                                [(xyz[0] + t.dims[0] * (xyz[1] + t.dims[1] * xyz[2])) as usize];
                        }
                    }
                    if brick.iter().any(|&v| v != background) {
                        table[(bx + bricks[0] * (by + bricks[1] * bz)) as usize] =
                            (pool.len() / BRICK_VOXELS) as u32;
                        pool.extend_from_slice(&brick);
                    }
                }
            }
        }
        BrickedTexture3d {
            dims: t.dims,
            bricks,
            table,
            pool,
        }
    }

    /// On the same voxels the bricked sampler gives the dense sampler's bits, scalar and 8-lane,
    /// inside, on brick seams, at the clamped edges and at NaN / infinite coordinates.
    #[test]
    fn bricked_and_dense_samplers_give_the_same_bits() {
        let mut rng = TestRng::new(44);
        for dims in [[1, 1, 1], [9, 5, 17], [16, 8, 8], [23, 31, 12]] {
            let n = dims.iter().product::<u32>() as usize;
            // Mostly background (0), some values: many bricks stay empty.
            let vox: Vec<f32> = (0..n)
                .map(|i| {
                    if i % 7 < 2 {
                        rng.float_range(-1.0, 2.0)
                    } else {
                        0.0
                    }
                })
                .collect();
            let dense = Texture3d::from_voxels(dims, vox).unwrap();
            let sparse = bricked(&dense, 0.0);
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        let i = (x + dims[0] * (y + dims[1] * z)) as usize;
                        assert_eq!(sparse.voxel([x, y, z]), dense.voxels[i]);
                    }
                }
            }
            let specials = [0.0f32, 1.0, -0.5, 1.5, f32::NAN, f32::INFINITY, 0.5];
            for _ in 0..4000 {
                let p: [[f32; 3]; 8] = std::array::from_fn(|_| {
                    std::array::from_fn(|_| match rng.next_u64() % 6 {
                        0 => specials[(rng.next_u64() % specials.len() as u64) as usize],
                        1 => rng.float_range(-0.2, 1.2),
                        _ => rng.float_range(0.0, 1.0),
                    })
                });
                let c = |k: usize| f32x8::new(std::array::from_fn(|i| p[i][k]));
                let lanes = sparse.sample([c(0), c(1), c(2)]).to_array();
                for i in 0..8 {
                    let d = dense.sample(p[i]);
                    assert_eq!(
                        sparse.sample(p[i]).to_bits(),
                        d.to_bits(),
                        "{dims:?} {:?}",
                        p[i]
                    );
                    assert_eq!(lanes[i].to_bits(), d.to_bits(), "lane {i} {dims:?}");
                }
            }
        }
    }

    #[test]
    fn brick_grid_limits() {
        assert_eq!(brick_grid([9, 8, 1]), Some(([2, 1, 1], 2)));
        assert_eq!(brick_grid([0, 8, 1]), None);
        assert_eq!(brick_grid([MAX_BRICKED_DIM + 1, 1, 1]), None);
        assert_eq!(
            brick_grid([1 << 24, 1 << 24, 8]),
            None,
            "2^42 bricks: over the table limit"
        );
        assert!(brick_grid([1 << 13, 1 << 13, 1 << 11]).is_some());
    }
}
