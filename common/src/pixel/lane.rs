//! The lane type every per-pixel stage is written over: one generic implementation, instantiated
//! for scalar `f32` (one lane) and `wide::f32x8` (eight lanes), so the scalar and SIMD paths run
//! the same IEEE operations in the same order, lane by lane, by construction.
//!
//! Only exact operations are offered: add, sub, mul, div, floor, sign-bit tricks, compares and
//! selects, saturating truncation, wrapping integer arithmetic, loads, stores and gathers. There
//! is no `mul_add`, no `min`/`max` (they differ on ±0 between `wide` and scalar) and no libm
//! transcendental.
//!
//! This file holds the lane arithmetic ([`Lane`] and its two instances). Its submodules hold the
//! memory side of the sweep's fast gathers: `layout` ([`Layout`]: the kernel-specific layouts
//! the CPU's 8-lane gathers read and sum in: lane pairs, pixel-interleaved planes, bilinear
//! blocks, grid fetches) and `avx2` (the AVX2 intrinsics behind the 8-lane type's gathers and
//! shuffles, with portable fallbacks). Loads, gathers and shuffles move values only, so neither
//! changes a bit.

use std::ops::{Add, Div, Mul, Sub};

use wide::{f32x8, u32x8};

use crate::pixel::hash::{mix32, mix32x8};

mod avx2;
mod layout;

pub use layout::{Grid, Layout, halves, load_halves, splat_within_halves};

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
    /// Broadcasts a float.
    fn splat(v: f32) -> Self;
    /// The correctly rounded square root per lane (IEEE 754, as WGSL's `sqrt` on the reference
    /// driver).
    fn sqrt(self) -> Self;
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
}

/// Panics unless `lo..=hi` lies inside `0..len` (a gather's or block's index range).
#[inline(always)]
fn check(lo: i64, hi: i64, len: usize) {
    assert!(
        lo >= 0 && hi < len as i64,
        "gather index {lo}..={hi} outside 0..{len}"
    );
}

impl Lane for f32 {
    const LANES: usize = 1;
    type U = u32;
    type M = bool;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
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
}

impl Lane for f32x8 {
    const LANES: usize = 8;
    type U = u32x8;
    type M = f32x8;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        f32x8::splat(v)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32x8::sqrt(self)
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
}

#[cfg(test)]
mod tests;
