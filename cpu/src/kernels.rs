//! Stage 1, convolution, for one pixel: the gather of one light's planes through a kernel's tap
//! row (paper §3, eq. 7; docs/how-it-works.md) and, with the distance penumbra, the level search
//! that picks the row. Mirrors `gpu/src/shaders/kernels.wgsl` function for function (`fetch`,
//! `phase_at`, `gather`, `distance_row`, `level_row`, `fetch_level`); the per-pixel stage
//! (`crate::sweep::pixel`) calls it.
//!
//! The sum order is fixed — tap by tap, corners (0,0), (1,0), (0,1), (1,1) — and each term is
//! `acc = acc + w·v` with no fused multiply-add, so every path gives the same bits. The SIMD
//! path's gathers (`crate::sweep::fast`) compute the same sums for 8 pixels at once.

use convshadow_common::pixel::hash::{phase_index, pixel_hash, row_hash};
use convshadow_common::plan::LIT_LEVEL;
use convshadow_common::plan::kernel::{KernelTable, PhaseMode, Tap};

/// Value read outside the buffer: the unoccluded light.
pub const OUTSIDE: f32 = 1.0;
/// Value a depth plane (distance penumbra) reads outside the buffer: no occluder.
pub const OUTSIDE_DEPTH: f32 = 0.0;

/// One light channel's previous buffer, as the gather reads it.
#[derive(Clone, Copy)]
pub struct Plane<'a> {
    /// The whole buffer (all rows).
    pub data: &'a [f32],
    /// Index of this plane's pixel (0, 0) in `data`.
    pub base: usize,
    /// Distance between rows in `data`.
    pub row_stride: usize,
    /// Distance between a row's neighbouring pixels in `data` (1 in a planar buffer, the planes
    /// per pixel in a pixel-interleaved one).
    pub pixel_step: usize,
    /// Grid width.
    pub width: i32,
    /// Grid height.
    pub height: i32,
    /// The value beyond the grid: [`OUTSIDE`] for light, [`OUTSIDE_DEPTH`] for a depth plane.
    pub outside: f32,
}

impl Plane<'_> {
    /// The value at (x, y), inside the grid.
    #[inline(always)]
    pub fn at(&self, x: i32, y: i32) -> f32 {
        self.data[self.base + y as usize * self.row_stride + x as usize * self.pixel_step]
    }

    /// The value at (x, y), or [`Plane::outside`] beyond the grid (kernels.wgsl's `fetch`).
    #[inline(always)]
    pub fn fetch(&self, x: i32, y: i32) -> f32 {
        if x >= 0 && y >= 0 && x < self.width && y < self.height {
            self.at(x, y)
        } else {
            self.outside
        }
    }
}

/// The phase a slab uses at pixel (x, y) given the light's row hash (see [`PhaseMode`]).
#[inline(always)]
pub fn phase_at(table: &KernelTable, slab: u32, slab_hash: u32, row_hash_v: u32, x: u32) -> u32 {
    match table.phase_mode {
        PhaseMode::PerPixel => phase_index(pixel_hash(row_hash_v, x), table.phase_bits()),
        PhaseMode::PerSlab => phase_index(slab_hash, table.phase_bits()),
        PhaseMode::Schedule => table.slab_phase[slab as usize],
    }
}

/// The row hash of a light for row y (the per-pixel phase hash's prefix).
#[inline(always)]
pub fn light_row_hash(slab_hash: u32, y: u32) -> u32 {
    row_hash(slab_hash, y)
}

/// Where one pixel's taps read: grid pixel (x, y), moved by the slab's whole-pixel shift.
#[derive(Clone, Copy, Debug)]
pub struct TapOrigin {
    pub x: i32,
    pub y: i32,
    /// The slab's shift (`KernelTable::slab_shift`).
    pub shift: [i32; 2],
    /// Every read of every tap of every row lies inside the grid (the sweep's `Reach`): no read
    /// needs the outside value, so none is tested.
    pub inside: bool,
}

impl TapOrigin {
    /// The top-left corner tap `t` reads.
    #[inline(always)]
    fn corner(&self, t: &Tap) -> (i32, i32) {
        (self.x + t.dx + self.shift[0], self.y + t.dy + self.shift[1])
    }
}

/// One light's tap table as the sweep reads it, built once per sweep from its [`KernelTable`]
/// (the same taps): per row, the taps with a nonzero weight and the taps the level search visits.
pub struct LightTaps {
    /// Every row's taps with a nonzero weight, row after row, each row in its order. A tap whose
    /// four weights are 0 adds +0 to a sum that is never −0 (weights and values are ≥ 0 and
    /// finite), so a gather that leaves it out keeps every bit; a box kernel's phases and the
    /// distance penumbra's levels (padded to the widest level) hold many.
    weighted: Vec<Tap>,
    /// Row r's taps in `weighted`: `weighted[start..end]`.
    rows: Vec<[u32; 2]>,
    /// Per row, the taps [`distance_row`] visits ([`level_taps`]).
    level_taps: Vec<u32>,
}

impl LightTaps {
    /// The rows of `table`.
    pub fn new(table: &KernelTable) -> LightTaps {
        let mut taps = LightTaps {
            weighted: Vec::new(),
            rows: Vec::with_capacity(table.rows() as usize),
            level_taps: (0..table.rows()).map(|r| level_taps(table, r)).collect(),
        };
        for row in 0..table.rows() {
            let start = taps.weighted.len() as u32;
            let weighted = table.phase(row).iter().filter(|t| t.w != [0.0; 4]);
            taps.weighted.extend(weighted);
            taps.rows.push([start, taps.weighted.len() as u32]);
        }
        taps
    }

    /// Row `row`'s taps with a nonzero weight, in the row's order.
    #[inline(always)]
    pub fn weighted(&self, row: u32) -> &[Tap] {
        let [start, end] = self.rows[row as usize];
        &self.weighted[start as usize..end as usize]
    }

    /// How many of row `row`'s taps [`distance_row`] visits.
    #[inline(always)]
    pub fn level_taps(&self, row: u32) -> usize {
        self.level_taps[row as usize] as usize
    }
}

/// The taps of row `row` of `table` that the level search must visit: up to the last that is not
/// the zero tap at (0, 0), plus one such tap if any follows. Every padding tap reads the same four
/// level corners, so one stands for all: the same minimum.
pub fn level_taps(table: &KernelTable, row: u32) -> u32 {
    let taps = table.phase(row);
    let padding = |t: &Tap| t.dx == 0 && t.dy == 0 && t.w == [0.0; 4];
    let real = taps.iter().rposition(|t| !padding(t)).map_or(0, |i| i + 1);
    (real + usize::from(real < taps.len())) as u32
}

/// The convolution of one light at one pixel: kernels.wgsl's `gather` for every plane of
/// `planes` (the light's channels, then its depth plane if any), through `taps` (one row of the
/// light's table, its zero taps left out: [`LightTaps`]) from `at`: tap by tap, the corners
/// (0,0), (1,0), (0,1), (1,1), each `acc = acc + w·v`; a read beyond the grid gives the plane's
/// outside value. Returns plane c's sum at c (0 beyond the light's planes).
#[inline(always)]
pub fn gather(planes: &LightPlanes<'_>, taps: &[Tap], at: TapOrigin) -> [f32; 4] {
    // A constant number of sums, so that they stay in registers.
    match planes.channels {
        1 => gather_c::<1>(planes, taps, at),
        2 => gather_c::<2>(planes, taps, at),
        3 => gather_c::<3>(planes, taps, at),
        4 => gather_c::<4>(planes, taps, at),
        n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
    }
}

/// [`gather`] of `C` planes: [`gather_held_c`] with no corner read otherwise (the optimiser
/// drops the call).
#[inline(always)]
fn gather_c<const C: usize>(planes: &LightPlanes<'_>, taps: &[Tap], at: TapOrigin) -> [f32; 4] {
    gather_held_c::<C>(planes, taps, at, |_, _, _| {})
}

/// [`gather`] where some corners are read otherwise than from the light buffer
/// (`convshadow_common::plan::surface_hold`): `fix(x, y, values)` may replace corner (x, y)'s
/// values (the light's channels, then its depth plane if any) — a held pixel behind whose
/// surface the reader lies, or a released pixel whose light is served on its surface. Every
/// corner is summed as [`gather`] sums it, in the same order: where `fix` changes nothing, the
/// same bits (kernels.wgsl's `gather_held`).
#[inline(always)]
pub fn gather_held(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    at: TapOrigin,
    fix: impl Fn(i32, i32, &mut [f32]),
) -> [f32; 4] {
    match planes.channels {
        1 => gather_held_c::<1>(planes, taps, at, fix),
        2 => gather_held_c::<2>(planes, taps, at, fix),
        3 => gather_held_c::<3>(planes, taps, at, fix),
        4 => gather_held_c::<4>(planes, taps, at, fix),
        n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
    }
}

/// [`gather_held`] of `C` planes.
#[inline(always)]
fn gather_held_c<const C: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    at: TapOrigin,
    fix: impl Fn(i32, i32, &mut [f32]),
) -> [f32; 4] {
    let mut acc = [0.0f32; 4];
    for t in taps {
        let (sx, sy) = at.corner(t);
        let mut v = planes.corners::<C>(sx, sy, at.inside);
        for (i, (cx, cy)) in [(sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1)]
            .into_iter()
            .enumerate()
        {
            fix(cx, cy, &mut v[i]);
        }
        for (c, a) in acc.iter_mut().enumerate().take(C) {
            // `a += p` is `a = a + p`: no fused multiply-add.
            *a += t.w[0] * v[0][c];
            *a += t.w[1] * v[1][c];
            *a += t.w[2] * v[2][c];
            *a += t.w[3] * v[3][c];
        }
    }
    acc
}

/// Distance penumbra: the tap row light `taps` (of `table`) gathers through at one pixel
/// (kernels.wgsl's `distance_row`). The pixel's own level (level 0's when it has none) gives a
/// row; the smallest level among its own and those at the four corners of every tap of that row
/// (from `at`) is the nearest occluder's in reach, whose row (level 0's when there is none) the
/// pixel gathers through. `phase`: the pixel's phase within a level ([`level_row`]).
#[inline(always)]
pub fn distance_row(
    levels: &LevelPlane<'_>,
    table: &KernelTable,
    taps: &LightTaps,
    phase: u32,
    slab: u32,
    slabs: u32,
    at: TapOrigin,
) -> u32 {
    let or_zero = |level: u32| if level == LIT_LEVEL { 0 } else { level };
    let own = levels.at(at.x, at.y);
    let own_row = level_row(table, or_zero(own), phase, slabs, slab);
    let mut nearest = own;
    // The row's taps (`table.phase(own_row)`), up to the last padding tap the search needs.
    let first = own_row as usize * table.taps_per_phase as usize;
    for t in &table.taps[first..][..taps.level_taps(own_row)] {
        let (sx, sy) = at.corner(t);
        nearest = nearest.min(levels.corners(sx, sy, at.inside));
    }
    level_row(table, or_zero(nearest), phase, slabs, slab)
}

/// The tap row of level `level` at phase `phase` (kernels.wgsl's `level_row`):
/// `level · phase_count + phase`, or for a scheduled kernel the level's own phase of slab `slab`,
/// `slab_phase[level · slabs + slab]`.
#[inline(always)]
pub fn level_row(table: &KernelTable, level: u32, phase: u32, slabs: u32, slab: u32) -> u32 {
    let first = level * table.phase_count;
    match table.phase_mode {
        PhaseMode::Schedule => first + table.slab_phase[(level * slabs + slab) as usize],
        _ => first + phase,
    }
}

/// The light buffers of one light as the gather reads them: `channels` planes of one
/// row-major grid, plane c's pixel (x, y) at `base + y·row_stride + x·pixel_step +
/// c·plane_step`. The sweep's buffer is pixel-interleaved (`[row][light][x][plane]`:
/// `pixel_step` = the light's planes, `plane_step` = 1), so that one lane's horizontal pixel
/// pair of every plane is one contiguous read; planar grids (`pixel_step` = 1) read the same.
#[derive(Clone, Copy)]
pub struct LightPlanes<'a> {
    /// The whole buffer (all rows).
    pub data: &'a [f32],
    /// Index of channel 0's pixel (0, 0) in `data`.
    pub base: usize,
    /// Planes gathered: the light's channels, then its depth plane if any.
    pub channels: usize,
    /// Planes that are light (read [`OUTSIDE`] beyond the grid); planes from this index on are
    /// depth planes (read [`OUTSIDE_DEPTH`]).
    pub light_channels: usize,
    /// Distance between rows in `data`.
    pub row_stride: usize,
    /// Distance between a row's neighbouring pixels of one plane.
    pub pixel_step: usize,
    /// Distance between a pixel's planes.
    pub plane_step: usize,
    /// Grid width.
    pub width: i32,
    /// Grid height.
    pub height: i32,
}

impl LightPlanes<'_> {
    /// Whether the planes gathered are every plane of a pixel-interleaved buffer (more than
    /// one): then one contiguous read gives a pixel's every plane.
    #[inline(always)]
    pub fn every_plane_interleaved(&self) -> bool {
        self.channels > 1 && self.pixel_step == self.channels && self.plane_step == 1
    }

    /// The corners (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1) of the first `C` planes, as
    /// `[corner][plane]`; beyond the grid, a plane's outside value. `inside`: the caller knows
    /// that every corner lies in the grid. Where they do and the planes are a pixel's every plane
    /// side by side, the block is two runs of `2·C` values, one bounds check each.
    #[inline(always)]
    pub fn corners<const C: usize>(&self, x: i32, y: i32, inside: bool) -> [[f32; C]; 4] {
        let inside = inside || (x >= 0 && y >= 0 && x + 1 < self.width && y + 1 < self.height);
        if inside && self.pixel_step == C && self.plane_step == 1 {
            let rs = self.row_stride;
            let at = self.base + y as usize * rs + x as usize * C;
            let (top, bottom) = (&self.data[at..][..2 * C], &self.data[at + rs..][..2 * C]);
            let run = |r: &[f32], from: usize| std::array::from_fn(|c| r[from + c]);
            return [run(top, 0), run(top, C), run(bottom, 0), run(bottom, C)];
        }
        let corner = |cx, cy| std::array::from_fn(|c| self.plane(c).fetch(cx, cy));
        [
            corner(x, y),
            corner(x + 1, y),
            corner(x, y + 1),
            corner(x + 1, y + 1),
        ]
    }

    /// Plane `c` as a scalar [`Plane`].
    #[inline(always)]
    pub fn plane(&self, c: usize) -> Plane<'_> {
        Plane {
            data: self.data,
            base: self.base + c * self.plane_step,
            row_stride: self.row_stride,
            pixel_step: self.pixel_step,
            width: self.width,
            height: self.height,
            outside: if c < self.light_channels {
                OUTSIDE
            } else {
                OUTSIDE_DEPTH
            },
        }
    }
}

/// One light's level plane of the previous slab (distance penumbra), as the gather reads it.
#[derive(Clone, Copy)]
pub struct LevelPlane<'a> {
    /// The whole plane (all rows, all lights).
    pub data: &'a [u32],
    /// The plane's 2×2 block minima, laid out as `data` (`crate::sweep::level_blocks`).
    pub blocks: &'a [u32],
    /// Index of this light's pixel (0, 0) in `data`.
    pub base: usize,
    /// Distance between rows in `data`.
    pub row_stride: usize,
    /// Grid width.
    pub width: i32,
    /// Grid height.
    pub height: i32,
}

impl LevelPlane<'_> {
    /// Whether (x, y) lies in the grid.
    #[inline(always)]
    fn inside(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.width && y < self.height
    }

    /// Index of (x, y) in `data` (and `blocks`).
    #[inline(always)]
    fn index(&self, x: i32, y: i32) -> usize {
        self.base + y as usize * self.row_stride + x as usize
    }

    /// The level at (x, y), inside the grid.
    #[inline(always)]
    pub fn at(&self, x: i32, y: i32) -> u32 {
        self.data[self.index(x, y)]
    }

    /// The level at (x, y), or [`LIT_LEVEL`] beyond the grid (kernels.wgsl's `fetch_level`).
    #[inline(always)]
    pub fn fetch(&self, x: i32, y: i32) -> u32 {
        if self.inside(x, y) {
            self.at(x, y)
        } else {
            LIT_LEVEL
        }
    }

    /// The smallest level at the corners (x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1), each
    /// [`LIT_LEVEL`] beyond the grid: one read of the block minima where (x, y) lies in the grid
    /// (`crate::sweep::level_blocks` gives the corners beyond it the same `LIT_LEVEL`; a minimum is
    /// exact and order-free, so one read gives the bits of four), the four corners elsewhere.
    /// `inside`: the caller knows that every corner lies in the grid.
    #[inline(always)]
    pub fn corners(&self, x: i32, y: i32, inside: bool) -> u32 {
        if inside || self.inside(x, y) {
            return self.blocks[self.index(x, y)];
        }
        let corners = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)];
        corners
            .map(|(cx, cy)| self.fetch(cx, cy))
            .into_iter()
            .fold(LIT_LEVEL, u32::min)
    }
}
