//! Stage 1, convolution: the gather of one light buffer through a kernel's tap table
//! (DESIGN §2 "Kernels"; paper §3, eq. 7). Mirrors `gpu/src/shaders/kernels.wgsl`.
//!
//! The sum order is fixed — tap by tap, corners (0,0), (1,0), (0,1), (1,1) — and each term is
//! `acc = acc + w·v` with no fused multiply-add, so every path gives the same bits.

use convshadow_common::hash::{mix32x8, phase_index, pixel_hash, row_hash};
use convshadow_common::kernel::{KernelTable, PhaseMode, Tap};
use wide::{f32x8, u32x8};

/// Value read outside the buffer: the unoccluded light.
pub const OUTSIDE: f32 = 1.0;

/// One light channel's previous buffer, as the gather reads it.
#[derive(Clone, Copy)]
pub struct Plane<'a> {
    /// The whole buffer (all rows).
    pub data: &'a [f32],
    /// Index of this plane's pixel (0, 0) in `data`.
    pub base: usize,
    /// Distance between rows in `data`.
    pub row_stride: usize,
    /// Grid width.
    pub width: i32,
    /// Grid height.
    pub height: i32,
}

impl Plane<'_> {
    /// The value at (x, y), or [`OUTSIDE`] beyond the grid.
    #[inline(always)]
    pub fn fetch(&self, x: i32, y: i32) -> f32 {
        if x >= 0 && y >= 0 && x < self.width && y < self.height {
            self.data[self.base + y as usize * self.row_stride + x as usize]
        } else {
            OUTSIDE
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

/// Gathers one channel at pixel (x, y) through `taps`, shifted by `shift`.
#[inline(always)]
pub fn gather(plane: &Plane<'_>, taps: &[Tap], shift: [i32; 2], x: i32, y: i32) -> f32 {
    let mut acc = 0.0f32;
    for t in taps {
        let sx = x + t.dx + shift[0];
        let sy = y + t.dy + shift[1];
        acc += t.w[0] * plane.fetch(sx, sy);
        acc += t.w[1] * plane.fetch(sx + 1, sy);
        acc += t.w[2] * plane.fetch(sx, sy + 1);
        acc += t.w[3] * plane.fetch(sx + 1, sy + 1);
    }
    acc
}

/// The light buffers of one light as the 8-lane gather reads them: `channels` planes of one
/// row-major grid, interleaved by row (`[row][light][channel][x]`).
#[derive(Clone, Copy)]
pub struct LightPlanes<'a> {
    /// The whole buffer (all rows).
    pub data: &'a [f32],
    /// Index of channel 0's pixel (0, 0) in `data`.
    pub base: usize,
    /// Channels of this light.
    pub channels: usize,
    /// Distance between rows in `data`.
    pub row_stride: usize,
    /// Grid width (and the distance between a row's channel planes).
    pub width: i32,
    /// Grid height.
    pub height: i32,
}

impl LightPlanes<'_> {
    /// Channel `c` as a scalar [`Plane`].
    #[inline(always)]
    pub fn plane(&self, c: usize) -> Plane<'_> {
        Plane {
            data: self.data,
            base: self.base + c * self.width as usize,
            row_stride: self.row_stride,
            width: self.width,
            height: self.height,
        }
    }
}

/// `acc + w0·v0 + w1·v1 + w2·v2 + w3·v3`, added left to right as the scalar [`gather`] does.
#[inline(always)]
fn add_bilinear(acc: f32x8, w: &[f32x8; 4], v: &[f32x8; 4]) -> f32x8 {
    let mut s = acc;
    for (wk, vk) in w.iter().zip(v) {
        s += *wk * *vk;
    }
    s
}

/// Loads 8 consecutive floats.
#[inline(always)]
fn load8(data: &[f32], at: usize) -> f32x8 {
    let a: [f32; 8] = data[at..at + 8].try_into().expect("8 floats");
    f32x8::new(a)
}

/// 8-lane [`gather`] for pixels x0..x0+8 of row y when every lane uses the same `taps`
/// (per-slab and scheduled phases): contiguous loads when `interior`, else checked fetches.
/// Adds into `acc[c]` in the scalar order, so each lane has the scalar bits.
#[inline(always)]
pub fn gather8_uniform(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    interior: bool,
    acc: &mut [f32x8],
) {
    for t in taps {
        let sx = x0 + t.dx + shift[0];
        let sy = y + t.dy + shift[1];
        let w = t.w.map(f32x8::splat);
        for (c, a) in acc.iter_mut().enumerate().take(planes.channels) {
            let v = if interior {
                let at = planes.base
                    + c * planes.width as usize
                    + sy as usize * planes.row_stride
                    + sx as usize;
                let below = at + planes.row_stride;
                [
                    load8(planes.data, at),
                    load8(planes.data, at + 1),
                    load8(planes.data, below),
                    load8(planes.data, below + 1),
                ]
            } else {
                let p = planes.plane(c);
                let lanes = |dx: i32, dy: i32| {
                    f32x8::new(std::array::from_fn(|i| {
                        p.fetch(sx + i as i32 + dx, sy + dy)
                    }))
                };
                [lanes(0, 0), lanes(1, 0), lanes(0, 1), lanes(1, 1)]
            };
            *a = add_bilinear(*a, &w, &v);
        }
    }
}

/// 8-lane [`gather`] for pixels x0..x0+8 of row y where lane i uses phase `phases[i]` of
/// `table` (per-pixel hashed phases): per-lane loads, vector arithmetic in the scalar order.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn gather8_lanes(
    planes: &LightPlanes<'_>,
    table: &KernelTable,
    phases: &[u32; 8],
    shift: [i32; 2],
    x0: i32,
    y: i32,
    interior: bool,
    acc: &mut [f32x8],
) {
    let n = table.taps_per_phase as usize;
    for k in 0..n {
        let taps: [&Tap; 8] = std::array::from_fn(|i| &table.taps[phases[i] as usize * n + k]);
        let w: [f32x8; 4] = std::array::from_fn(|j| f32x8::new(taps.map(|t| t.w[j])));
        let sx: [i32; 8] = std::array::from_fn(|i| x0 + i as i32 + taps[i].dx + shift[0]);
        let sy: [i32; 8] = std::array::from_fn(|i| y + taps[i].dy + shift[1]);
        for (c, a) in acc.iter_mut().enumerate().take(planes.channels) {
            let v = if interior {
                let base = planes.base + c * planes.width as usize;
                let at: [usize; 8] = std::array::from_fn(|i| {
                    base + sy[i] as usize * planes.row_stride + sx[i] as usize
                });
                // Each lane's two horizontal neighbours are one 8-byte load per row.
                let rs = planes.row_stride;
                let d = planes.data;
                let top: [[f32; 2]; 8] = at.map(|i| [d[i], d[i + 1]]);
                let bottom: [[f32; 2]; 8] = at.map(|i| [d[i + rs], d[i + rs + 1]]);
                [
                    f32x8::new(top.map(|p| p[0])),
                    f32x8::new(top.map(|p| p[1])),
                    f32x8::new(bottom.map(|p| p[0])),
                    f32x8::new(bottom.map(|p| p[1])),
                ]
            } else {
                let p = planes.plane(c);
                let lanes = |dx: i32, dy: i32| {
                    f32x8::new(std::array::from_fn(|i| p.fetch(sx[i] + dx, sy[i] + dy)))
                };
                [lanes(0, 0), lanes(1, 0), lanes(0, 1), lanes(1, 1)]
            };
            *a = add_bilinear(*a, &w, &v);
        }
    }
}

/// The per-pixel phases of 8 pixels x0..x0+8 (the 8-lane [`phase_at`] for `PerPixel` tables):
/// the pixel hash in u32x8 lanes.
#[inline(always)]
pub fn phases8(table: &KernelTable, row_hash_v: u32, x0: u32) -> [u32; 8] {
    let bits = table.phase_bits();
    if bits == 0 {
        return [0; 8];
    }
    let x = u32x8::new(std::array::from_fn(|i| x0 + i as u32));
    let h = mix32x8(u32x8::splat(row_hash_v) ^ (x * u32x8::splat(0x9e37_79b9)));
    (h >> (32 - bits)).to_array()
}
