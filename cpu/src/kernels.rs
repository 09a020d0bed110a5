//! Stage 1, convolution: the gather of one light buffer through a kernel's tap table
//! (paper §3, eq. 7; docs/how-it-works.md). Mirrors `gpu/src/shaders/kernels.wgsl`.
//!
//! The sum order is fixed — tap by tap, corners (0,0), (1,0), (0,1), (1,1) — and each term is
//! `acc = acc + w·v` with no fused multiply-add, so every path gives the same bits. Written once
//! over [`Lane`]: the scalar path is the 1-lane instance.

use convshadow_common::pixel::hash::{phase_index, pixel_hash, row_hash};
use convshadow_common::pixel::lane::{Layout, MAX_LANES, halves, load_halves, splat_within_halves};
use convshadow_common::plan::LIT_LEVEL;
use convshadow_common::plan::kernel::{KernelTable, PhaseMode, Tap};
use std::ops::Range;
use wide::i32x8;

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

/// [`gather`] of `C` planes.
#[inline(always)]
fn gather_c<const C: usize>(planes: &LightPlanes<'_>, taps: &[Tap], at: TapOrigin) -> [f32; 4] {
    let mut acc = [0.0f32; 4];
    for t in taps {
        let (sx, sy) = at.corner(t);
        let v = planes.corners::<C>(sx, sy, at.inside);
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

/// `acc + w0·v0 + w1·v1 + w2·v2 + w3·v3`, added left to right (the fixed sum order).
#[inline(always)]
fn add_bilinear<L: Layout>(acc: L, w: &[L; 4], v: &[L; 4]) -> L {
    let mut s = acc;
    for (wk, vk) in w.iter().zip(v) {
        s = s + *wk * *vk;
    }
    s
}

/// The four bilinear corners (0,0), (1,0), (0,1), (1,1) of lane i's sample at
/// (`sx[i]`, `sy[i]`) in `plane` (reads outside give its outside value; [`Lane::fetch_grid`]).
#[inline(always)]
fn fetch_corners<L: Layout>(plane: &Plane<'_>, sx: L::U, sy: L::U) -> [L; 4] {
    let one = L::u_splat(1);
    let (sx1, sy1) = (L::u_add(sx, one), L::u_add(sy, one));
    let (w, h) = (plane.width, plane.height);
    let fetch = |x, y| {
        L::fetch_grid(
            plane.data,
            plane.base,
            plane.row_stride,
            plane.pixel_step,
            w,
            h,
            x,
            y,
            plane.outside,
        )
    };
    [
        fetch(sx, sy),
        fetch(sx1, sy),
        fetch(sx, sy1),
        fetch(sx1, sy1),
    ]
}

/// Whether every bilinear read of the `lanes` pixels x0.. of row y through taps whose top-left
/// corners span `extent` (`[min dx, max dx, min dy, max dy]`), moved by `shift`, lies inside the
/// `width` × `height` grid. The sweep's per-chunk test uses the reach of every row of every
/// table; this one the rows a chunk actually reads, so that chunks near the grid's edge whose
/// kernels stay inside take the unchecked path (the same values: only reads beyond the grid differ).
#[inline(always)]
pub fn reads_inside(
    extent: [i32; 4],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    lanes: usize,
    width: i32,
    height: i32,
) -> bool {
    let (x, y) = (i64::from(x0 + shift[0]), i64::from(y + shift[1]));
    let e = extent.map(i64::from);
    x + e[0] >= 0
        && x + lanes as i64 + e[1] < i64::from(width)
        && y + e[2] >= 0
        && y + e[3] + 1 < i64::from(height)
}

/// Gathers every channel of one light at pixels x0.. (one per lane) of row y when every lane
/// uses the same `taps` (per-slab and scheduled phases, and any 1-lane gather): contiguous loads
/// when `interior` (every read inside the grid; one bounds check for the taps' whole
/// `extent`, see `TapColumns::extent`), else tap by tap: contiguous loads where the tap's
/// corners lie inside, `RowRun`s where they do not. Adds into `acc[c]` tap by tap,
/// corner by corner, so every lane has the bits of any other lane count.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn gather_lanes<L: Layout>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    extent: [i32; 4],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    interior: bool,
    acc: &mut [L],
) {
    let (w, h) = (planes.width, planes.height);
    if interior || reads_inside(extent, shift, x0, y, L::LANES, w, h) {
        gather_inside(planes, taps, extent, shift, x0, y, [acc]);
        return;
    }
    match planes.channels {
        1 => gather_near_edge::<L, 1>(planes, taps, shift, x0, y, acc),
        2 => gather_near_edge::<L, 2>(planes, taps, shift, x0, y, acc),
        3 => gather_near_edge::<L, 3>(planes, taps, shift, x0, y, acc),
        4 => gather_near_edge::<L, 4>(planes, taps, shift, x0, y, acc),
        n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
    }
}

/// [`gather_lanes`] of a chunk whose reads may leave the grid, for `C` planes (a constant, so that
/// the sums stay in registers): tap by tap, contiguous loads where the tap's corners lie inside,
/// [`RowRun`]s where they do not. Every plane of a pixel-interleaved buffer is summed in the
/// buffer's order (the runs' values put in it), as [`gather_inside`] sums it.
#[inline(always)]
fn gather_near_edge<L: Layout, const C: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    acc: &mut [L],
) {
    let (w, h, rs) = (planes.width, planes.height, planes.row_stride);
    let (step, plane_step) = (planes.pixel_step, planes.plane_step);
    let interleaved = planes.every_plane_interleaved();
    let lanes = L::LANES as i32;
    let mut sums = [L::splat(0.0); C];
    sums.copy_from_slice(&acc[..C]);
    if interleaved {
        sums = L::pixel_order(sums);
    }
    for t in taps {
        let sx = x0 + t.dx + shift[0];
        let sy = y + t.dy + shift[1];
        let weights = [
            L::splat(t.w[0]),
            L::splat(t.w[1]),
            L::splat(t.w[2]),
            L::splat(t.w[3]),
        ];
        if sx >= 0 && sx + 1 + lanes <= w && sy >= 0 && sy + 1 < h {
            // This tap's corners lie inside: the interior's loads.
            let at = planes.base + sy as usize * rs + sx as usize * step;
            for (c, sum) in sums.iter_mut().enumerate() {
                let v = if interleaved {
                    let at = at + c * L::LANES;
                    let load = |at| L::load(planes.data, at);
                    [load(at), load(at + C), load(at + rs), load(at + rs + C)]
                } else {
                    let at = at + c * plane_step;
                    let load = |at| load_step::<L>(planes.data, at, step);
                    [
                        load(at),
                        load(at + step),
                        load(at + rs),
                        load(at + rs + step),
                    ]
                };
                *sum = add_bilinear(*sum, &weights, &v);
            }
            continue;
        }
        // The same four runs in every plane: placed once per tap.
        let runs = [
            RowRun::at::<L>(w, h, [rs, step], sx, sy),
            RowRun::at::<L>(w, h, [rs, step], sx + 1, sy),
            RowRun::at::<L>(w, h, [rs, step], sx, sy + 1),
            RowRun::at::<L>(w, h, [rs, step], sx + 1, sy + 1),
        ];
        let mut corners = [[L::splat(0.0); C]; 4];
        for c in 0..C {
            let plane = planes.plane(c);
            for (corner, run) in corners.iter_mut().zip(&runs) {
                corner[c] = run.read(&plane);
            }
        }
        if interleaved {
            for corner in corners.iter_mut() {
                *corner = L::pixel_order(*corner);
            }
        }
        for (j, sum) in sums.iter_mut().enumerate() {
            let v = [corners[0][j], corners[1][j], corners[2][j], corners[3][j]];
            *sum = add_bilinear(*sum, &weights, &v);
        }
    }
    if interleaved {
        sums = L::plane_order(sums);
    }
    acc[..C].copy_from_slice(&sums);
}

/// Where the `LANES` values at (x.., y) of a plane come from, each what [`Plane::fetch`] gives;
/// the same for every plane of a grid, so placed once and read per plane.
#[derive(Clone, Copy)]
enum RowRun {
    /// Wholly beyond the grid: the plane's outside value.
    Outside,
    /// `LANES` values from `at` (past the plane's pixel (0, 0)) moved by `by` lanes
    /// ([`Lane::shift_lanes`]): 0 inside the grid; where the run crosses the grid's left or
    /// right edge, the row's first or last `LANES` values moved into place.
    Load { at: usize, by: i32 },
    /// Crossing an edge of a grid narrower than `LANES`: lane by lane.
    Fetch { x: i32, y: i32 },
}

impl RowRun {
    /// The run at (x.., y) of a `width` × `height` grid with rows and pixels `[row_stride,
    /// pixel_step]` apart.
    #[inline(always)]
    fn at<L: Layout>(width: i32, height: i32, strides: [usize; 2], x: i32, y: i32) -> RowRun {
        let [row_stride, step] = strides;
        let lanes = L::LANES as i32;
        if y < 0 || y >= height || x >= width || x + lanes <= 0 {
            return RowRun::Outside;
        }
        let row = y as usize * row_stride;
        if x >= 0 && x + lanes <= width {
            return RowRun::Load {
                at: row + x as usize * step,
                by: 0,
            };
        }
        if width < lanes {
            return RowRun::Fetch { x, y };
        }
        // Columns 0.. (x < 0) or width − LANES.. (the run ends beyond the grid): lane i then
        // holds column x + i.
        let first = if x < 0 { 0 } else { width - lanes };
        RowRun::Load {
            at: row + first as usize * step,
            by: x - first,
        }
    }

    /// The run's values in `plane`.
    #[inline(always)]
    fn read<L: Layout>(self, plane: &Plane<'_>) -> L {
        match self {
            RowRun::Outside => L::splat(plane.outside),
            RowRun::Load { at, by } => {
                load_step::<L>(plane.data, plane.base + at, plane.pixel_step)
                    .shift_lanes(by, plane.outside)
            }
            RowRun::Fetch { x, y } => {
                let mut v = [0.0f32; MAX_LANES];
                for (i, value) in v.iter_mut().enumerate().take(L::LANES) {
                    *value = plane.fetch(x + i as i32, y);
                }
                L::load(&v, 0)
            }
        }
    }
}

/// `data[at + i·step]` in lane i: one contiguous load when `step` is 1, else a gather (a plane
/// of a pixel-interleaved buffer read on its own).
#[inline(always)]
fn load_step<L: Layout>(data: &[f32], at: usize, step: usize) -> L {
    if step == 1 {
        return L::load(data, at);
    }
    assert!(
        at <= u32::MAX as usize,
        "load at {at} beyond 32-bit indices"
    );
    let lanes = L::u_mul(L::u_iota(0), L::u_splat(step as u32));
    L::gather(data, L::u_add(L::u_splat(at as u32), lanes))
}

/// Writes planes `planes` of pixels x.. (lane i: pixel x + i) to a pixel-interleaved buffer
/// whose pixel x's plane 0 is `data[at]` (the planes of a pixel side by side, `planes.len()` of
/// them).
#[inline(always)]
pub fn store_pixels<L: Layout>(planes: &[L], data: &mut [f32], at: usize) {
    match planes {
        [p] => p.store(data, at),
        [a, b] => store_in_pixel_order(&[*a, *b], data, at),
        [a, b, c] => store_in_pixel_order(&[*a, *b, *c], data, at),
        [a, b, c, d] => store_in_pixel_order(&[*a, *b, *c, *d], data, at),
        _ => panic!("a light has 1 to 4 planes, not {}", planes.len()),
    }
}

/// [`store_pixels`] for `C` planes.
#[inline(always)]
fn store_in_pixel_order<L: Layout, const C: usize>(planes: &[L; C], data: &mut [f32], at: usize) {
    // One bounds check for the run (a check per value cost 1 % of the sweep's instructions).
    let run = &mut data[at..at + C * L::LANES];
    for (j, v) in L::pixel_order(*planes).iter().enumerate() {
        v.store(run, j * L::LANES);
    }
}

/// [`gather_lanes`] of `K` neighbouring chunks at once (chunk k at pixels x0 + k·LANES..), every read
/// inside the grid: each tap's weights are splat once for all chunks, and the chunks' sums are
/// independent chains the processor overlaps (one chunk's sums wait on the add latency). Each
/// lane's sum has the same terms in the same order as one chunk alone: the same bits. A
/// pixel-interleaved buffer whose every plane is gathered is summed in its own order (every
/// value's sum apart, so the same terms) and put back in plane order once
/// ([`Lane::plane_order`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn gather_inside<L: Layout, const K: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    extent: [i32; 4],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    accs: [&mut [L]; K],
) {
    // The lowest index any tap's top-left corner reads, and the highest index any read reaches,
    // over every plane and chunk.
    let rs = planes.row_stride as i64;
    let (step, plane_step) = (planes.pixel_step as i64, planes.plane_step as i64);
    let (x, y) = (i64::from(x0 + shift[0]), i64::from(y + shift[1]));
    let base = planes.base as i64;
    let lo = base + (y + i64::from(extent[2])) * rs + (x + i64::from(extent[0])) * step;
    let last_plane = (planes.channels as i64 - 1) * plane_step;
    let last_pixel = x + i64::from(extent[1]) + (K * L::LANES) as i64;
    let hi = base + last_plane + (y + i64::from(extent[3]) + 1) * rs + last_pixel * step;
    assert!(
        lo >= 0 && hi < planes.data.len() as i64,
        "gather footprint {lo}..={hi} outside the light buffer"
    );
    let interleaved = planes.every_plane_interleaved();
    match planes.channels {
        2 if interleaved => gather_pixels::<L, K, 2>(planes, taps, x, y, accs),
        3 if interleaved => gather_pixels::<L, K, 3>(planes, taps, x, y, accs),
        4 if interleaved => gather_pixels::<L, K, 4>(planes, taps, x, y, accs),
        _ => gather_planes(planes, taps, x, y, accs),
    }
}

/// [`gather_inside`] plane by plane, after its bounds proof (`x`, `y`: the chunks' shifted
/// origin): contiguous loads in a planar buffer, strided ones otherwise.
#[inline(always)]
fn gather_planes<L: Layout, const K: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    x: i64,
    y: i64,
    mut accs: [&mut [L]; K],
) {
    let (rs, step) = (planes.row_stride, planes.pixel_step);
    for t in taps {
        let w = [t.w[0], t.w[1], t.w[2], t.w[3]].map(L::splat);
        let at0 = planes.base as i64
            + (y + i64::from(t.dy)) * rs as i64
            + (x + i64::from(t.dx)) * step as i64;
        for c in 0..planes.channels {
            let first = (at0 + (c * planes.plane_step) as i64) as usize;
            for (k, acc) in accs.iter_mut().enumerate() {
                let at = first + k * L::LANES * step;
                let below = at + rs;
                let v = if step == 1 {
                    // SAFETY: every load lies in the footprint `gather_inside` checked.
                    unsafe {
                        [
                            L::load_unchecked(planes.data, at),
                            L::load_unchecked(planes.data, at + 1),
                            L::load_unchecked(planes.data, below),
                            L::load_unchecked(planes.data, below + 1),
                        ]
                    }
                } else {
                    let load = |at| load_step::<L>(planes.data, at, step);
                    [load(at), load(at + step), load(below), load(below + step)]
                };
                acc[c] = add_bilinear(acc[c], &w, &v);
            }
        }
    }
}

/// [`gather_inside`] of every plane of a pixel-interleaved buffer (`C` planes per pixel), after
/// its bounds proof: `C` contiguous loads per corner and chunk, summed value by value in the
/// buffer's order, then put in plane order.
#[inline(always)]
fn gather_pixels<L: Layout, const K: usize, const C: usize>(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    x: i64,
    y: i64,
    accs: [&mut [L]; K],
) {
    let rs = planes.row_stride;
    let mut sums = [[L::splat(0.0); C]; K];
    for (sum, acc) in sums.iter_mut().zip(&accs) {
        sum.copy_from_slice(&acc[..C]);
        *sum = L::pixel_order(*sum);
    }
    for t in taps {
        let w = [t.w[0], t.w[1], t.w[2], t.w[3]].map(L::splat);
        let at0 = (planes.base as i64
            + (y + i64::from(t.dy)) * rs as i64
            + (x + i64::from(t.dx)) * C as i64) as usize;
        for (k, chunk) in sums.iter_mut().enumerate() {
            for (j, sum) in chunk.iter_mut().enumerate() {
                let at = at0 + (k * C + j) * L::LANES;
                let below = at + rs;
                // SAFETY: every load lies in the footprint `gather_inside` checked (pixel x + 1's
                // planes of the chunk's last pixel end at its highest index).
                let v = unsafe {
                    [
                        L::load_unchecked(planes.data, at),
                        L::load_unchecked(planes.data, at + C),
                        L::load_unchecked(planes.data, below),
                        L::load_unchecked(planes.data, below + C),
                    ]
                };
                *sum = add_bilinear(*sum, &w, &v);
            }
        }
    }
    for (acc, chunk) in accs.into_iter().zip(&sums) {
        acc[..C].copy_from_slice(&L::plane_order(*chunk));
    }
}

/// A light's tap table by tap, as structure-of-arrays for the per-lane gather: tap k of row p
/// at `k * phase_count + p`, so that one gather by the lanes' rows reads a tap's column. Built
/// once per sweep from the plan's [`KernelTable`] (same values, another layout). Its fields are
/// only built by [`TapColumns::new`] (never changed after), so they agree with one another: the
/// per-lane gather's unchecked loads rely on it.
pub struct TapColumns {
    /// Rows of the table (levels × phases).
    pub(crate) phase_count: usize,
    /// The four corner weights of each tap, one column per tap.
    pub(crate) weights: Vec<[f32; 4]>,
    /// `dy · row_stride + dx · pixel_step` (wrapping: an `i32` offset in the light buffer).
    pub(crate) offset: Vec<u32>,
    /// Per phase, the taps' `[min dx, max dx, min dy, max dy]` (the top-left corners' extent).
    pub(crate) extent: Vec<[i32; 4]>,
    /// `dy · level_stride + dx` (wrapping): the taps' offsets in the level plane (distance
    /// penumbra).
    pub(crate) level_offset: Vec<u32>,
    /// Per row, the taps the light gather must visit: up to the last with a nonzero weight. The
    /// distance penumbra pads each level's rows to the widest level with zero taps; a zero
    /// weight adds +0 to a sum that is never −0 (weights and values are ≥ 0 and finite), so
    /// skipping trailing zero taps keeps every bit.
    pub(crate) gather_taps: Vec<u32>,
    /// Per row, the taps [`distance_rows`] must visit: up to the last that is not the zero tap at
    /// (0, 0), plus one such tap if any follows (every padding tap reads the same four level
    /// corners, so one stands for all: the same minimum).
    pub(crate) level_taps: Vec<u32>,
    /// Per row, `[−min dx, max dx, −min dy, max dy, gather_taps, level_taps, −min offset,
    /// max offset]` (offsets: its taps' [`TapColumns::offset`]s read as `i32`): every field of
    /// [`LaneRows`] is a maximum over lanes, so a chunk's summary is one 8-lane `max` per lane.
    pub(crate) summary: Vec<[i32; 8]>,
    /// The largest of every row's summary, field by field: a summary of any lanes' rows (wider
    /// extents and offset spans than theirs, which only proofs read), exact in its tap counts
    /// where `same_counts` holds.
    pub(crate) whole_summary: [i32; 8],
    /// Whether every row has the same `gather_taps` and the same `level_taps`.
    pub(crate) same_counts: bool,
    /// Every row's taps with a nonzero weight, row after row, in each row's order. A tap whose
    /// four weights are 0 adds +0 to a sum that is never −0 (see `gather_taps`), so a gather
    /// that skips it keeps every bit; a box kernel's phases are padded with many such taps.
    pub(crate) weighted: Vec<Tap>,
    /// Row r's taps in [`TapColumns::weighted`]: `weighted[start..end]`.
    pub(crate) weighted_rows: Vec<[u32; 2]>,
    /// The light buffer's and the level plane's row strides and the light buffer's pixel step
    /// the offsets were built for: the unchecked gathers check them against the buffers they
    /// read.
    pub(crate) strides: [usize; 3],
}

/// What a chunk's lanes read through their rows: the union of the rows' extents, the most taps
/// any lane's gather (and level search) visits, and whether every lane has the same row.
pub struct LaneRows {
    /// `[min dx, max dx, min dy, max dy]` over the lanes' rows.
    pub extent: [i32; 4],
    /// The largest `TapColumns::gather_taps` of the lanes' rows.
    pub gather_taps: usize,
    /// The largest `TapColumns::level_taps` of the lanes' rows.
    pub level_taps: usize,
    /// The row of every lane, when they all have the same one.
    pub uniform: Option<u32>,
    /// `[min, max]` over the lanes' rows of their taps' `TapColumns::offset`s (as `i32`).
    pub offset_span: [i64; 2],
}

impl LaneRows {
    /// The summary of the lanes' rows `rows` in `columns`.
    #[inline(always)]
    pub fn of<L: Layout>(columns: &TapColumns, rows: L::U) -> LaneRows {
        let mut r = [0u32; MAX_LANES];
        L::u_store(rows, &mut r);
        let mut most = i32x8::splat(i32::MIN);
        for &row in &r[..L::LANES] {
            most = most.max(i32x8::new(columns.summary[row as usize]));
        }
        LaneRows::from_summary(most.to_array(), L::u_uniform(rows))
    }

    /// [`LaneRows::of`] for lanes whose every read the caller knows to lie inside the grid
    /// (`interior`): where every row of `columns` visits as many taps as any other, the table's
    /// [`TapColumns::whole_summary`] without a lookup per lane (the same tap counts; its wider
    /// extent and offset span hold for any rows, and inside the grid they only prove reads).
    /// Kept apart from `of`'s body: one shared body measured +3.7 % sweep instructions.
    #[inline(always)]
    pub fn within<L: Layout>(columns: &TapColumns, rows: L::U, interior: bool) -> LaneRows {
        if !(interior && columns.same_counts) {
            return LaneRows::of::<L>(columns, rows);
        }
        // Every lane's row is a row of the table, as `of`'s lookup checks (unchecked gathers
        // by these rows rely on it).
        let highest = L::u_largest(rows);
        assert!(
            (highest as usize) < columns.phase_count,
            "row {highest} beyond the table"
        );
        LaneRows::from_summary(columns.whole_summary, L::u_uniform(rows))
    }

    /// A summary from the fieldwise largest of rows' [`TapColumns::summary`] entries.
    #[inline(always)]
    fn from_summary(m: [i32; 8], uniform: Option<u32>) -> LaneRows {
        LaneRows {
            extent: [-m[0], m[1], -m[2], m[3]],
            gather_taps: m[4] as usize,
            level_taps: m[5] as usize,
            uniform,
            offset_span: [-i64::from(m[6]), i64::from(m[7])],
        }
    }
}

impl TapColumns {
    /// The taps of row `row` with a nonzero weight, in the row's order: the taps a gather through
    /// one row for every lane must visit (`TapColumns::weighted`).
    #[inline(always)]
    pub fn weighted_taps(&self, row: u32) -> &[Tap] {
        let [start, end] = self.weighted_rows[row as usize];
        &self.weighted[start as usize..end as usize]
    }

    /// The columns of `table` for light buffers with rows `row_stride` and pixels `pixel_step`
    /// apart and level planes with rows `level_stride` apart.
    pub fn new(
        table: &KernelTable,
        row_stride: usize,
        pixel_step: usize,
        level_stride: usize,
    ) -> TapColumns {
        assert!(
            (1..=4).contains(&pixel_step),
            "a pixel pair of {pixel_step} planes exceeds 8 floats"
        );
        // Every row of every level: the per-lane gather picks a row per lane.
        let (pc, n) = (table.rows() as usize, table.taps_per_phase as usize);
        let mut columns = TapColumns {
            summary: Vec::new(),
            whole_summary: [i32::MIN; 8],
            same_counts: false,
            weighted: Vec::new(),
            weighted_rows: Vec::with_capacity(pc),
            strides: [row_stride, level_stride, pixel_step],

            phase_count: pc,
            weights: (0..n * pc)
                .map(|j| table.taps[(j % pc) * n + j / pc].w)
                .collect(),
            offset: (0..n * pc)
                .map(|j| {
                    let t = &table.taps[(j % pc) * n + j / pc];
                    let dx = t.dx as i64 * pixel_step as i64;
                    (t.dy as i64 * row_stride as i64 + dx) as i32 as u32
                })
                .collect(),
            level_offset: (0..n * pc)
                .map(|j| {
                    let t = &table.taps[(j % pc) * n + j / pc];
                    (t.dy as i64 * level_stride as i64 + t.dx as i64) as i32 as u32
                })
                .collect(),
            gather_taps: (0..pc as u32)
                .map(|p| {
                    let taps = table.phase(p);
                    let last = taps.iter().rposition(|t| t.w.iter().any(|&w| w != 0.0));
                    last.map_or(0, |i| i + 1) as u32
                })
                .collect(),
            level_taps: (0..pc as u32).map(|p| level_taps(table, p)).collect(),
            extent: (0..pc as u32)
                .map(|p| {
                    let taps = table.phase(p);
                    let (dx, dy) = (taps.iter().map(|t| t.dx), taps.iter().map(|t| t.dy));
                    [
                        dx.clone().min().unwrap_or(0),
                        dx.max().unwrap_or(0),
                        dy.clone().min().unwrap_or(0),
                        dy.max().unwrap_or(0),
                    ]
                })
                .collect(),
        };
        for row in 0..pc as u32 {
            let start = columns.weighted.len() as u32;
            let weighted = table.phase(row).iter().filter(|t| t.w != [0.0; 4]);
            columns.weighted.extend(weighted);
            columns
                .weighted_rows
                .push([start, columns.weighted.len() as u32]);
        }
        // Each row's summary from the fields above (see `summary`).
        columns.summary = (0..pc)
            .map(|row| {
                let e = columns.extent[row];
                let (g, l) = (columns.gather_taps[row], columns.level_taps[row]);
                let offsets = (0..n).map(|k| columns.offset[k * pc + row] as i32);
                let (lo, hi) = (
                    offsets.clone().min().unwrap_or(0),
                    offsets.max().unwrap_or(0),
                );
                assert!(lo > i32::MIN, "tap offset {lo} out of range");
                [-e[0], e[1], -e[2], e[3], g as i32, l as i32, -lo, hi]
            })
            .collect();
        for row in &columns.summary {
            let most = i32x8::new(columns.whole_summary).max(i32x8::new(*row));
            columns.whole_summary = most.to_array();
        }
        let counts = |v: &[u32]| v.iter().all(|&c| c == v[0]);
        columns.same_counts = counts(&columns.gather_taps) && counts(&columns.level_taps);
        columns
    }
}

/// [`gather_lanes`] where lane i uses phase `phases[i]` of `table` (per-pixel hashed phases; `columns`
/// is the same table by tap, `lane_rows` its [`LaneRows`] summary of `phases`): gathered weights and, inside the grid, gathered loads; lane
/// arithmetic in the same order.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn gather_per_lane<L: Layout>(
    planes: &LightPlanes<'_>,
    table: &KernelTable,
    columns: &TapColumns,
    phases: L::U,
    lane_rows: &LaneRows,
    shift: [i32; 2],
    x0: i32,
    y: i32,
    interior: bool,
    acc: &mut [L],
) {
    let n = lane_rows.gather_taps;
    let pc = columns.phase_count;
    let (rs, step) = (planes.row_stride, planes.pixel_step);
    // Lane 0's pixel, and lane i's offset to its pixel at the slab's shifted origin.
    let pixel = planes.base + y as usize * rs + x0 as usize * step;
    let shift_offset = shift[1] as i64 * rs as i64 + shift[0] as i64 * step as i64;
    let lane_step = L::u_mul(L::u_iota(0), L::u_splat(step as u32));
    let lane_shift = L::u_add(lane_step, L::u_splat(shift_offset as i32 as u32));
    let (w, h) = (planes.width, planes.height);
    let pair_loads = PairLoads {
        planes,
        columns,
        phases,
        pixel,
        lane_shift,
        shift: shift_offset,
        offset_span: lane_rows.offset_span,
    };
    if interior || reads_inside(lane_rows.extent, shift, x0, y, L::LANES, w, h) {
        pair_loads.add_taps(0..n, acc, Bounds::WholeRows);
        return;
    }
    let mut lane_phase = [0u32; MAX_LANES];
    L::u_store(phases, &mut lane_phase);
    for k in 0..n {
        let mut sx = [0i32; MAX_LANES];
        let mut sy = [0i32; MAX_LANES];
        for i in 0..L::LANES {
            let t = &table.phase(lane_phase[i])[k];
            sx[i] = x0 + i as i32 + t.dx + shift[0];
            sy[i] = y + t.dy + shift[1];
        }
        let (xs, ys) = (&sx[..L::LANES], &sy[..L::LANES]);
        let lowest = |v: &[i32]| v.iter().fold(i32::MAX, |m, &a| m.min(a));
        let highest = |v: &[i32]| v.iter().fold(i32::MIN, |m, &a| m.max(a));
        let tap_inside =
            lowest(xs) >= 0 && highest(xs) + 1 < w && lowest(ys) >= 0 && highest(ys) + 1 < h;
        if tap_inside {
            // Near the edge, a tap whose corners all lie inside takes the interior path's
            // loads: the same terms in the same order.
            pair_loads.add_taps(k..k + 1, acc, Bounds::PerTap);
            continue;
        }
        let w4 = L::gather4(&columns.weights[k * pc..(k + 1) * pc], phases);
        // Signed coordinates as integer lanes ([`Lane::fetch_grid`] reads them back as i32).
        let (sx, sy) = (
            L::u_load(&sx.map(|v| v as u32), 0),
            L::u_load(&sy.map(|v| v as u32), 0),
        );
        for (c, a) in acc.iter_mut().enumerate().take(planes.channels) {
            let v = fetch_corners(&planes.plane(c), sx, sy);
            *a = add_bilinear(*a, &w4, &v);
        }
    }
}

/// How [`PairLoads::add_taps`] proves its reads lie in the light buffer.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Bounds {
    /// Every tap of every lane's row reads inside the grid: one proof for them all.
    WholeRows,
    /// Only the taps added read inside: a check per tap.
    PerTap,
}

/// The per-lane gather's reads inside the grid: every plane's two pixel pairs per lane and tap
/// ([`Lane::acc_blocks`]), lane i at `pixel + lane_shift[i] +` its tap's offset.
struct PairLoads<'a, L: Layout> {
    planes: &'a LightPlanes<'a>,
    columns: &'a TapColumns,
    phases: L::U,
    pixel: usize,
    /// Lane i's offset `i + shift` to the shifted origin (wrapping; `shift` below).
    lane_shift: L::U,
    /// The slab's shift as an offset in the light buffer, `shift_y · row_stride + shift_x`.
    shift: i64,
    /// [`LaneRows::offset_span`] of the lanes' rows `phases`.
    offset_span: [i64; 2],
}

impl<L: Layout> PairLoads<'_, L> {
    /// Adds taps `taps` (every corner of every lane inside the grid) to `acc`, plane by plane.
    #[inline(always)]
    fn add_taps(&self, taps: std::ops::Range<usize>, acc: &mut [L], bounds: Bounds) {
        match self.planes.channels {
            1 => self.add_taps_to::<1>(taps, acc, bounds),
            2 => self.add_taps_to::<2>(taps, acc, bounds),
            3 => self.add_taps_to::<3>(taps, acc, bounds),
            4 => self.add_taps_to::<4>(taps, acc, bounds),
            n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
        }
    }

    /// [`PairLoads::add_taps`] for `C` planes (a constant, so that the sums stay in registers):
    /// by pixel pairs of one plane in a planar buffer, of all planes in a pixel-interleaved one
    /// whose every plane is gathered, else by gathers.
    #[inline(always)]
    fn add_taps_to<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let planes = self.planes;
        if planes.pixel_step == 1 {
            self.add_plane_pairs::<C>(taps, acc, bounds);
        } else if planes.every_plane_interleaved() {
            self.add_pixel_pairs::<C>(taps, acc, bounds);
        } else {
            self.add_gathered::<C>(taps, acc);
        }
    }

    /// [`PairLoads::add_taps_to`] in a planar buffer: every plane's two pixel pairs per lane.
    #[inline(always)]
    fn add_plane_pairs<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let planes = self.planes;
        // C sums, a constant length: copied back in registers (a run-time length was a `memcpy`
        // call, two per chunk of the default scene).
        let acc = &mut acc[..C];
        // Every plane's accumulator, in the lane type's layout for pixel-pair loads (a shuffle).
        let mut sums = [L::acc_from(L::splat(0.0)); C];
        for (sum, a) in sums.iter_mut().zip(acc.iter()) {
            *sum = L::acc_from(*a);
        }
        let plane_step = planes.plane_step;
        let (data, rs) = (planes.data, planes.row_stride);
        if bounds == Bounds::PerTap {
            for k in taps {
                let (w, rel) = self.tap(k);
                L::acc_blocks(&mut sums, &w, data, self.pixel, plane_step, rel, rs);
            }
        } else {
            // One bounds proof for every tap: the lanes' rows' offset span, moved by the lanes'
            // shifts, with no wrap in the 32-bit offsets `rel`, puts every read of every plane in
            // `data`.
            let [lo, hi] = self.offset_span;
            let (lo, hi) = (lo + self.shift, hi + self.shift + L::LANES as i64 - 1);
            let last_plane = (C as i64 - 1) * plane_step as i64;
            let (first, last) = (self.pixel as i64 + lo, self.pixel as i64 + hi + last_plane);
            assert!(
                self.columns.strides[0] == rs
                    && self.columns.strides[2] == 1
                    && lo >= i64::from(i32::MIN)
                    && hi <= i64::from(i32::MAX)
                    && first >= 0
                    && last + rs as i64 + 1 < data.len() as i64,
                "per-lane gather reads {first}..={last} outside the light buffer"
            );
            for k in taps {
                let (w, rel) = self.tap(k);
                // SAFETY: lane i reads at `pixel + rel[i]` (and + 1, + rs, + rs + 1) in each
                // plane, and rel[i] = i + shift + the offset of a tap of lane i's row, within the
                // span proved above (`LaneRows::within` of these rows, from `TapColumns::new`).
                unsafe {
                    L::acc_blocks_unchecked(&mut sums, &w, data, self.pixel, plane_step, rel, rs);
                }
            }
        }
        for (a, sum) in acc.iter_mut().zip(sums.iter()) {
            *a = L::acc_finish(*sum);
        }
    }

    /// [`PairLoads::add_taps_to`] in a pixel-interleaved buffer of `C` planes (C ≤ 4), all
    /// gathered: two lanes to a value (lanes i and i + 4, [`Lane::to_lane_pairs`]), each corner
    /// pixel's planes one 16-byte read per lane ([`load_halves`]), times its weight spread over
    /// the lane's half ([`splat_within_halves`]), added in the fixed order: top left, top right,
    /// bottom left, bottom right. Each lane's arithmetic is its own, so any pairing gives the
    /// same bits; pairs halve the multiplies and adds of one value per lane.
    #[inline(always)]
    fn add_pixel_pairs<const C: usize>(
        &self,
        taps: std::ops::Range<usize>,
        acc: &mut [L],
        bounds: Bounds,
    ) {
        let columns = self.columns;
        let (data, rs, pc) = (
            self.planes.data,
            self.planes.row_stride,
            columns.phase_count,
        );
        let mut rows = [0u32; MAX_LANES];
        let mut lane_shift = [0u32; MAX_LANES];
        L::u_store(self.phases, &mut rows);
        L::u_store(self.lane_shift, &mut lane_shift);
        let mut sums = L::to_lane_pairs::<C>(&std::array::from_fn(|c| acc[c]));
        // One value per pair of lanes (i, i + 4); one lane alone shares its value with itself
        // (the high half's sums are dropped).
        let (pairs, partner) = if L::LANES == 8 { (4, 4) } else { (L::LANES, 0) };
        let checked = bounds == Bounds::PerTap;
        if !checked {
            // One bounds proof for every tap (as `add_plane_pairs`'): lane i reads 4 floats at
            // `pixel + rel[i]`, `+ C`, `+ rs` and `+ rs + C`, all below `+ rs + 8`.
            let [lo, hi] = self.offset_span;
            let lane_span = ((L::LANES - 1) * C) as i64;
            let (lo, hi) = (lo + self.shift, hi + self.shift + lane_span);
            let (first, last) = (
                self.pixel as i64 + lo,
                self.pixel as i64 + hi + rs as i64 + 7,
            );
            assert!(
                columns.strides[0] == rs
                    && columns.strides[2] == C
                    && lo >= i64::from(i32::MIN)
                    && hi <= i64::from(i32::MAX)
                    && first >= 0
                    && last < data.len() as i64,
                "per-lane gather reads {first}..={last} outside the light buffer"
            );
        }
        // Every lane's entry `k·pc + row` lies in the columns: rows below `pc`, taps below the
        // columns' count.
        let highest = L::u_largest(self.phases);
        assert!(
            (highest as usize) < pc
                && taps.end * pc <= columns.offset.len()
                && columns.weights.len() == columns.offset.len(),
            "per-lane gather: row {highest} or tap {} beyond the columns",
            taps.end
        );
        // Lane j's reads start `rel[j]` past `pixel`.
        let rel = |entry: usize, j: usize| {
            // SAFETY: `entry` lies in the columns (checked above).
            let offset = unsafe { *columns.offset.get_unchecked(entry) };
            offset.wrapping_add(lane_shift[j]) as i32 as isize
        };
        let origin = data.as_ptr().wrapping_add(self.pixel);
        for k in taps {
            for (i, sum) in sums.iter_mut().enumerate().take(pairs) {
                let (ea, eb) = (
                    k * pc + rows[i] as usize,
                    k * pc + rows[i + partner] as usize,
                );
                let (ra, rb) = (rel(ea, i), rel(eb, i + partner));
                // SAFETY: both entries lie in the weights column (checked above).
                let w = unsafe {
                    halves(
                        columns.weights.get_unchecked(ea),
                        columns.weights.get_unchecked(eb),
                    )
                };
                let w = splat_within_halves(w);
                let corner = |by: usize| {
                    if checked {
                        let (a, b) = (self.pixel as isize + ra, self.pixel as isize + rb);
                        let (a, b) = (a as usize + by, b as usize + by);
                        let four = |at: usize| <&[f32; 4]>::try_from(&data[at..at + 4]).unwrap();
                        halves(four(a), four(b))
                    } else {
                        // SAFETY: within the span proved above: rel[i] = i·C + shift + the
                        // offset of a tap of lane i's row (`LaneRows::within`, from
                        // `TapColumns::new`), and `by + 4 ≤ rs + 8`.
                        unsafe { load_halves(origin.offset(ra).add(by), origin.offset(rb).add(by)) }
                    }
                };
                // `a += p` is `a = a + p`: no fused multiply-add (DESIGN §3).
                *sum += corner(0) * w[0];
                *sum += corner(C) * w[1];
                *sum += corner(rs) * w[2];
                *sum += corner(rs + C) * w[3];
            }
        }
        acc[..C].copy_from_slice(&L::from_lane_pairs::<C>(&sums));
    }

    /// [`PairLoads::add_taps_to`] by one gather per corner, plane and tap (some planes of a
    /// pixel-interleaved buffer: a depth plane alone), each checked.
    #[inline(always)]
    fn add_gathered<const C: usize>(&self, taps: std::ops::Range<usize>, acc: &mut [L]) {
        let planes = self.planes;
        let (step, rs) = (planes.pixel_step as u32, planes.row_stride as u32);
        for k in taps {
            let col = k * self.columns.phase_count..(k + 1) * self.columns.phase_count;
            let w = L::gather4(&self.columns.weights[col.clone()], self.phases);
            let rel = L::u_add(
                L::u_gather(&self.columns.offset[col], self.phases),
                self.lane_shift,
            );
            for (c, a) in acc.iter_mut().enumerate().take(C) {
                let origin = (self.pixel + c * planes.plane_step) as u32;
                let top_left = L::u_add(L::u_splat(origin), rel);
                let corner = |by: u32| L::gather(planes.data, L::u_add(top_left, L::u_splat(by)));
                let v = [corner(0), corner(step), corner(rs), corner(rs + step)];
                *a = add_bilinear(*a, &w, &v);
            }
        }
    }

    /// Tap k's weights for the lanes' rows and each lane's offset `rel` from `pixel`.
    #[inline(always)]
    fn tap(&self, k: usize) -> (L::W4, L::U) {
        let columns = self.columns;
        let col = k * columns.phase_count..(k + 1) * columns.phase_count;
        let w = L::weights4(&columns.weights[col.clone()], self.phases);
        let rel = L::u_add(
            L::u_gather(&columns.offset[col], self.phases),
            self.lane_shift,
        );
        (w, rel)
    }
}

/// One light's level plane of the previous slab (distance penumbra), as the gather reads it.
#[derive(Clone, Copy)]
pub struct LevelPlane<'a> {
    /// The whole plane (all rows, all lights).
    pub data: &'a [u32],
    /// The plane's 2×2 block minima, laid out as `data` ([`level_block_minima`]).
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
    /// ([`level_block_minima`] gives the corners beyond it the same `LIT_LEVEL`; a minimum is
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

/// Distance penumbra: one row of the level plane's 2×2 block minima, at pixels `xs` of every
/// light. `levels` is row y of the plane (every light's `width` levels side by side), `below`
/// row y + 1 (`None` for the last row); `out[i]` becomes the smallest of `levels[i]`,
/// `levels[i + 1]`, `below[i]` and `below[i + 1]`, where a corner beyond the grid counts as
/// [`LIT_LEVEL`] (no occluder, the largest level), as the level search's edge path reads it.
/// Built once per slab so that [`distance_rows`] reads one value per tap and lane, not four.
pub(crate) fn level_block_minima(
    levels: &[u32],
    below: Option<&[u32]>,
    width: usize,
    xs: Range<usize>,
    out: &mut [u32],
) {
    assert!(width > 0 && levels.len().is_multiple_of(width) && out.len() == levels.len());
    assert!(
        xs.start <= xs.end && xs.end <= width,
        "pixels {xs:?} of {width}"
    );
    // Pixels whose right neighbour lies in the grid, then (if in `xs`) the last pixel.
    let inner = xs.start.min(width - 1)..xs.end.min(width - 1);
    for (l, out) in out.chunks_exact_mut(width).enumerate() {
        let top = &levels[l * width..][..width];
        let bottom = below.map(|b| &b[l * width..][..width]);
        let (left, right) = (inner.clone(), inner.start + 1..inner.end + 1);
        for ((o, a), b) in out[left.clone()]
            .iter_mut()
            .zip(&top[left.clone()])
            .zip(&top[right.clone()])
        {
            *o = (*a).min(*b);
        }
        if let Some(bottom) = bottom {
            let pairs = bottom[left.clone()].iter().zip(&bottom[right]);
            for (o, (a, b)) in out[left].iter_mut().zip(pairs) {
                *o = (*o).min((*a).min(*b));
            }
        }
        if xs.end == width {
            let last = width - 1;
            out[last] = bottom.map_or(top[last], |b| top[last].min(b[last]));
        }
    }
}

/// Distance penumbra: the rows that pixels x0.. of row y gather through. A pixel takes the
/// smallest level among its own and those of every pixel its own level's kernel reads (level 0's
/// kernel when it has no occluder; pixels without one do not count): the kernel of the nearest
/// occluder in reach. So a fresh shadow's lit neighbours take its small kernel (a gather with a
/// larger one would erode it), and a pixel in a distant occluder's penumbra next to a surface
/// that was just crossed does not blur the darkness behind that surface over itself.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn distance_rows<L: Layout>(
    levels: &LevelPlane<'_>,
    table: &KernelTable,
    columns: &TapColumns,
    phase: L::U,
    slabs: u32,
    slab: u32,
    shift: [i32; 2],
    x0: i32,
    y: i32,
    interior: bool,
) -> L::U {
    let lit = L::u_splat(LIT_LEVEL);
    let zero = L::u_splat(0);
    let at = levels.base + y as usize * levels.row_stride + x0 as usize;
    let own = L::u_load(levels.data, at);
    let own_rows = level_rows::<L>(
        table,
        L::u_select(L::u_eq(own, lit), zero, own),
        phase,
        slabs,
        slab,
    );
    let mut nearest = own;
    let own_reads = LaneRows::within::<L>(columns, own_rows, interior);
    let n = own_reads.level_taps;
    let pc = columns.phase_count;
    let rs = levels.row_stride;
    let (w, h) = (levels.width, levels.height);
    if interior || reads_inside(own_reads.extent, shift, x0, y, L::LANES, w, h) {
        let lane_shift = L::u_add(
            L::u_iota(at as u32),
            L::u_splat((shift[1] as i64 * rs as i64 + shift[0] as i64) as i32 as u32),
        );
        // Each tap's four corners are one block minimum (`level_block_minima`): `min` is exact
        // and order-free, so one read gives the bits of four.
        if let Some(row) = own_reads.uniform {
            // Every lane through the same row: each tap's blocks are one contiguous load.
            let origin = at as i64 + shift[1] as i64 * rs as i64 + shift[0] as i64;
            for k in 0..n {
                let rel = columns.level_offset[k * pc + row as usize] as i32;
                let top_left = (origin + i64::from(rel)) as usize;
                nearest = L::u_min(nearest, L::u_load(levels.blocks, top_left));
            }
            let nearest = L::u_select(L::u_eq(nearest, lit), zero, nearest);
            return level_rows::<L>(table, nearest, phase, slabs, slab);
        }
        // One proof for every gather below: `LaneRows::within` checked each lane's row against
        // a table of `pc` rows (so `rel` reads inside its column), and the test above (or the
        // sweep's reach) put every corner inside the grid, whose rows lie in `levels.data`.
        assert!(
            levels.data.len() <= i32::MAX as usize
                && levels.blocks.len() == levels.data.len()
                && columns.summary.len() == pc
        );
        // Crate-internal invariants (this function is crate-private): the sweep builds the level
        // plane and the columns from one plan.
        debug_assert!(
            columns.strides[1] == rs
                && levels.base + (levels.height.max(1) as usize - 1) * rs + levels.width as usize
                    <= levels.data.len(),
            "level search: a table for another level plane, or a grid beyond its data"
        );
        for k in 0..n {
            let column = &columns.level_offset[k * pc..(k + 1) * pc];
            // SAFETY: every lane's row is below `pc` (see above).
            let rel = unsafe { L::u_gather_unchecked(column, own_rows) };
            let top_left = L::u_add(lane_shift, rel);
            // SAFETY: every corner lies inside the grid (see above), so every top-left corner
            // lies in `blocks`, laid out as `data`.
            let block = unsafe { L::u_gather_unchecked(levels.blocks, top_left) };
            nearest = L::u_min(nearest, block);
        }
    } else {
        let mut rows = [0u32; MAX_LANES];
        let mut near = [0u32; MAX_LANES];
        L::u_store(own_rows, &mut rows);
        L::u_store(nearest, &mut near);
        let inside = |x: i32, y: i32| x >= 0 && y >= 0 && x < levels.width && y < levels.height;
        let at = |x: i32, y: i32| levels.base + y as usize * rs + x as usize;
        let fetch = |x: i32, y: i32| {
            if inside(x, y) {
                levels.data[at(x, y)]
            } else {
                LIT_LEVEL
            }
        };
        for i in 0..L::LANES {
            let used = columns.level_taps[rows[i] as usize] as usize;
            for t in &table.phase(rows[i])[..used] {
                let (sx, sy) = (x0 + i as i32 + t.dx + shift[0], y + t.dy + shift[1]);
                near[i] = near[i].min(if inside(sx, sy) {
                    // Its corners beyond the grid count as LIT_LEVEL there too.
                    levels.blocks[at(sx, sy)]
                } else {
                    let corners = [(sx, sy), (sx + 1, sy), (sx, sy + 1), (sx + 1, sy + 1)];
                    corners
                        .into_iter()
                        .map(|(cx, cy)| fetch(cx, cy))
                        .fold(LIT_LEVEL, u32::min)
                });
            }
        }
        nearest = L::u_gather(&near, L::u_iota(0));
    }
    let nearest = L::u_select(L::u_eq(nearest, lit), zero, nearest);
    level_rows::<L>(table, nearest, phase, slabs, slab)
}

/// The rows of levels `level` at the lanes' phases: `level · phase_count + phase`, or for a
/// scheduled kernel the level's phase of slab `slab`, `slab_phase[level · slabs + slab]`.
#[inline(always)]
fn level_rows<L: Layout>(
    table: &KernelTable,
    level: L::U,
    phase: L::U,
    slabs: u32,
    slab: u32,
) -> L::U {
    let rows = L::u_mul(level, L::u_splat(table.phase_count));
    match table.phase_mode {
        PhaseMode::Schedule => schedule_rows::<L>(table, rows, slabs, slab),
        _ => L::u_add(rows, phase),
    }
}

/// Distance penumbra with a scheduled kernel: `rows` (level · phase_count, phase 0) moved to the
/// level's phase of slab `slab`, `slab_phase[level · slabs + slab]`.
#[inline(always)]
pub fn schedule_rows<L: Layout>(table: &KernelTable, rows: L::U, slabs: u32, slab: u32) -> L::U {
    let mut r = [0u32; MAX_LANES];
    L::u_store(rows, &mut r);
    let pc = table.phase_count;
    for v in r.iter_mut().take(L::LANES) {
        let level = *v / pc;
        *v = level * pc + table.slab_phase[(level * slabs + slab) as usize];
    }
    L::u_gather(&r, L::u_iota(0))
}

/// The per-pixel phases of pixels x0.. as integer lanes ([`phase_at`] for `PerPixel` tables): the
/// pixel hash on integer lanes.
#[inline(always)]
pub fn phases<L: Layout>(table: &KernelTable, row_hash_v: u32, x0: u32) -> L::U {
    let bits = table.phase_bits();
    if bits == 0 {
        return L::u_splat(0);
    }
    let x = L::u_iota(x0);
    let h = L::u_mix32(L::u_xor(
        L::u_splat(row_hash_v),
        L::u_mul(x, L::u_splat(0x9e37_79b9)),
    ));
    L::u_shr(h, 32 - bits)
}

#[cfg(test)]
mod tests {
    use convshadow_common::model::kernel::KernelSpec;
    use convshadow_common::pixel::lane::Lane;
    use convshadow_common::plan::kernel::{KernelMoments, build_distance_table};
    use convshadow_testkit::TestRng;
    use wide::{f32x8, u32x8};

    use super::*;

    /// A distance-penumbra table of `kernel` for 40 slabs (levels of different widths).
    fn distance_table(kernel: &str) -> KernelTable {
        let spec: KernelSpec = kernel.parse().expect("kernel");
        let per_e2 = |f: f64| KernelMoments {
            mean: [0.3 * f.sqrt(), -0.2],
            cov: [[0.35 * f, 0.1 * f], [0.1 * f, 0.2 * f]],
        };
        build_distance_table(spec, &per_e2, 40, true)
    }

    /// A `w` × `h` light buffer of three channels and a depth plane per row (`4 · w` apart).
    fn three_channels_and_depth(data: &[f32], w: usize, h: usize) -> LightPlanes<'_> {
        LightPlanes {
            data,
            base: 0,
            channels: 4,
            light_channels: 3,
            row_stride: 4 * w,
            pixel_step: 1,
            plane_step: w,
            width: w as i32,
            height: h as i32,
        }
    }

    #[test]
    fn skipped_taps_are_zero_and_the_level_search_keeps_one_padding_tap() {
        for kernel in ["box", "gaussian:7", "ellipse2", "poisson8", "ellipse3:slab"] {
            let table = distance_table(kernel);
            let columns = TapColumns::new(&table, 1000, 1, 100);
            let padding = |t: &Tap| t.dx == 0 && t.dy == 0 && t.w == [0.0; 4];
            let mut padded_rows = 0;
            for row in 0..table.rows() {
                let taps = table.phase(row);
                let (g, l) = (
                    columns.gather_taps[row as usize] as usize,
                    columns.level_taps[row as usize] as usize,
                );
                assert!(
                    g >= 1 && g <= taps.len() && l <= taps.len(),
                    "{kernel} row {row}"
                );
                assert!(
                    taps[g..].iter().all(|t| t.w == [0.0; 4]),
                    "{kernel} row {row}"
                );
                assert!(taps[l..].iter().all(padding), "{kernel} row {row}");
                // The level search keeps every read corner: one padding tap stands for the rest.
                if taps.iter().any(padding) {
                    assert!(taps[..l].iter().any(padding), "{kernel} row {row}");
                }
                padded_rows += usize::from(g < taps.len());
            }
            if kernel == "box" || kernel.starts_with("gaussian") {
                assert!(
                    padded_rows > 0,
                    "{kernel}: levels of different widths are padded"
                );
            }
        }
    }

    /// Eight rows of `table`: one row for every lane a third of the time, else each its own.
    fn random_rows(rng: &mut TestRng, table: &KernelTable) -> [u32; 8] {
        let one_row = rng.below(3) == 0;
        let first = rng.below(table.rows());
        std::array::from_fn(|_| {
            if one_row {
                first
            } else {
                rng.below(table.rows())
            }
        })
    }

    #[test]
    fn lane_rows_summarise_the_taps_of_every_lane() {
        // Against the taps themselves: the union of the lanes' extents, the most taps, uniformity.
        let mut rng = TestRng::new(3);
        for kernel in ["box", "gaussian:7", "ellipse2", "poisson8"] {
            let table = distance_table(kernel);
            let columns = TapColumns::new(&table, 1000, 1, 100);
            for _ in 0..200 {
                let rows = random_rows(&mut rng, &table);
                let got = LaneRows::of::<f32x8>(&columns, u32x8::new(rows));
                let taps = rows.map(|r| table.phase(r));
                let all = || taps.iter().flat_map(|t| t.iter());
                let extent = [
                    all().map(|t| t.dx).min().unwrap(),
                    all().map(|t| t.dx).max().unwrap(),
                    all().map(|t| t.dy).min().unwrap(),
                    all().map(|t| t.dy).max().unwrap(),
                ];
                assert_eq!(got.extent, extent, "{kernel} rows {rows:?}");
                // The offsets the gathers read (row stride 1000, as built above), as signed.
                let offsets = || all().map(|t| i64::from(t.dy) * 1000 + i64::from(t.dx));
                let span = [offsets().min().unwrap(), offsets().max().unwrap()];
                assert_eq!(got.offset_span, span, "{kernel} rows {rows:?}");
                let nonzero =
                    |t: &[Tap]| t.iter().rposition(|t| t.w != [0.0; 4]).map_or(0, |i| i + 1);
                let most = taps.iter().map(|t| nonzero(t)).max().unwrap();
                assert_eq!(got.gather_taps, most, "{kernel} rows {rows:?}");
                let level_most = rows.map(|r| columns.level_taps[r as usize]);
                assert_eq!(got.level_taps, *level_most.iter().max().unwrap() as usize);
                let same = rows.iter().all(|&r| r == rows[0]);
                assert_eq!(
                    got.uniform,
                    same.then_some(rows[0]),
                    "{kernel} rows {rows:?}"
                );
            }
        }
    }

    #[test]
    fn a_summary_inside_the_grid_visits_the_taps_of_the_lanes_own() {
        // `within` against `of`: the same row and tap counts, extents and offset spans that hold
        // theirs; and `of` itself where the reads are not known to lie inside.
        let mut rng = TestRng::new(5);
        let mut fast = 0;
        for kernel in ["box", "gaussian:7", "ellipse2", "ellipse3:slab", "poisson8"] {
            let table = distance_table(kernel);
            let columns = TapColumns::new(&table, 1000, 1, 100);
            fast += usize::from(columns.same_counts);
            for _ in 0..200 {
                let rows = random_rows(&mut rng, &table);
                let rows = u32x8::new(rows);
                let own = LaneRows::of::<f32x8>(&columns, rows);
                for interior in [false, true] {
                    let got = LaneRows::within::<f32x8>(&columns, rows, interior);
                    let why = format!("{kernel} rows {rows:?} interior {interior}");
                    assert_eq!(got.uniform, own.uniform, "{why}");
                    assert_eq!(got.gather_taps, own.gather_taps, "{why}");
                    assert_eq!(got.level_taps, own.level_taps, "{why}");
                    let (e, o) = (got.extent, own.extent);
                    let holds = e[0] <= o[0] && e[1] >= o[1] && e[2] <= o[2] && e[3] >= o[3];
                    assert!(holds, "{why}");
                    let (s, t) = (got.offset_span, own.offset_span);
                    assert!(s[0] <= t[0] && s[1] >= t[1], "{why}");
                    if !interior {
                        assert_eq!((e, s), (o, t), "{why}");
                    }
                }
            }
        }
        // The default kernel's levels all visit the same taps: it takes the path without lookups.
        assert!(TapColumns::new(&distance_table("ellipse2"), 1000, 1, 100).same_counts);
        assert!(fast < 5, "the padded kernels keep the lookup per lane");
    }

    #[test]
    #[should_panic(expected = "beyond the table")]
    fn a_row_beyond_the_table_panics_without_a_lookup_too() {
        let table = distance_table("ellipse2");
        let columns = TapColumns::new(&table, 1000, 1, 100);
        LaneRows::within::<f32x8>(&columns, f32x8::u_splat(table.rows()), true);
    }

    #[test]
    fn a_uniform_row_gathers_the_bits_of_the_per_lane_gather() {
        let (w, h) = (64usize, 40usize);
        let mut rng = TestRng::new(9);
        for kernel in ["box", "gaussian:7", "ellipse2:slab"] {
            let table = distance_table(kernel);
            // Three light channels and a depth plane per row.
            let row_stride = 4 * w;
            let data: Vec<f32> = (0..row_stride * h)
                .map(|_| rng.below(1 << 20) as f32 / (1 << 20) as f32)
                .collect();
            let columns = TapColumns::new(&table, row_stride, 1, w);
            let skips_inside = (0..table.rows())
                .any(|r| columns.weighted_taps(r).len() < columns.gather_taps[r as usize] as usize);
            // A box kernel's phases have zero taps between weighted ones: the skip is exercised.
            assert!(
                skips_inside || kernel != "box",
                "{kernel}: no zero tap to skip"
            );
            let planes = three_channels_and_depth(&data, w, h);
            for row in 0..table.rows() {
                for (x0, y) in [(20, 20), (0, 1), (w as i32 - 8, h as i32 - 2)] {
                    let shift = [rng.below(3) as i32 - 1, rng.below(3) as i32 - 1];
                    let (mut uniform, mut per_lane) =
                        ([f32x8::splat(0.0); 4], [f32x8::splat(0.0); 4]);
                    // The uniform gather skips zero taps; the per-lane one visits them all.
                    let extent = columns.extent[row as usize];
                    let taps = columns.weighted_taps(row);
                    gather_lanes(&planes, taps, extent, shift, x0, y, false, &mut uniform);
                    let rows = f32x8::u_splat(row);
                    let reads = LaneRows::of::<f32x8>(&columns, rows);
                    gather_per_lane(
                        &planes,
                        &table,
                        &columns,
                        rows,
                        &reads,
                        shift,
                        x0,
                        y,
                        false,
                        &mut per_lane,
                    );
                    for c in 0..4 {
                        let (a, b) = (uniform[c].to_array(), per_lane[c].to_array());
                        assert_eq!(
                            a.map(f32::to_bits),
                            b.map(f32::to_bits),
                            "{kernel} row {row} at ({x0}, {y}) plane {c}"
                        );
                    }
                }
            }
        }
    }

    /// `planar` (`planes` planes per row, each `w` wide, rows `planes · w` apart) with its pixels
    /// interleaved (pixel x's plane c at `x · planes + c`), and 8 floats of slack after it.
    fn interleave(planar: &[f32], w: usize, planes: usize) -> Vec<f32> {
        let mut out = vec![f32::NAN; planar.len() + 8];
        for (k, &v) in planar.iter().enumerate() {
            let (row, at) = (k / (planes * w), k % (planes * w));
            let (c, x) = (at / w, at % w);
            out[row * planes * w + x * planes + c] = v;
        }
        out
    }

    #[test]
    fn a_pixel_interleaved_buffer_gathers_the_bits_of_a_planar_one() {
        let (w, h) = (48usize, 40usize);
        let mut rng = TestRng::new(21);
        for kernel in ["ellipse2", "poisson8", "box", "gaussian:7", "ellipse2:slab"] {
            let table = distance_table(kernel);
            // Per case: the planes per pixel, the planes gathered (a depth plane alone: the
            // last) and the first of them.
            for (per_pixel, gathered, first) in [(4, 4, 0), (3, 3, 0), (2, 2, 0), (4, 1, 3)] {
                let row_stride = per_pixel * w;
                let planar: Vec<f32> = (0..row_stride * h + 8)
                    .map(|_| rng.below(1 << 20) as f32 / (1 << 20) as f32)
                    .collect();
                let pixels = interleave(&planar[..row_stride * h], w, per_pixel);
                let light = gathered.min(3 - first.min(3));
                let by_plane = LightPlanes {
                    data: &planar,
                    base: first * w,
                    channels: gathered,
                    light_channels: light,
                    row_stride,
                    pixel_step: 1,
                    plane_step: w,
                    width: w as i32,
                    height: h as i32,
                };
                let by_pixel = LightPlanes {
                    data: &pixels,
                    base: first,
                    pixel_step: per_pixel,
                    plane_step: 1,
                    ..by_plane
                };
                let planar_columns = TapColumns::new(&table, row_stride, 1, w);
                let pixel_columns = TapColumns::new(&table, row_stride, per_pixel, w);
                for _ in 0..60 {
                    let rows = f32x8::u_load(&random_rows(&mut rng, &table), 0);
                    let x0 = rng.below(w as u32 - 7) as i32;
                    let y = rng.below(h as u32) as i32;
                    let shift = [rng.below(3) as i32 - 1, rng.below(3) as i32 - 1];
                    let gather_with = |planes: &LightPlanes<'_>, columns: &TapColumns| {
                        let reads = LaneRows::of::<f32x8>(columns, rows);
                        let inside =
                            reads_inside(reads.extent, shift, x0, y, 8, w as i32, h as i32);
                        let mut per_lane = [f32x8::splat(0.0); 4];
                        let args = (shift, x0, y, inside);
                        gather_per_lane(
                            planes,
                            &table,
                            columns,
                            rows,
                            &reads,
                            args.0,
                            args.1,
                            args.2,
                            args.3,
                            &mut per_lane[..gathered],
                        );
                        // The first lane's row for every lane: the uniform gather.
                        let row = rows.to_array()[0];
                        let (taps, extent) =
                            (columns.weighted_taps(row), columns.extent[row as usize]);
                        let mut uniform = [f32x8::splat(0.0); 4];
                        gather_lanes(
                            planes,
                            taps,
                            extent,
                            shift,
                            x0,
                            y,
                            false,
                            &mut uniform[..gathered],
                        );
                        // And one pixel at a time (the scalar path's gathers).
                        let mut one = [[0.0f32; 8]; 4];
                        for (i, r) in rows.to_array().into_iter().enumerate() {
                            let lane_reads = LaneRows::of::<f32>(columns, r);
                            let mut sums = [0.0f32; 4];
                            let x = x0 + i as i32;
                            gather_per_lane(
                                planes,
                                &table,
                                columns,
                                r,
                                &lane_reads,
                                shift,
                                x,
                                y,
                                false,
                                &mut sums[..gathered],
                            );
                            for c in 0..gathered {
                                one[c][i] = sums[c];
                            }
                        }
                        let bits = |v: [f32x8; 4]| v.map(|p| p.to_array().map(f32::to_bits));
                        (
                            bits(per_lane),
                            bits(uniform),
                            one.map(|p| p.map(f32::to_bits)),
                        )
                    };
                    let want = gather_with(&by_plane, &planar_columns);
                    let got = gather_with(&by_pixel, &pixel_columns);
                    assert_eq!(
                        got, want,
                        "{kernel}, {gathered} of {per_pixel} planes, at ({x0}, {y})"
                    );
                }
                // Two chunks at once, inside the grid.
                let row = rng.below(table.rows());
                let (x0, y) = (12, 20);
                let pair = |planes: &LightPlanes<'_>, columns: &TapColumns| {
                    let (mut a, mut b) = ([f32x8::splat(0.0); 4], [f32x8::splat(0.0); 4]);
                    let (taps, extent) = (columns.weighted_taps(row), columns.extent[row as usize]);
                    let accs = [&mut a[..gathered], &mut b[..gathered]];
                    gather_inside(planes, taps, extent, [1, -1], x0, y, accs);
                    [a, b].map(|v| v.map(|p| p.to_array().map(f32::to_bits)))
                };
                assert_eq!(
                    pair(&by_pixel, &pixel_columns),
                    pair(&by_plane, &planar_columns),
                    "{kernel}, {gathered} of {per_pixel} planes, two chunks"
                );
            }
        }
    }

    #[test]
    fn stored_pixels_land_where_the_interleaved_layout_puts_them() {
        for planes in 1..=4usize {
            let values: [f32x8; 4] =
                std::array::from_fn(|c| f32x8::new(std::array::from_fn(|i| (10 * c + i) as f32)));
            let mut data = vec![-1.0f32; 3 + 8 * planes + 2];
            store_pixels(&values[..planes], &mut data, 3);
            for i in 0..8 {
                for c in 0..planes {
                    assert_eq!(
                        data[3 + i * planes + c],
                        (10 * c + i) as f32,
                        "{planes} planes"
                    );
                }
            }
            assert_eq!(&data[..3], &[-1.0; 3]);
            assert_eq!(&data[3 + 8 * planes..], &[-1.0; 2]);
            // The one-lane store writes one pixel's planes.
            let mut one = vec![-1.0f32; planes];
            let scalar: Vec<f32> = (0..planes).map(|c| c as f32).collect();
            store_pixels(&scalar, &mut one, 0);
            assert_eq!(one, scalar);
        }
    }

    #[test]
    fn a_row_run_reads_what_fetch_reads_on_either_side_of_the_grid() {
        // Narrower than, as wide as and wider than 8 lanes; runs wholly beyond, straddling and inside.
        for width in [3i32, 8, 13] {
            let (height, stride) = (3i32, width as usize + 5);
            let data: Vec<f32> = (0..stride * height as usize + 8)
                .map(|i| i as f32 + 0.5)
                .collect();
            for outside in [OUTSIDE, OUTSIDE_DEPTH] {
                let plane = Plane {
                    data: &data,
                    base: 2,
                    row_stride: stride,
                    pixel_step: 1,
                    width,
                    height,
                    outside,
                };
                for y in -1..=height {
                    for x in -10..=width + 1 {
                        let run = RowRun::at::<f32x8>(width, height, [stride, 1], x, y)
                            .read::<f32x8>(&plane)
                            .to_array();
                        let fetched: [f32; 8] =
                            std::array::from_fn(|i| plane.fetch(x + i as i32, y));
                        assert_eq!(
                            run.map(f32::to_bits),
                            fetched.map(f32::to_bits),
                            "width {width}, ({x}, {y})"
                        );
                        let one =
                            RowRun::at::<f32>(width, height, [stride, 1], x, y).read::<f32>(&plane);
                        assert_eq!(
                            one.to_bits(),
                            fetched[0].to_bits(),
                            "1 lane, width {width}, ({x}, {y})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    #[should_panic(expected = "outside the light buffer")]
    fn a_per_lane_gather_claimed_interior_at_the_corner_panics_not_reads() {
        // `interior` claimed at pixel (0, 0) with a shift up and left: the one proof per call
        // must catch the reads before the buffer, not read them unchecked.
        let table = distance_table("ellipse2");
        let (w, h) = (64usize, 40usize);
        let row_stride = 4 * w;
        let data = vec![0.5f32; row_stride * h];
        let columns = TapColumns::new(&table, row_stride, 1, w);
        let planes = three_channels_and_depth(&data, w, h);
        let rows = f32x8::u_splat(table.rows() - 1);
        let reads = LaneRows::of::<f32x8>(&columns, rows);
        let mut acc = [f32x8::splat(0.0); 4];
        let shift = [-3, -3];
        gather_per_lane(
            &planes, &table, &columns, rows, &reads, shift, 0, 0, true, &mut acc,
        );
    }
}
