//! The lane type every per-pixel stage is written over: one generic implementation, instantiated
//! for scalar `f32` (one lane) and `wide::f32x8` (eight lanes), so the scalar and SIMD paths run
//! the same IEEE operations in the same order, lane by lane, by construction.
//!
//! Only exact operations are offered: add, sub, mul, div, floor, sign-bit tricks, compares and
//! selects, saturating truncation, wrapping integer arithmetic, loads, stores and gathers. There
//! is no `mul_add`, no `min`/`max` (they differ on ±0 between `wide` and scalar) and no libm
//! transcendental.

use std::ops::{Add, Div, Mul, Sub};

use wide::{f32x8, u32x8};

use crate::pixel::hash::{mix32, mix32x8};

/// The widest lane type's lane count: per-lane scratch arrays have this length.
pub const MAX_LANES: usize = 8;

/// A value of [`Lane::LANES`] f32 lanes, with its integer lanes [`Lane::U`] and masks [`Lane::M`].
pub trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Lanes per value.
    const LANES: usize;
    /// Unsigned integer lanes.
    type U: Copy;
    /// Comparison mask.
    type M: Copy;
    /// The per-lane gather's accumulator, in the lane type's own layout (see [`Lane::acc_blocks`]).
    type Acc: Copy;
    /// A tap's four corner weights per lane, in the layout [`Lane::acc_blocks`] reads.
    type W4: Copy;
    /// Broadcasts a float.
    fn splat(v: f32) -> Self;
    /// Rounds towards −∞.
    fn floor(self) -> Self;
    /// Clears the sign bit.
    fn abs(self) -> Self;
    /// `self > o` (false for NaN).
    fn gt(self, o: Self) -> Self::M;
    /// `self < o` (false for NaN).
    fn lt(self, o: Self) -> Self::M;
    /// Lane-wise `if m { a } else { b }`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// `(self as i32) as u32` with Rust's saturating conversion (NaN → 0).
    fn trunc_u32(self) -> Self::U;
    /// Xors `bits` into the IEEE bit pattern (used with bit 31 only: a sign flip).
    fn xor_bits(self, bits: Self::U) -> Self;
    /// Broadcasts an integer.
    fn u_splat(v: u32) -> Self::U;
    /// Wrapping add.
    fn u_add(a: Self::U, b: Self::U) -> Self::U;
    /// Wrapping multiply.
    fn u_mul(a: Self::U, b: Self::U) -> Self::U;
    /// Bitwise xor.
    fn u_xor(a: Self::U, b: Self::U) -> Self::U;
    /// Bitwise and.
    fn u_and(a: Self::U, b: Self::U) -> Self::U;
    /// Bitwise or.
    fn u_or(a: Self::U, b: Self::U) -> Self::U;
    /// Logical shift right by a constant.
    fn u_shr(a: Self::U, n: u32) -> Self::U;
    /// Shift left by a constant.
    fn u_shl(a: Self::U, n: u32) -> Self::U;
    /// `a == b` as a float-select mask.
    fn u_eq(a: Self::U, b: Self::U) -> Self::M;
    /// The smaller of `a` and `b` per lane.
    fn u_min(a: Self::U, b: Self::U) -> Self::U;
    /// `a` where `m` is set, else `b`, on integer lanes.
    fn u_select(m: Self::M, a: Self::U, b: Self::U) -> Self::U;
    /// `table[i]` per lane (bounds-checked).
    fn gather(table: &[f32], i: Self::U) -> Self;
    /// `table[i]` per integer lane (bounds-checked).
    fn u_gather(table: &[u32], i: Self::U) -> Self::U;
    /// [`Lane::u_gather`] without the bounds check, for callers that proved the indices once
    /// for many gathers.
    ///
    /// # Safety
    /// Every lane's index is below `table.len()`, and `table.len() <= i32::MAX as usize`.
    unsafe fn u_gather_unchecked(table: &[u32], i: Self::U) -> Self::U;
    /// `data[at..at + LANES]` as integer lanes (bounds-checked): [`Lane::u_gather`] at
    /// `at + u_iota(0)`, as one contiguous load.
    fn u_load(data: &[u32], at: usize) -> Self::U;
    /// The four floats of `table[i]` per lane, as four values (a transposed gather).
    fn gather4(table: &[[f32; 4]], i: Self::U) -> [Self; 4];
    /// The weights `table[i]` of every lane, for [`Lane::acc_blocks`].
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
    /// [`Lane::acc_blocks`] without its bounds check, for callers that proved the reads of many
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
    /// The inverse of [`Lane::pixel_order`].
    fn plane_order<const C: usize>(pixels: [Self; C]) -> [Self; C];
    /// Plane c's lane i from slot c of half `i / 4` of `pairs[i % 4]`: per-lane sums of
    /// pixel-interleaved planes (C ≤ 4), two lanes to a value (lanes i and i + 4), as
    /// [`load_halves`] reads them.
    fn from_lane_pairs<const C: usize>(pairs: &[f32x8; 4]) -> [Self; C];
    /// The inverse of [`Lane::from_lane_pairs`] (the other slots 0, and those of lanes beyond
    /// `LANES`).
    fn to_lane_pairs<const C: usize>(planes: &[Self; C]) -> [f32x8; 4];
    /// `self != o` (true for NaN).
    fn ne(self, o: Self) -> Self::M;
    /// Lane-wise or of two masks.
    fn m_or(a: Self::M, b: Self::M) -> Self::M;
    /// Whether any lane of the mask is set.
    fn m_any(m: Self::M) -> bool;
    /// The mask with lane i set where `flags[i]` (only the first `LANES` flags are read).
    fn m_from(flags: &[bool; MAX_LANES]) -> Self::M;
    /// `data[at..at + LANES]`.
    fn load(data: &[f32], at: usize) -> Self;
    /// `data[at..at + LANES]` without a bounds check.
    ///
    /// # Safety
    /// `at + LANES <= data.len()`.
    unsafe fn load_unchecked(data: &[f32], at: usize) -> Self;
    /// Writes the lanes to `data[at..at + LANES]`.
    fn store(self, data: &mut [f32], at: usize);
    /// Lane `i`.
    fn lane(self, i: usize) -> f32;
    /// The integer lanes `x0, x0 + 1, …` (wrapping).
    fn u_iota(x0: u32) -> Self::U;
    /// `mix32` (lowbias32) of every integer lane (see [`crate::pixel::hash::mix32`]).
    fn u_mix32(a: Self::U) -> Self::U;
    /// Writes the integer lanes to `out[..LANES]`.
    fn u_store(a: Self::U, out: &mut [u32; MAX_LANES]);
    /// The largest lane.
    fn u_largest(a: Self::U) -> u32;
    /// The lanes' value when every lane holds the same one.
    fn u_uniform(a: Self::U) -> Option<u32>;
    /// Lane i takes lane `i + by` of `self`, or `fill` where `i + by` is not a lane (a run of
    /// values moved along a row, in registers).
    fn shift_lanes(self, by: i32, fill: f32) -> Self;
    /// Lane i: the pixel `(x[i], y[i])` (read as `i32`) of the `width` × `height` grid whose pixel
    /// (x, y) is `data[base + y·stride + x·step]`, or `outside` beyond the grid. Panics unless the
    /// grid lies in `data`.
    #[allow(clippy::too_many_arguments)]
    fn fetch_grid(
        data: &[f32],
        base: usize,
        stride: usize,
        step: usize,
        width: i32,
        height: i32,
        x: Self::U,
        y: Self::U,
        outside: f32,
    ) -> Self;
}

/// Panics unless `lo..=hi` lies inside `0..len` (a gather's or block's index range).
#[inline(always)]
fn check(lo: i64, hi: i64, len: usize) {
    assert!(
        lo >= 0 && hi < len as i64,
        "gather index {lo}..={hi} outside 0..{len}"
    );
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

impl Lane for f32 {
    const LANES: usize = 1;
    type U = u32;
    type M = bool;
    type Acc = f32;
    type W4 = [f32; 4];
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32::floor(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn trunc_u32(self) -> u32 {
        self as i32 as u32
    }
    #[inline(always)]
    fn xor_bits(self, bits: u32) -> Self {
        f32::from_bits(self.to_bits() ^ bits)
    }
    #[inline(always)]
    fn u_splat(v: u32) -> u32 {
        v
    }
    #[inline(always)]
    fn u_add(a: u32, b: u32) -> u32 {
        a.wrapping_add(b)
    }
    #[inline(always)]
    fn u_mul(a: u32, b: u32) -> u32 {
        a.wrapping_mul(b)
    }
    #[inline(always)]
    fn u_xor(a: u32, b: u32) -> u32 {
        a ^ b
    }
    #[inline(always)]
    fn u_and(a: u32, b: u32) -> u32 {
        a & b
    }
    #[inline(always)]
    fn u_or(a: u32, b: u32) -> u32 {
        a | b
    }
    #[inline(always)]
    fn u_shr(a: u32, n: u32) -> u32 {
        a >> n
    }
    #[inline(always)]
    fn u_shl(a: u32, n: u32) -> u32 {
        a << n
    }
    #[inline(always)]
    fn u_eq(a: u32, b: u32) -> bool {
        a == b
    }
    #[inline(always)]
    fn u_min(a: u32, b: u32) -> u32 {
        a.min(b)
    }
    #[inline(always)]
    fn u_select(m: bool, a: u32, b: u32) -> u32 {
        if m { a } else { b }
    }
    #[inline(always)]
    fn gather(table: &[f32], i: u32) -> Self {
        table[i as usize]
    }
    #[inline(always)]
    fn u_gather(table: &[u32], i: u32) -> u32 {
        table[i as usize]
    }
    #[inline(always)]
    unsafe fn u_gather_unchecked(table: &[u32], i: u32) -> u32 {
        // SAFETY: the caller guarantees `i < table.len()`.
        unsafe { *table.get_unchecked(i as usize) }
    }
    #[inline(always)]
    fn u_load(data: &[u32], at: usize) -> u32 {
        data[at]
    }
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
    fn ne(self, o: Self) -> bool {
        self != o
    }
    #[inline(always)]
    fn m_or(a: bool, b: bool) -> bool {
        a | b
    }
    #[inline(always)]
    fn m_any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn m_from(flags: &[bool; MAX_LANES]) -> bool {
        flags[0]
    }
    #[inline(always)]
    fn load(data: &[f32], at: usize) -> Self {
        data[at]
    }
    #[inline(always)]
    unsafe fn load_unchecked(data: &[f32], at: usize) -> Self {
        // SAFETY: the caller guarantees `at < data.len()`.
        unsafe { *data.get_unchecked(at) }
    }
    #[inline(always)]
    fn store(self, data: &mut [f32], at: usize) {
        data[at] = self;
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn u_iota(x0: u32) -> u32 {
        x0
    }
    #[inline(always)]
    fn u_mix32(a: u32) -> u32 {
        mix32(a)
    }
    #[inline(always)]
    fn u_store(a: u32, out: &mut [u32; MAX_LANES]) {
        out[0] = a;
    }
    #[inline(always)]
    fn u_largest(a: u32) -> u32 {
        a
    }
    #[inline(always)]
    fn u_uniform(a: u32) -> Option<u32> {
        Some(a)
    }
    #[inline(always)]
    fn shift_lanes(self, by: i32, fill: f32) -> f32 {
        if by == 0 { self } else { fill }
    }
    #[inline(always)]
    fn fetch_grid(
        data: &[f32],
        base: usize,
        stride: usize,
        step: usize,
        width: i32,
        height: i32,
        x: u32,
        y: u32,
        outside: f32,
    ) -> f32 {
        let (x, y) = (x as i32, y as i32);
        if x >= 0 && y >= 0 && x < width && y < height {
            data[base + y as usize * stride + x as usize * step]
        } else {
            outside
        }
    }
}

impl Lane for f32x8 {
    const LANES: usize = 8;
    type U = u32x8;
    type M = f32x8;
    type Acc = [f32x8; 2];
    type W4 = [f32x8; 4];
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32x8::floor(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32x8::abs(self)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> f32x8 {
        self.simd_gt(o)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> f32x8 {
        self.simd_lt(o)
    }
    #[inline(always)]
    fn select(m: f32x8, a: Self, b: Self) -> Self {
        m.select(a, b)
    }
    #[inline(always)]
    fn trunc_u32(self) -> u32x8 {
        self.trunc_int().cast_unsigned()
    }
    #[inline(always)]
    fn xor_bits(self, bits: u32x8) -> Self {
        f32x8::from_bits(self.to_bits() ^ bits)
    }
    #[inline(always)]
    fn u_splat(v: u32) -> u32x8 {
        u32x8::splat(v)
    }
    #[inline(always)]
    fn u_add(a: u32x8, b: u32x8) -> u32x8 {
        a + b
    }
    #[inline(always)]
    fn u_mul(a: u32x8, b: u32x8) -> u32x8 {
        a * b
    }
    #[inline(always)]
    fn u_xor(a: u32x8, b: u32x8) -> u32x8 {
        a ^ b
    }
    #[inline(always)]
    fn u_and(a: u32x8, b: u32x8) -> u32x8 {
        a & b
    }
    #[inline(always)]
    fn u_or(a: u32x8, b: u32x8) -> u32x8 {
        a | b
    }
    #[inline(always)]
    fn u_shr(a: u32x8, n: u32) -> u32x8 {
        a >> n
    }
    #[inline(always)]
    fn u_shl(a: u32x8, n: u32) -> u32x8 {
        a << n
    }
    #[inline(always)]
    fn u_eq(a: u32x8, b: u32x8) -> f32x8 {
        f32x8::from_bits(a.simd_eq(b))
    }
    #[inline(always)]
    fn u_min(a: u32x8, b: u32x8) -> u32x8 {
        a.min(b)
    }
    #[inline(always)]
    fn u_select(m: f32x8, a: u32x8, b: u32x8) -> u32x8 {
        m.to_bits().select(a, b)
    }
    #[inline(always)]
    fn gather(table: &[f32], i: u32x8) -> Self {
        avx2::gather_f32(table, i)
    }
    #[inline(always)]
    fn u_gather(table: &[u32], i: u32x8) -> u32x8 {
        avx2::gather_u32(table, i)
    }
    #[inline(always)]
    unsafe fn u_gather_unchecked(table: &[u32], i: u32x8) -> u32x8 {
        // SAFETY: the caller guarantees every index lies in `table` and fits i32.
        unsafe { avx2::gather_u32_unchecked(table, i) }
    }
    #[inline(always)]
    fn u_load(data: &[u32], at: usize) -> u32x8 {
        let a: [u32; 8] = data[at..at + 8].try_into().expect("8 integers");
        u32x8::new(a)
    }
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
    fn ne(self, o: Self) -> f32x8 {
        self.simd_ne(o)
    }
    #[inline(always)]
    fn m_or(a: f32x8, b: f32x8) -> f32x8 {
        a | b
    }
    #[inline(always)]
    fn m_any(m: f32x8) -> bool {
        m.any()
    }
    #[inline(always)]
    fn m_from(flags: &[bool; MAX_LANES]) -> f32x8 {
        let on = f32::from_bits(u32::MAX);
        let mut m = [0.0f32; 8];
        for (v, &f) in m.iter_mut().zip(flags) {
            if f {
                *v = on;
            }
        }
        f32x8::new(m)
    }
    #[inline(always)]
    fn load(data: &[f32], at: usize) -> Self {
        let a: [f32; 8] = data[at..at + 8].try_into().expect("8 floats");
        f32x8::new(a)
    }
    #[inline(always)]
    unsafe fn load_unchecked(data: &[f32], at: usize) -> Self {
        // SAFETY: the caller guarantees `at + 8 <= data.len()`; an unaligned read.
        f32x8::new(unsafe { data.as_ptr().add(at).cast::<[f32; 8]>().read_unaligned() })
    }
    #[inline(always)]
    fn store(self, data: &mut [f32], at: usize) {
        let dst: &mut [f32; 8] = (&mut data[at..at + 8]).try_into().expect("8 floats");
        *dst = self.to_array();
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.to_array()[i]
    }
    #[inline(always)]
    fn u_iota(x0: u32) -> u32x8 {
        u32x8::splat(x0) + u32x8::new([0, 1, 2, 3, 4, 5, 6, 7])
    }
    #[inline(always)]
    fn u_mix32(a: u32x8) -> u32x8 {
        mix32x8(a)
    }
    #[inline(always)]
    fn u_store(a: u32x8, out: &mut [u32; MAX_LANES]) {
        *out = a.to_array();
    }
    #[inline(always)]
    fn u_largest(a: u32x8) -> u32 {
        avx2::largest(a)
    }
    #[inline(always)]
    fn u_uniform(a: u32x8) -> Option<u32> {
        // Every lane equal to lane 0: a compare with lane 0 broadcast, one mask test.
        let first = a.as_array()[0];
        a.simd_eq(u32x8::splat(first)).all().then_some(first)
    }
    #[inline(always)]
    fn shift_lanes(self, by: i32, fill: f32) -> f32x8 {
        avx2::shift_lanes(self, by, fill)
    }
    #[inline(always)]
    fn fetch_grid(
        data: &[f32],
        base: usize,
        stride: usize,
        step: usize,
        width: i32,
        height: i32,
        x: u32x8,
        y: u32x8,
        outside: f32,
    ) -> f32x8 {
        if width <= 0 || height <= 0 {
            return f32x8::splat(outside);
        }
        check_grid(data.len(), base, [stride, step], width, height);
        avx2::fetch_grid(data, base, [stride, step], [width, height], x, y, outside)
    }
}

/// The 4 floats at `a` in the low half and the 4 at `b` in the high half: two lanes' pixels
/// (up to 4 planes each) side by side, as [`Lane::to_lane_pairs`] lays out their sums.
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

/// Gathers for the 8-lane type where the build has AVX2 (`.cargo/config.toml`): one bounds check
/// for all lanes, then unchecked loads, shuffles and `vgatherdps`; without AVX2, checked loads
/// lane by lane. Loads and shuffles do not change bits, so both give the same values.
mod avx2 {
    #[cfg(target_feature = "avx2")]
    use std::arch::x86_64::*;

    #[cfg(target_feature = "avx2")]
    use wide::bytemuck::cast;
    use wide::{f32x8, u32x8};

    /// The lowest and highest lane of `rel` read as signed (`i32`) offsets, widened.
    #[inline(always)]
    fn signed_range(rel: u32x8) -> (i64, i64) {
        let v: wide::i32x8 = rel.cast_signed();
        (i64::from(v.reduce_min()), i64::from(v.reduce_max()))
    }

    use super::check;

    /// The highest of the unsigned lane indices `i`, after checking that all lie in `0..len`.
    #[inline(always)]
    fn checked_max(i: u32x8, len: usize) -> i64 {
        let hi = i64::from(i.reduce_max());
        check(0, hi, len);
        hi
    }

    /// `data[i]` per lane.
    #[inline(always)]
    pub(super) fn gather_f32(data: &[f32], i: u32x8) -> f32x8 {
        let hi = checked_max(i, data.len());
        #[cfg(target_feature = "avx2")]
        if hi <= i64::from(i32::MAX) {
            // SAFETY: every lane's index lies in 0..data.len() (checked above) and fits i32.
            return cast(unsafe { _mm256_i32gather_ps::<4>(data.as_ptr(), cast(i)) });
        }
        let a = i.to_array();
        f32x8::new(std::array::from_fn(|k| data[a[k] as usize]))
    }

    /// `table[i]` per integer lane, unchecked.
    ///
    /// # Safety
    /// Every lane's index lies in `0..table.len()`, and `table.len() <= i32::MAX as usize`.
    #[inline(always)]
    pub(super) unsafe fn gather_u32_unchecked(table: &[u32], i: u32x8) -> u32x8 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: the caller's contract.
        unsafe {
            let base = table.as_ptr().cast::<i32>();
            cast(_mm256_i32gather_epi32::<4>(base, cast(i)))
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let a = i.to_array();
            // SAFETY: the caller's contract.
            u32x8::new(std::array::from_fn(|k| unsafe {
                *table.get_unchecked(a[k] as usize)
            }))
        }
    }

    /// `table[i]` per integer lane.
    #[inline(always)]
    pub(super) fn gather_u32(table: &[u32], i: u32x8) -> u32x8 {
        let hi = checked_max(i, table.len());
        #[cfg(target_feature = "avx2")]
        if hi <= i64::from(i32::MAX) {
            // SAFETY: every lane's index lies in 0..table.len() (checked above) and fits i32.
            let base = table.as_ptr().cast::<i32>();
            return cast(unsafe { _mm256_i32gather_epi32::<4>(base, cast(i)) });
        }
        let a = i.to_array();
        u32x8::new(std::array::from_fn(|k| table[a[k] as usize]))
    }

    /// `table[i]`'s four floats per lane, transposed: eight 16-byte loads and a 4×4 transpose
    /// in each 128-bit half.
    #[inline(always)]
    pub(super) fn gather4(table: &[[f32; 4]], i: u32x8) -> [f32x8; 4] {
        checked_max(i, table.len());
        let a = i.to_array();
        #[cfg(target_feature = "avx2")]
        // SAFETY: every lane's entry lies in `table` (checked above).
        unsafe {
            let p = table.as_ptr().cast::<f32>();
            let r = |k: usize| _mm_loadu_ps(p.add(a[k] as usize * 4));
            let t0 = _mm256_set_m128(r(4), r(0));
            let t1 = _mm256_set_m128(r(5), r(1));
            let t2 = _mm256_set_m128(r(6), r(2));
            let t3 = _mm256_set_m128(r(7), r(3));
            let u0 = _mm256_unpacklo_ps(t0, t1);
            let u1 = _mm256_unpackhi_ps(t0, t1);
            let u2 = _mm256_unpacklo_ps(t2, t3);
            let u3 = _mm256_unpackhi_ps(t2, t3);
            [
                cast(_mm256_shuffle_ps::<0x44>(u0, u2)),
                cast(_mm256_shuffle_ps::<0xEE>(u0, u2)),
                cast(_mm256_shuffle_ps::<0x44>(u1, u3)),
                cast(_mm256_shuffle_ps::<0xEE>(u1, u3)),
            ]
        }
        #[cfg(not(target_feature = "avx2"))]
        [0, 1, 2, 3].map(|j| f32x8::new(std::array::from_fn(|k| table[a[k] as usize][j])))
    }

    /// Per half (lanes 0–3, 4–7), the weights interleaved by pairs: `[w0 w1]` of each lane in
    /// one value, `[w2 w3]` in another — the layout of [`acc_blocks`]'s pixel pairs. Order:
    /// `[w01 of lanes 0–3, w01 of lanes 4–7, w23 of lanes 0–3, w23 of lanes 4–7]`.
    #[inline(always)]
    pub(super) fn weights4(table: &[[f32; 4]], i: u32x8) -> [f32x8; 4] {
        checked_max(i, table.len());
        let a = i.to_array();
        #[cfg(target_feature = "avx2")]
        // SAFETY: every lane's entry lies in `table` (checked above).
        unsafe {
            let p = table.as_ptr().cast::<f64>();
            let r = |k: usize| _mm_loadu_pd(p.add(a[k] as usize * 2));
            let (r0, r1, r2, r3) = (r(0), r(1), r(2), r(3));
            let (r4, r5, r6, r7) = (r(4), r(5), r(6), r(7));
            [
                cast(_mm256_set_m128d(
                    _mm_unpacklo_pd(r2, r3),
                    _mm_unpacklo_pd(r0, r1),
                )),
                cast(_mm256_set_m128d(
                    _mm_unpacklo_pd(r6, r7),
                    _mm_unpacklo_pd(r4, r5),
                )),
                cast(_mm256_set_m128d(
                    _mm_unpackhi_pd(r2, r3),
                    _mm_unpackhi_pd(r0, r1),
                )),
                cast(_mm256_set_m128d(
                    _mm_unpackhi_pd(r6, r7),
                    _mm_unpackhi_pd(r4, r5),
                )),
            ]
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let half = |h: usize, j: usize| {
                f32x8::new(std::array::from_fn(|k| {
                    table[a[4 * h + k / 2] as usize][2 * j + k % 2]
                }))
            };
            [half(0, 0), half(1, 0), half(0, 1), half(1, 1)]
        }
    }

    /// The pixel pairs `[data[at], data[at + 1]]` of lanes `4h..4h + 4` (`at = origin +
    /// rel[lane]`), interleaved in one value. The caller has checked every pair's bounds.
    #[inline(always)]
    fn pairs(data: &[f32], origin: usize, rel: &[u32; 8], h: usize) -> f32x8 {
        let at = |lane: usize| (origin as i64 + i64::from(rel[lane] as i32)) as usize;
        #[cfg(target_feature = "avx2")]
        // SAFETY: the caller checked that both floats of every lane's pair lie in `data`.
        unsafe {
            let pair = |k: usize| data.as_ptr().add(at(4 * h + k)).cast::<f64>();
            let two = |k: usize| _mm_loadh_pd(_mm_load_sd(pair(k)), pair(k + 1));
            cast(_mm256_set_m128d(two(2), two(0)))
        }
        #[cfg(not(target_feature = "avx2"))]
        f32x8::new(std::array::from_fn(|k| data[at(4 * h + k / 2) + k % 2]))
    }

    /// Each odd slot's value moved to the even slot below it (a 64-bit shift by 32 bits).
    #[inline(always)]
    fn odd_to_even(v: f32x8) -> f32x8 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: a register shift; this build has AVX2.
        unsafe {
            cast(_mm256_srli_epi64::<32>(cast(v)))
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let a = v.to_array();
            f32x8::new(std::array::from_fn(
                |k| if k % 2 == 0 { a[k + 1] } else { 0.0 },
            ))
        }
    }

    /// [`Lane::acc_blocks`](super::Lane::acc_blocks) on pixel pairs: per half, the top row's
    /// pairs times the interleaved weights `[w0 w1]` are added to the accumulator's even slots
    /// as they are (`+ w0·v00`), then moved down one slot (`+ w1·v10`); the bottom row likewise.
    /// Each lane gets its four terms in the fixed order without a shuffle to split the pairs
    /// (the odd slots hold values nobody reads).
    #[inline(always)]
    pub(super) fn acc_blocks(
        sums: &mut [[f32x8; 2]],
        w: &[f32x8; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32x8,
        stride: usize,
    ) {
        let (lo, hi) = signed_range(rel);
        let o = origin as i64;
        let last_plane = (sums.len().max(1) as i64 - 1) * plane_step as i64;
        check(o + lo, o + last_plane + hi + stride as i64 + 1, data.len());
        // SAFETY: every read lies in `data` (checked above).
        unsafe { acc_blocks_unchecked(sums, w, data, origin, plane_step, rel, stride) }
    }

    /// [`acc_blocks`] without its check: see [`super::Lane::acc_blocks_unchecked`].
    ///
    /// # Safety
    /// As [`super::Lane::acc_blocks_unchecked`].
    #[inline(always)]
    pub(super) unsafe fn acc_blocks_unchecked(
        sums: &mut [[f32x8; 2]],
        w: &[f32x8; 4],
        data: &[f32],
        origin: usize,
        plane_step: usize,
        rel: u32x8,
        stride: usize,
    ) {
        let rel = rel.to_array();
        for (c, sum) in sums.iter_mut().enumerate() {
            let at = origin + c * plane_step;
            for (h, half) in sum.iter_mut().enumerate() {
                for (row, weights) in [(0, w[h]), (stride, w[2 + h])] {
                    let p = pairs(data, at + row, &rel, h) * weights;
                    *half = (*half + p) + odd_to_even(p);
                }
            }
        }
    }

    /// A 4×4 transpose in each 128-bit half: value r's slot c (per half) takes value c's slot r.
    #[cfg(target_feature = "avx2")]
    #[inline(always)]
    unsafe fn transpose_halves(v: [__m256; 4]) -> [__m256; 4] {
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            let t0 = _mm256_unpacklo_ps(v[0], v[1]);
            let t1 = _mm256_unpackhi_ps(v[0], v[1]);
            let t2 = _mm256_unpacklo_ps(v[2], v[3]);
            let t3 = _mm256_unpackhi_ps(v[2], v[3]);
            [
                _mm256_shuffle_ps::<0x44>(t0, t2),
                _mm256_shuffle_ps::<0xEE>(t0, t2),
                _mm256_shuffle_ps::<0x44>(t1, t3),
                _mm256_shuffle_ps::<0xEE>(t1, t3),
            ]
        }
    }

    /// Three planes' slots in the order that makes their pixel order three blends apart:
    /// plane c's pixel `ROTATED[c][s]` at slot s, so that pixel-ordered value j's slot s (plane
    /// (8j + s) mod 3) holds pixel (8j + s) div 3 of that plane.
    #[cfg(target_feature = "avx2")]
    const ROTATED: [[i32; 8]; 3] = [
        [0, 3, 6, 1, 4, 7, 2, 5],
        [5, 0, 3, 6, 1, 4, 7, 2],
        [2, 5, 0, 3, 6, 1, 4, 7],
    ];
    /// The inverse permutations of [`ROTATED`]: pixel i of plane c sits at slot
    /// `UNROTATED[c][i]`.
    #[cfg(target_feature = "avx2")]
    const UNROTATED: [[i32; 8]; 3] = [
        [0, 3, 6, 1, 4, 7, 2, 5],
        [1, 4, 7, 2, 5, 0, 3, 6],
        [2, 5, 0, 3, 6, 1, 4, 7],
    ];

    /// Slots 0, 3, 6 from `a`, 1, 4, 7 from `b`, 2, 5 from `c` (two immediate blends).
    #[cfg(target_feature = "avx2")]
    #[inline(always)]
    unsafe fn blend_thirds(a: __m256, b: __m256, c: __m256) -> __m256 {
        // SAFETY: register blends; this build has AVX2.
        unsafe { _mm256_blend_ps::<0b0010_0100>(_mm256_blend_ps::<0b1001_0010>(a, b), c) }
    }

    /// Where slot m of pixel-ordered value j comes from: (plane, pixel) = ((8j + m) mod C,
    /// (8j + m) div C).
    const fn pixel_slot(c_count: usize, j: usize, m: usize) -> (usize, usize) {
        ((8 * j + m) % c_count, (8 * j + m) / c_count)
    }

    /// [`super::Lane::pixel_order`]: a transpose by halves for 4 planes, unpacks for 2, one
    /// permute per plane and value (and blends) for 3.
    #[inline(always)]
    pub(super) fn pixel_order<const C: usize>(planes: [f32x8; C]) -> [f32x8; C] {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            let p: [__m256; C] = planes.map(cast);
            match C {
                1 => return planes,
                2 => {
                    let lo = _mm256_unpacklo_ps(p[0], p[1]);
                    let hi = _mm256_unpackhi_ps(p[0], p[1]);
                    let out = [
                        _mm256_permute2f128_ps::<0x20>(lo, hi),
                        _mm256_permute2f128_ps::<0x31>(lo, hi),
                    ];
                    return std::array::from_fn(|j| cast(out[j]));
                }
                4 => {
                    let u = transpose_halves([p[0], p[1], p[2], p[3]]);
                    let out = [
                        _mm256_permute2f128_ps::<0x20>(u[0], u[1]),
                        _mm256_permute2f128_ps::<0x20>(u[2], u[3]),
                        _mm256_permute2f128_ps::<0x31>(u[0], u[1]),
                        _mm256_permute2f128_ps::<0x31>(u[2], u[3]),
                    ];
                    return std::array::from_fn(|j| cast(out[j]));
                }
                3 => {
                    // Each plane rotated once (ROTATED), then every value three blends.
                    let [r, g, b] =
                        [0, 1, 2].map(|c| _mm256_permutevar8x32_ps(p[c], cast(ROTATED[c])));
                    let out = [
                        blend_thirds(r, g, b),
                        blend_thirds(b, r, g),
                        blend_thirds(g, b, r),
                    ];
                    return std::array::from_fn(|j| cast(out[j]));
                }
                _ => {}
            }
        }
        #[allow(unreachable_code)]
        {
            let a = planes.map(|v| v.to_array());
            std::array::from_fn(|j| {
                f32x8::new(std::array::from_fn(|m| {
                    let (c, i) = pixel_slot(C, j, m);
                    a[c][i]
                }))
            })
        }
    }

    /// [`super::Lane::plane_order`]: the inverse of [`pixel_order`], the same way.
    #[inline(always)]
    pub(super) fn plane_order<const C: usize>(pixels: [f32x8; C]) -> [f32x8; C] {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            let v: [__m256; C] = pixels.map(cast);
            match C {
                1 => return pixels,
                2 => {
                    let u0 = _mm256_permute2f128_ps::<0x20>(v[0], v[1]);
                    let u1 = _mm256_permute2f128_ps::<0x31>(v[0], v[1]);
                    let out = [
                        _mm256_shuffle_ps::<0x88>(u0, u1),
                        _mm256_shuffle_ps::<0xDD>(u0, u1),
                    ];
                    return std::array::from_fn(|c| cast(out[c]));
                }
                4 => {
                    let out = transpose_halves([
                        _mm256_permute2f128_ps::<0x20>(v[0], v[2]),
                        _mm256_permute2f128_ps::<0x31>(v[0], v[2]),
                        _mm256_permute2f128_ps::<0x20>(v[1], v[3]),
                        _mm256_permute2f128_ps::<0x31>(v[1], v[3]),
                    ]);
                    return std::array::from_fn(|c| cast(out[c]));
                }
                3 => {
                    // [`pixel_order`]'s blends undone (each plane's slots, rotated), then each
                    // plane's rotation (UNROTATED).
                    let rotated = [
                        blend_thirds(v[0], v[1], v[2]),
                        blend_thirds(v[2], v[0], v[1]),
                        blend_thirds(v[1], v[2], v[0]),
                    ];
                    let out: [__m256; 3] = std::array::from_fn(|c| {
                        _mm256_permutevar8x32_ps(rotated[c], cast(UNROTATED[c]))
                    });
                    return std::array::from_fn(|c| cast(out[c]));
                }
                _ => {}
            }
        }
        #[allow(unreachable_code)]
        {
            let a = pixels.map(|v| v.to_array());
            std::array::from_fn(|c| {
                f32x8::new(std::array::from_fn(|i| {
                    let at = i * C + c;
                    a[at / 8][at % 8]
                }))
            })
        }
    }

    /// [`super::Lane::from_lane_pairs`]: a transpose by halves (C ≤ 4).
    #[inline(always)]
    pub(super) fn from_lane_pairs<const C: usize>(pairs: &[f32x8; 4]) -> [f32x8; C] {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            let out = transpose_halves(pairs.map(cast));
            return std::array::from_fn(|c| cast(out[c]));
        }
        #[allow(unreachable_code)]
        {
            let a = pairs.map(|v| v.to_array());
            std::array::from_fn(|c| f32x8::new(std::array::from_fn(|i| a[i % 4][4 * (i / 4) + c])))
        }
    }

    /// [`super::Lane::to_lane_pairs`]: the inverse of [`from_lane_pairs`] (slots from C on 0).
    #[inline(always)]
    pub(super) fn to_lane_pairs<const C: usize>(planes: &[f32x8; C]) -> [f32x8; 4] {
        const { assert!(C <= 4, "a lane pair holds at most 4 planes per lane") };
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            let p: [__m256; 4] = std::array::from_fn(|c| {
                if c < C {
                    cast(planes[c])
                } else {
                    _mm256_setzero_ps()
                }
            });
            return transpose_halves(p).map(cast);
        }
        #[allow(unreachable_code)]
        {
            let a = planes.map(|v| v.to_array());
            std::array::from_fn(|k| {
                f32x8::new(std::array::from_fn(|s| {
                    let (lane, c) = (k + 4 * (s / 4), s % 4);
                    if c < C { a[c][lane] } else { 0.0 }
                }))
            })
        }
    }

    /// [`super::load_halves`]: one 16-byte load and one inserted.
    ///
    /// # Safety
    /// `a..a + 4` and `b..b + 4` are readable.
    #[inline(always)]
    pub(super) unsafe fn load_halves(a: *const f32, b: *const f32) -> f32x8 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: the caller's contract; unaligned 16-byte reads.
        unsafe {
            return cast(_mm256_loadu2_m128(b, a));
        }
        #[allow(unreachable_code)]
        // SAFETY: the caller's contract.
        unsafe {
            let (lo, hi) = (
                a.cast::<[f32; 4]>().read_unaligned(),
                b.cast::<[f32; 4]>().read_unaligned(),
            );
            f32x8::new([lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]])
        }
    }

    /// [`super::splat_within_halves`]: one in-half permute per slot.
    #[inline(always)]
    pub(super) fn splat_within_halves(w: f32x8) -> [f32x8; 4] {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register permutes; this build has AVX2.
        unsafe {
            let v: __m256 = cast(w);
            return [
                cast(_mm256_permute_ps::<0x00>(v)),
                cast(_mm256_permute_ps::<0x55>(v)),
                cast(_mm256_permute_ps::<0xAA>(v)),
                cast(_mm256_permute_ps::<0xFF>(v)),
            ];
        }
        #[allow(unreachable_code)]
        {
            let a = w.to_array();
            std::array::from_fn(|k| f32x8::new(std::array::from_fn(|s| a[4 * (s / 4) + k])))
        }
    }

    /// [`super::Lane::u_largest`]: three maxima of halves (`wide`'s `reduce_max` goes lane by
    /// lane).
    #[inline(always)]
    pub(super) fn largest(a: u32x8) -> u32 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles and maxima; this build has AVX2.
        unsafe {
            let v: __m256i = cast(a);
            let m = _mm_max_epu32(_mm256_castsi256_si128(v), _mm256_extracti128_si256::<1>(v));
            let m = _mm_max_epu32(m, _mm_shuffle_epi32::<0b01_00_11_10>(m));
            let m = _mm_max_epu32(m, _mm_shuffle_epi32::<0b10_11_00_01>(m));
            return _mm_cvtsi128_si32(m) as u32;
        }
        #[allow(unreachable_code)]
        a.reduce_max()
    }

    /// [`super::Lane::shift_lanes`]: one permute and one blend.
    #[inline(always)]
    pub(super) fn shift_lanes(v: f32x8, by: i32, fill: f32) -> f32x8 {
        let from = wide::i32x8::new(std::array::from_fn(|i| i as i32)) + wide::i32x8::splat(by);
        #[cfg(target_feature = "avx2")]
        // SAFETY: register permutes and compares; this build has AVX2.
        unsafe {
            let from: __m256i = cast(from);
            // Lanes whose source is outside 0..8: all ones where from < 0 or from > 7.
            let beyond = _mm256_or_si256(
                _mm256_cmpgt_epi32(_mm256_setzero_si256(), from),
                _mm256_cmpgt_epi32(from, _mm256_set1_epi32(7)),
            );
            let moved = _mm256_permutevar8x32_ps(cast(v), from);
            cast(_mm256_blendv_ps(
                moved,
                _mm256_set1_ps(fill),
                _mm256_castsi256_ps(beyond),
            ))
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let (a, from) = (v.to_array(), from.to_array());
            f32x8::new(std::array::from_fn(|i| {
                if (0..8).contains(&from[i]) {
                    a[from[i] as usize]
                } else {
                    fill
                }
            }))
        }
    }

    /// [`super::Lane::fetch_grid`] once the grid (`size` = [width, height], both > 0) has been
    /// checked to lie in `data`: a masked `vgatherdps` of the lanes inside the grid.
    #[inline(always)]
    pub(super) fn fetch_grid(
        data: &[f32],
        base: usize,
        [stride, step]: [usize; 2],
        size: [i32; 2],
        x: u32x8,
        y: u32x8,
        outside: f32,
    ) -> f32x8 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: the lanes read are inside the grid (unsigned x < width and y < height: a
        // negative coordinate reads as ≥ 2^31), whose pixels the caller checked lie in `data`,
        // of at most i32::MAX values: the signed 32-bit indices are exact.
        unsafe {
            let (xi, yi): (__m256i, __m256i) = (cast(x), cast(y));
            let below = |v: __m256i, n: i32| {
                _mm256_cmpeq_epi32(_mm256_min_epu32(v, _mm256_set1_epi32(n - 1)), v)
            };
            let inside = _mm256_and_si256(below(xi, size[0]), below(yi, size[1]));
            let times = |v: __m256i, n: usize| _mm256_mullo_epi32(v, _mm256_set1_epi32(n as i32));
            let at = _mm256_add_epi32(
                _mm256_add_epi32(times(yi, stride), times(xi, step)),
                _mm256_set1_epi32(base as i32),
            );
            cast(_mm256_mask_i32gather_ps::<4>(
                _mm256_set1_ps(outside),
                data.as_ptr(),
                at,
                _mm256_castsi256_ps(inside),
            ))
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let (x, y) = (x.to_array(), y.to_array());
            f32x8::new(std::array::from_fn(|i| {
                let (x, y) = (x[i] as i32, y[i] as i32);
                if x >= 0 && y >= 0 && x < size[0] && y < size[1] {
                    data[base + y as usize * stride + x as usize * step]
                } else {
                    outside
                }
            }))
        }
    }

    /// Lanes 0–3 and 4–7 of `v` in the even slots of two values (odd slots get copies).
    #[inline(always)]
    pub(super) fn acc_from(v: f32x8) -> [f32x8; 2] {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            // [l0 l1 l4 l5 | l2 l3 l6 l7], then each float doubled within its half.
            let v = _mm256_castpd_ps(_mm256_permute4x64_pd::<0xD8>(cast(v)));
            [
                cast(_mm256_unpacklo_ps(v, v)),
                cast(_mm256_unpackhi_ps(v, v)),
            ]
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let a = v.to_array();
            [0, 1].map(|h| f32x8::new(std::array::from_fn(|k| a[4 * h + k / 2])))
        }
    }

    /// The even slots of the two halves: lanes 0–7 in order.
    #[inline(always)]
    pub(super) fn acc_finish(acc: [f32x8; 2]) -> f32x8 {
        #[cfg(target_feature = "avx2")]
        // SAFETY: register shuffles; this build has AVX2.
        unsafe {
            // [l0 l1 l4 l5 | l2 l3 l6 l7] → 64-bit chunks reordered 0, 2, 1, 3.
            let even = _mm256_shuffle_ps::<0x88>(cast(acc[0]), cast(acc[1]));
            cast(_mm256_permute4x64_pd::<0xD8>(_mm256_castps_pd(even)))
        }
        #[cfg(not(target_feature = "avx2"))]
        {
            let (a, b) = (acc[0].to_array(), acc[1].to_array());
            f32x8::new(std::array::from_fn(|k| {
                if k < 4 { a[2 * k] } else { b[2 * (k - 4)] }
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floats of every kind: ordinary, ±0, ±∞, NaN, subnormal, huge; from a `mix32` counter.
    fn floats(seed: u32) -> [f32; MAX_LANES] {
        let special = [
            0.0,
            -0.0,
            f32::INFINITY,
            -f32::INFINITY,
            f32::NAN,
            1e-40,
            3e9,
            -2.5,
        ];
        let mut out = [0.0f32; MAX_LANES];
        for (i, v) in out.iter_mut().enumerate() {
            let h = mix32(seed.wrapping_mul(8).wrapping_add(i as u32));
            *v = match h % 4 {
                0 => special[(h >> 8) as usize % special.len()],
                1 => f32::from_bits(h),
                _ => (h >> 8) as f32 / 65536.0 - 128.0,
            };
        }
        out
    }

    /// Each lane of `eight` has the bits of `one` on that lane's inputs.
    /// NaNs agree with any NaN: which operand's payload an operation on two NaNs returns is
    /// not fixed by IEEE 754, and the compiler may swap the operands of `+` and `*` (it does in
    /// the AVX2 build). The pipeline never lets a NaN reach a pixel, so payloads are no part of
    /// the bit contract.
    fn agree(eight: f32x8, one: impl Fn(usize) -> f32, what: &str) {
        let e = eight.to_array();
        for (i, v) in e.iter().enumerate() {
            let o = one(i);
            if v.is_nan() && o.is_nan() {
                continue;
            }
            assert_eq!(v.to_bits(), o.to_bits(), "{what}, lane {i}");
        }
    }

    #[test]
    fn eight_lanes_give_the_bits_of_one_lane() {
        for seed in 0..2000 {
            let (a, b) = (floats(seed), floats(seed + 7919));
            let (va, vb) = (f32x8::new(a), f32x8::new(b));
            agree(va + vb, |i| a[i] + b[i], "add");
            agree(va * vb, |i| a[i] * b[i], "mul");
            agree(va / vb, |i| a[i] / b[i], "div");
            agree(Lane::floor(va), |i| Lane::floor(a[i]), "floor");
            agree(Lane::abs(va), |i| Lane::abs(a[i]), "abs");
            let m = va.gt(vb);
            agree(
                <f32x8 as Lane>::select(m, va, vb),
                |i| if a[i] > b[i] { a[i] } else { b[i] },
                "gt",
            );
            let m = <f32x8 as Lane>::m_or(va.lt(vb), va.ne(vb));
            agree(
                <f32x8 as Lane>::select(m, va, vb),
                |i| {
                    <f32 as Lane>::select(
                        <f32 as Lane>::m_or(a[i].lt(b[i]), a[i].ne(b[i])),
                        a[i],
                        b[i],
                    )
                },
                "lt, ne, or",
            );
            let t = va.trunc_u32().to_array();
            for i in 0..MAX_LANES {
                assert_eq!(t[i], a[i].trunc_u32(), "trunc lane {i}");
            }
            let mut h = [0u32; MAX_LANES];
            f32x8::u_store(f32x8::u_mix32(f32x8::u_iota(seed)), &mut h);
            for (i, v) in h.iter().enumerate() {
                assert_eq!(
                    *v,
                    f32::u_mix32(f32::u_iota(seed + i as u32)),
                    "mix32 lane {i}"
                );
            }
            let idx: [u32; MAX_LANES] = std::array::from_fn(|i| h[i] % 16);
            let data: Vec<f32> = (0..16).map(|k| floats(seed + k)[k as usize % 8]).collect();
            agree(
                f32x8::gather(&data, u32x8::new(idx)),
                |i| f32::gather(&data, idx[i]),
                "gather",
            );
        }
    }

    /// Unit-range floats, exact 0 and 1 one time in eight each (light values and weights).
    fn unit(h: u32) -> f32 {
        match h % 8 {
            0 => 0.0,
            1 => 1.0,
            _ => (h >> 8) as f32 / 16_777_216.0,
        }
    }

    #[test]
    fn shifted_lanes_take_their_neighbours_or_the_fill() {
        let v = f32x8::new(std::array::from_fn(|i| i as f32 + 0.25));
        for by in -9..=9 {
            let got = v.shift_lanes(by, -1.0).to_array();
            let want: [f32; 8] = std::array::from_fn(|i| {
                let from = i as i32 + by;
                if (0..8).contains(&from) {
                    from as f32 + 0.25
                } else {
                    -1.0
                }
            });
            assert_eq!(got, want, "by {by}");
            assert_eq!(
                2.5f32.shift_lanes(by, -1.0),
                if by == 0 { 2.5 } else { -1.0 }
            );
        }
    }

    #[test]
    fn a_grid_fetch_reads_inside_and_gives_the_outside_value_beyond() {
        let (width, height, stride, base) = (13i32, 5i32, 53usize, 3usize);
        let data: Vec<f32> = (0..base + 4 * stride + 13 * 4)
            .map(|k| k as f32 + 0.5)
            .collect();
        // Planar rows (pixels 1 apart) and pixel-interleaved ones (pixels 4 apart).
        for (seed, step) in (0..2000u32).flat_map(|s| [(s, 1usize), (s, 4)]) {
            let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32));
            // Coordinates from −4 to width + 3 (and height + 3), and now and then far beyond.
            let coord = |v: u32, n: i32| match v % 16 {
                0 => i32::MIN + (v >> 8) as i32,
                1 => i32::MAX - (v >> 8) as i32,
                _ => (v >> 4) as i32 % (n + 8) - 4,
            };
            let x = h.map(|v| coord(v, width) as u32);
            let y = h.map(|v| coord(mix32(v), height) as u32);
            let got = f32x8::fetch_grid(
                &data,
                base,
                stride,
                step,
                width,
                height,
                u32x8::new(x),
                u32x8::new(y),
                -1.0,
            );
            agree(
                got,
                |i| {
                    let (xi, yi) = (x[i] as i32, y[i] as i32);
                    let inside = (0..width).contains(&xi) && (0..height).contains(&yi);
                    let want = if inside {
                        data[base + yi as usize * stride + xi as usize * step]
                    } else {
                        -1.0
                    };
                    let (w, h) = (width, height);
                    let one = f32::fetch_grid(&data, base, stride, step, w, h, x[i], y[i], -1.0);
                    assert_eq!(one.to_bits(), want.to_bits(), "one lane at ({xi}, {yi})");
                    want
                },
                "fetch_grid",
            );
        }
    }

    /// [`Lane::pixel_order`], [`Lane::plane_order`], [`Lane::from_lane_pairs`] and
    /// [`Lane::to_lane_pairs`] of `C` planes against their definitions, element by element.
    fn check_orders<const C: usize>() {
        let planes: [f32x8; C] =
            std::array::from_fn(|c| f32x8::new(std::array::from_fn(|i| (10 * c + i) as f32)));
        let pixels = f32x8::pixel_order(planes);
        for (j, v) in pixels.iter().enumerate() {
            for (m, got) in v.to_array().into_iter().enumerate() {
                let (c, i) = ((8 * j + m) % C, (8 * j + m) / C);
                assert_eq!(got, (10 * c + i) as f32, "{C} planes: value {j} slot {m}");
            }
        }
        let back = f32x8::plane_order(pixels).map(|v| v.to_array());
        assert_eq!(back, planes.map(|v| v.to_array()), "{C} planes back");
        let pairs = f32x8::to_lane_pairs(&planes);
        for (k, v) in pairs.iter().enumerate() {
            for (s, got) in v.to_array().into_iter().enumerate() {
                let (lane, c) = (k + 4 * (s / 4), s % 4);
                let want = if c < C { (10 * c + lane) as f32 } else { 0.0 };
                assert_eq!(got, want, "{C} planes: value {k} slot {s}");
            }
        }
        let from = f32x8::from_lane_pairs::<C>(&pairs).map(|v| v.to_array());
        assert_eq!(
            from,
            planes.map(|v| v.to_array()),
            "{C} planes from lane pairs"
        );
        // One lane: plane order is pixel order, and lane 0's sums are its planes.
        let one: [f32; C] = std::array::from_fn(|c| c as f32 + 0.5);
        assert_eq!(f32::pixel_order(one), one);
        assert_eq!(f32::plane_order(one), one);
        assert_eq!(f32::from_lane_pairs::<C>(&f32::to_lane_pairs(&one)), one);
    }

    #[test]
    fn orders_of_pixel_interleaved_planes_move_every_value_where_defined() {
        check_orders::<1>();
        check_orders::<2>();
        check_orders::<3>();
        check_orders::<4>();
    }

    #[test]
    fn halves_hold_two_lanes_reads_and_each_halfs_weights_spread_over_it() {
        let data: Vec<f32> = (0..64u32).map(|k| unit(mix32(k ^ 0x77))).collect();
        for (a, b) in [(0usize, 60usize), (13, 2), (7, 7), (59, 31)] {
            // SAFETY: a + 4 and b + 4 are at most 64 = data.len().
            let got = unsafe { load_halves(data.as_ptr().add(a), data.as_ptr().add(b)) };
            let want: [f32; 8] =
                std::array::from_fn(|s| data[if s < 4 { a + s } else { b + s - 4 }]);
            assert_eq!(got.to_array(), want, "reads at {a} and {b}");
        }
        let (wa, wb) = ([0.5f32, 0.25, 0.125, 0.0625], [1.0f32, 2.0, 3.0, 4.0]);
        let both = halves(&wa, &wb);
        assert_eq!(
            both.to_array(),
            [0.5, 0.25, 0.125, 0.0625, 1.0, 2.0, 3.0, 4.0]
        );
        for (k, spread) in splat_within_halves(both).iter().enumerate() {
            let want: [f32; 8] = std::array::from_fn(|s| if s < 4 { wa[k] } else { wb[k] });
            assert_eq!(spread.to_array(), want, "corner {k}");
        }
    }

    #[test]
    fn eight_lane_gathers_and_blocks_give_the_bits_of_one_lane() {
        let data: Vec<f32> = (0..4096u32).map(|k| unit(mix32(k ^ 0x5151))).collect();
        let table: Vec<[f32; 4]> = (0..64u32)
            .map(|k| std::array::from_fn(|j| unit(mix32(k * 4 + j as u32))))
            .collect();
        let ints: Vec<u32> = (0..64u32).map(|k| mix32(k + 99)).collect();
        let stride = 61;
        for seed in 0..500u32 {
            let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32));
            let phase = u32x8::new(h.map(|v| v % 64));
            let ph = phase.to_array();
            agree(
                f32x8::gather(&data, u32x8::new(h.map(|v| v % 4096))),
                |i| f32::gather(&data, h[i] % 4096),
                "gather",
            );
            let mut out = [0u32; MAX_LANES];
            f32x8::u_store(f32x8::u_gather(&ints, phase), &mut out);
            for i in 0..MAX_LANES {
                assert_eq!(out[i], f32::u_gather(&ints, ph[i]), "u_gather lane {i}");
            }
            // SAFETY: every index is below 64 = ints.len().
            f32x8::u_store(unsafe { f32x8::u_gather_unchecked(&ints, phase) }, &mut out);
            for i in 0..MAX_LANES {
                // SAFETY: as above.
                let one = unsafe { f32::u_gather_unchecked(&ints, ph[i]) };
                assert_eq!((out[i], one), (ints[ph[i] as usize], ints[ph[i] as usize]));
            }
            let at = (h[0] % 56) as usize;
            f32x8::u_store(f32x8::u_load(&ints, at), &mut out);
            for (i, v) in out.iter().enumerate() {
                assert_eq!(*v, f32::u_load(&ints, at + i), "u_load lane {i}");
            }
            let four = f32x8::gather4(&table, phase);
            for (j, v) in four.iter().enumerate() {
                agree(*v, |i| f32::gather4(&table, ph[i])[j], "gather4");
            }
            // Two taps into an accumulator that starts at arbitrary values; signed offsets.
            let origin = 2000;
            let start = f32x8::new(std::array::from_fn(|i| unit(h[i] >> 3)));
            let mut eight = f32x8::acc_from(start);
            let mut one: [f32; MAX_LANES] = start.to_array();
            for tap in 0..2u32 {
                let rel: [u32; MAX_LANES] =
                    std::array::from_fn(|i| ((mix32(h[i] + tap) % 1500) as i32 - 750) as u32);
                let w8 = f32x8::weights4(&table, phase + u32x8::splat(0));
                let mut sums = [eight];
                f32x8::acc_blocks(&mut sums, &w8, &data, origin, 0, u32x8::new(rel), stride);
                // The unchecked blocks read the same values (every read here lies in `data`).
                let mut unchecked = [eight];
                // SAFETY: origin ± 750 plus stride + 1 lies in 0..4096.
                unsafe {
                    f32x8::acc_blocks_unchecked(
                        &mut unchecked,
                        &w8,
                        &data,
                        origin,
                        0,
                        u32x8::new(rel),
                        stride,
                    );
                }
                agree(
                    f32x8::acc_finish(unchecked[0]),
                    |i| f32x8::acc_finish(sums[0]).to_array()[i],
                    "acc_blocks_unchecked",
                );
                eight = sums[0];
                for i in 0..MAX_LANES {
                    let w1 = f32::weights4(&table, ph[i]);
                    let mut s1 = [one[i]];
                    f32::acc_blocks(&mut s1, &w1, &data, origin, 0, rel[i], stride);
                    let mut u1 = [one[i]];
                    // SAFETY: as above.
                    unsafe {
                        f32::acc_blocks_unchecked(&mut u1, &w1, &data, origin, 0, rel[i], stride);
                    }
                    assert_eq!(
                        u1[0].to_bits(),
                        s1[0].to_bits(),
                        "one-lane unchecked blocks"
                    );
                    one[i] = s1[0];
                }
            }
            agree(f32x8::acc_finish(eight), |i| one[i], "acc_blocks");
        }
    }

    #[test]
    fn the_largest_lane_and_a_uniform_value_are_those_of_the_lanes() {
        for seed in 0..300u32 {
            // Small values, so that equal lanes are common; some chunks all equal.
            let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32) % 3);
            let lanes = if seed % 4 == 0 { [h[0]; MAX_LANES] } else { h };
            let lanes = lanes.map(|v| v.wrapping_mul(0x8000_0001));
            let v = u32x8::new(lanes);
            assert_eq!(f32x8::u_largest(v), *lanes.iter().max().unwrap());
            let same = lanes.iter().all(|&x| x == lanes[0]);
            assert_eq!(f32x8::u_uniform(v), same.then_some(lanes[0]), "{lanes:?}");
            assert_eq!(
                (f32::u_largest(lanes[3]), f32::u_uniform(lanes[3])),
                (lanes[3], Some(lanes[3]))
            );
        }
        // Full-range values, the largest in each lane in turn (the reduction visits every lane).
        for at in 0..8 {
            for seed in 0..50u32 {
                let mut lanes: [u32; 8] = std::array::from_fn(|i| mix32(seed * 8 + i as u32) >> 1);
                lanes[at] = u32::MAX - seed;
                assert_eq!(
                    f32x8::u_largest(u32x8::new(lanes)),
                    u32::MAX - seed,
                    "{lanes:?}"
                );
            }
        }
    }

    #[test]
    #[should_panic(expected = "outside")]
    fn a_block_outside_the_data_panics() {
        let data = vec![1.0f32; 100];
        let w = f32x8::weights4(&[[0.25; 4]], u32x8::splat(0));
        let rel = u32x8::new([0, 1, 2, 3, 4, 5, 6, 90]);
        // Lane 7's bottom-right corner is 90 + 10 + 1 = 101.
        let mut sums = [f32x8::acc_from(f32x8::splat(0.0))];
        f32x8::acc_blocks(&mut sums, &w, &data, 0, 0, rel, 10);
    }
}
