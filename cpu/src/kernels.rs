//! Stage 1, convolution: the gather of one light buffer through a kernel's tap table
//! (DESIGN §2 "Kernels"; paper §3, eq. 7). Mirrors `gpu/src/shaders/kernels.wgsl`.
//!
//! The sum order is fixed — tap by tap, corners (0,0), (1,0), (0,1), (1,1) — and each term is
//! `acc = acc + w·v` with no fused multiply-add, so every path gives the same bits.

use convshadow_common::hash::{phase_index, pixel_hash, row_hash};
use convshadow_common::kernel::{KernelTable, PhaseMode, Tap};

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
