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

use crate::hash::{mix32, mix32x8};

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
    /// `table[i]` per lane (bounds-checked).
    fn gather(table: &[f32], i: Self::U) -> Self;
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
    /// Writes the lanes to `data[at..at + LANES]`.
    fn store(self, data: &mut [f32], at: usize);
    /// `data[at[i]]` per lane (the 1-lane instance is a single load).
    fn gather_at(data: &[f32], at: &[usize; MAX_LANES]) -> Self;
    /// Lane `i`.
    fn lane(self, i: usize) -> f32;
    /// The integer lanes `x0, x0 + 1, …` (wrapping).
    fn u_iota(x0: u32) -> Self::U;
    /// `mix32` (lowbias32) of every integer lane (see [`crate::hash::mix32`]).
    fn u_mix32(a: Self::U) -> Self::U;
    /// Writes the integer lanes to `out[..LANES]`.
    fn u_store(a: Self::U, out: &mut [u32; MAX_LANES]);
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
    fn gather(table: &[f32], i: u32) -> Self {
        table[i as usize]
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
    fn store(self, data: &mut [f32], at: usize) {
        data[at] = self;
    }
    #[inline(always)]
    fn gather_at(data: &[f32], at: &[usize; MAX_LANES]) -> Self {
        data[at[0]]
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
    fn gather(table: &[f32], i: u32x8) -> Self {
        let i = i.to_array();
        f32x8::new([
            table[i[0] as usize],
            table[i[1] as usize],
            table[i[2] as usize],
            table[i[3] as usize],
            table[i[4] as usize],
            table[i[5] as usize],
            table[i[6] as usize],
            table[i[7] as usize],
        ])
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
    fn store(self, data: &mut [f32], at: usize) {
        let dst: &mut [f32; 8] = (&mut data[at..at + 8]).try_into().expect("8 floats");
        *dst = self.to_array();
    }
    #[inline(always)]
    fn gather_at(data: &[f32], at: &[usize; MAX_LANES]) -> Self {
        f32x8::new([
            data[at[0]],
            data[at[1]],
            data[at[2]],
            data[at[3]],
            data[at[4]],
            data[at[5]],
            data[at[6]],
            data[at[7]],
        ])
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
    fn agree(eight: f32x8, one: impl Fn(usize) -> f32, what: &str) {
        let e = eight.to_array();
        for (i, v) in e.iter().enumerate() {
            assert_eq!(v.to_bits(), one(i).to_bits(), "{what}, lane {i}");
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
            let at: [usize; MAX_LANES] = std::array::from_fn(|i| (h[i] % 16) as usize);
            let data: Vec<f32> = (0..16).map(|k| floats(seed + k)[k as usize % 8]).collect();
            agree(
                f32x8::gather_at(&data, &at),
                |i| f32::gather_at(&data, &[at[i]; 8]),
                "gather_at",
            );
        }
    }
}
