//! The memory layouts of the CPU sweep's fast gathers, per lane type ([`Layout`]): the per-lane
//! gather's accumulators and pixel blocks, the order of a pixel-interleaved buffer's planes in
//! lanes, two lanes' pixels in one value's halves, a grid fetch that gives an outside value
//! beyond the grid. Each moves values only, and each 8-lane operation gives in every lane the
//! bits of the 1-lane one (`super::tests`); the 8-lane instance runs on the AVX2 intrinsics of
//! `super::avx2`.

use wide::{f32x8, u32x8};

use super::{Lane, avx2, check};

/// How lanes of [`Lane`] are read from and summed in the sweep's buffers by its fast gathers.
pub trait Layout: Lane {
    /// The per-lane gather's accumulator, in the lane type's own layout (see [`Layout::acc_blocks`]).
    type Acc: Copy;
    /// A tap's four corner weights per lane, in the layout [`Layout::acc_blocks`] reads.
    type W4: Copy;
    /// The four floats of `table[i]` per lane, as four values (a transposed gather).
    fn gather4(table: &[[f32; 4]], i: Self::U) -> [Self; 4];
    /// The weights `table[i]` of every lane, for [`Layout::acc_blocks`].
    fn weights4(table: &[[f32; 4]], i: Self::U) -> Self::W4;
    /// An accumulator holding `v`'s lanes.
    fn acc_from(v: Self) -> Self::Acc;
    /// Adds lane i's bilinear tap to each plane's accumulator `sums[c]`:
    /// `acc + w0·v00 + w1·v10 + w2·v01 + w3·v11`, left to right, where `v00, v10` are
    /// `data[at], data[at + 1]` and `v01, v11` the same `stride` further,
    /// `at = origin + c·plane_step + rel[i]` (`rel` signed); one bounds check for all planes and
    /// lanes, panicking outside `data`.
    fn acc_blocks(
        sums: &mut [Self::Acc],
        w: &Self::W4,
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: Self::U,
        stride: usize,
    );
    /// [`Layout::acc_blocks`] without its bounds check, for callers that proved the reads of many
    /// taps at once.
    ///
    /// # Safety
    /// For every plane `c < sums.len()` and lane i, `origin + c·plane_step + rel[i]` (`rel[i]`
    /// read as `i32`) is at least 0, and that index plus `stride + 1` is below `data.len()`.
    unsafe fn acc_blocks_unchecked(
        sums: &mut [Self::Acc],
        w: &Self::W4,
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: Self::U,
        stride: usize,
    );
    /// The accumulated values.
    fn acc_finish(acc: Self::Acc) -> Self;
    /// `C` planes of `LANES` pixels (lane i: pixel i) in pixel-interleaved order: value j's
    /// lane m holds plane `(j·LANES + m) mod C` of pixel `(j·LANES + m) div C`. Moves only.
    fn pixel_order<const C: usize>(planes: [Self; C]) -> [Self; C];
    /// The inverse of [`Layout::pixel_order`].
    fn plane_order<const C: usize>(pixels: [Self; C]) -> [Self; C];
    /// Plane c's lane i from slot c of half `i / 4` of `pairs[i % 4]`: per-lane sums of
    /// pixel-interleaved planes (C ≤ 4), two lanes to a value (lanes i and i + 4), as
    /// [`load_halves`] reads them.
    fn from_lane_pairs<const C: usize>(pairs: &[f32x8; 4]) -> [Self; C];
    /// The inverse of [`Layout::from_lane_pairs`] (the other slots 0, and those of lanes beyond
    /// `LANES`).
    fn to_lane_pairs<const C: usize>(planes: &[Self; C]) -> [f32x8; 4];
    /// Lane i takes lane `i + by` of `self`, or `fill` where `i + by` is not a lane (a run of
    /// values moved along a row, in registers).
    fn shift_lanes(self, by: i32, fill: f32) -> Self;
    /// Lane i: the pixel `(x[i], y[i])` (read as `i32`) of `grid`, or `outside` beyond it.
    /// Panics unless the grid lies in its data.
    fn fetch_grid(grid: &Grid<'_>, x: Self::U, y: Self::U, outside: f32) -> Self;
}

/// A `width` × `height` grid of values in `data`: pixel (x, y) at `data[base + y·stride + x·step]`
/// (a plane of a light buffer, as [`Layout::fetch_grid`] reads it).
#[derive(Clone, Copy)]
pub struct Grid<'a> {
    pub data: &'a [f32],
    pub base: usize,
    /// Distance between rows.
    pub stride: usize,
    /// Distance between a row's neighbouring pixels.
    pub step: usize,
    pub width: i32,
    pub height: i32,
}

/// Panics unless the `width` × `height` grid at `base` with rows `stride` and pixels `step`
/// apart lies in `data` (of at most `i32::MAX` values, so that its indices fit a signed 32-bit
/// gather).
#[inline(always)]
fn check_grid(len: usize, base: usize, [stride, step]: [usize; 2], width: i32, height: i32) {
    let last = (base as u64)
        .saturating_add((height.max(1) as u64 - 1).saturating_mul(stride as u64))
        .saturating_add((width.max(1) as u64 - 1).saturating_mul(step as u64))
        .saturating_add(1);
    assert!(
        last <= len as u64 && len <= i32::MAX as usize,
        "grid {width}x{height} at {base} (rows {stride} apart) outside 0..{len}"
    );
}

impl Layout for f32 {
    type Acc = f32;
    type W4 = [f32; 4];
    #[inline(always)]
    fn gather4(table: &[[f32; 4]], i: u32) -> [Self; 4] {
        table[i as usize]
    }
    #[inline(always)]
    fn weights4(table: &[[f32; 4]], i: u32) -> [f32; 4] {
        table[i as usize]
    }
    #[inline(always)]
    fn acc_from(v: f32) -> f32 {
        v
    }
    #[inline(always)]
    fn acc_blocks(
        sums: &mut [f32],
        w: &[f32; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32,
        stride: usize,
    ) {
        let first = origin as i64 + i64::from(rel as i32);
        let last_plane = (sums.len().max(1) as i64 - 1) * plane_step as i64;
        check(first, first + last_plane + stride as i64 + 1, data.len());
        // SAFETY: every plane's four reads lie in the range checked above.
        unsafe { Self::acc_blocks_unchecked(sums, w, data, origin, plane_step, rel, stride) }
    }
    #[inline(always)]
    unsafe fn acc_blocks_unchecked(
        sums: &mut [f32],
        w: &[f32; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32,
        stride: usize,
    ) {
        let first = origin.wrapping_add_signed(rel as i32 as isize);
        for (c, acc) in sums.iter_mut().enumerate() {
            let at = first + c * plane_step;
            // SAFETY: the caller guarantees that all four reads lie in `data`.
            let v = unsafe {
                [
                    *data.get_unchecked(at),
                    *data.get_unchecked(at + 1),
                    *data.get_unchecked(at + stride),
                    *data.get_unchecked(at + stride + 1),
                ]
            };
            *acc = (((*acc + w[0] * v[0]) + w[1] * v[1]) + w[2] * v[2]) + w[3] * v[3];
        }
    }
    #[inline(always)]
    fn acc_finish(acc: f32) -> f32 {
        acc
    }
    #[inline(always)]
    fn pixel_order<const C: usize>(planes: [f32; C]) -> [f32; C] {
        planes
    }
    #[inline(always)]
    fn plane_order<const C: usize>(pixels: [f32; C]) -> [f32; C] {
        pixels
    }
    #[inline(always)]
    fn from_lane_pairs<const C: usize>(pairs: &[f32x8; 4]) -> [f32; C] {
        let v = pairs[0].to_array();
        std::array::from_fn(|c| v[c])
    }
    #[inline(always)]
    fn to_lane_pairs<const C: usize>(planes: &[f32; C]) -> [f32x8; 4] {
        const { assert!(C <= 4, "a lane pair holds at most 4 planes per lane") };
        let mut pairs = [f32x8::splat(0.0); 4];
        pairs[0] = f32x8::new(std::array::from_fn(|s| if s < C { planes[s] } else { 0.0 }));
        pairs
    }
    #[inline(always)]
    fn shift_lanes(self, by: i32, fill: f32) -> f32 {
        if by == 0 { self } else { fill }
    }
    #[inline(always)]
    fn fetch_grid(grid: &Grid<'_>, x: u32, y: u32, outside: f32) -> f32 {
        let (x, y) = (x as i32, y as i32);
        if x >= 0 && y >= 0 && x < grid.width && y < grid.height {
            grid.data[grid.base + y as usize * grid.stride + x as usize * grid.step]
        } else {
            outside
        }
    }
}

impl Layout for f32x8 {
    type Acc = [f32x8; 2];
    type W4 = [f32x8; 4];
    #[inline(always)]
    fn gather4(table: &[[f32; 4]], i: u32x8) -> [Self; 4] {
        avx2::gather4(table, i)
    }
    #[inline(always)]
    fn weights4(table: &[[f32; 4]], i: u32x8) -> [f32x8; 4] {
        avx2::weights4(table, i)
    }
    #[inline(always)]
    fn acc_from(v: f32x8) -> [f32x8; 2] {
        avx2::acc_from(v)
    }
    #[inline(always)]
    fn acc_blocks(
        sums: &mut [[f32x8; 2]],
        w: &[f32x8; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32x8,
        stride: usize,
    ) {
        avx2::acc_blocks(sums, w, data, origin, plane_step, rel, stride)
    }
    #[inline(always)]
    unsafe fn acc_blocks_unchecked(
        sums: &mut [[f32x8; 2]],
        w: &[f32x8; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32x8,
        stride: usize,
    ) {
        // SAFETY: the caller guarantees that every read lies in `data`.
        unsafe { avx2::acc_blocks_unchecked(sums, w, data, origin, plane_step, rel, stride) }
    }
    #[inline(always)]
    fn acc_finish(acc: [f32x8; 2]) -> Self {
        avx2::acc_finish(acc)
    }
    #[inline(always)]
    fn pixel_order<const C: usize>(planes: [f32x8; C]) -> [f32x8; C] {
        avx2::pixel_order(planes)
    }
    #[inline(always)]
    fn plane_order<const C: usize>(pixels: [f32x8; C]) -> [f32x8; C] {
        avx2::plane_order(pixels)
    }
    #[inline(always)]
    fn from_lane_pairs<const C: usize>(pairs: &[f32x8; 4]) -> [f32x8; C] {
        avx2::from_lane_pairs(pairs)
    }
    #[inline(always)]
    fn to_lane_pairs<const C: usize>(planes: &[f32x8; C]) -> [f32x8; 4] {
        avx2::to_lane_pairs(planes)
    }
    #[inline(always)]
    fn shift_lanes(self, by: i32, fill: f32) -> f32x8 {
        avx2::shift_lanes(self, by, fill)
    }
    #[inline(always)]
    fn fetch_grid(grid: &Grid<'_>, x: u32x8, y: u32x8, outside: f32) -> f32x8 {
        let Grid {
            data,
            base,
            stride,
            step,
            width,
            height,
        } = *grid;
        if width <= 0 || height <= 0 {
            return f32x8::splat(outside);
        }
        check_grid(data.len(), base, [stride, step], width, height);
        avx2::fetch_grid(data, base, [stride, step], [width, height], x, y, outside)
    }
}

/// The 4 floats at `a` in the low half and the 4 at `b` in the high half: two lanes' pixels
/// (up to 4 planes each) side by side, as [`Layout::to_lane_pairs`] lays out their sums.
///
/// # Safety
/// `a..a + 4` and `b..b + 4` are readable.
#[inline(always)]
pub unsafe fn load_halves(a: *const f32, b: *const f32) -> f32x8 {
    // SAFETY: the caller's contract.
    unsafe { avx2::load_halves(a, b) }
}

/// [`load_halves`] of two lanes' 4 floats held by reference (a tap's corner weights `[w0, w1,
/// w2, w3]`, or a pixel's planes read with a bounds check).
#[inline(always)]
pub fn halves(a: &[f32; 4], b: &[f32; 4]) -> f32x8 {
    // SAFETY: each reference holds 4 floats.
    unsafe { avx2::load_halves(a.as_ptr(), b.as_ptr()) }
}

/// Slot k of each half of `w` spread over its half, for k = 0..4: two lanes' corner weights
/// ([`halves`]) as factors for their pixels ([`load_halves`]). One in-half permute each.
#[inline(always)]
pub fn splat_within_halves(w: f32x8) -> [f32x8; 4] {
    avx2::splat_within_halves(w)
}
