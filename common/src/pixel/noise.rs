//! Volumetric detail functions: improved Perlin noise (3D and 4D), fBm, ridged multifractal and
//! turbulence, bit-exact between the scalar path, the 8-lane SIMD path and the WGSL port.
//!
//! # Bit-exactness rules
//! Every function here is written **once**, generically over [`Lane`], and
//! instantiated for `f32` (scalar) and `wide::f32x8` (SIMD). Both instantiations therefore run
//! the identical sequence of IEEE operations, lane by lane. Only these operations are used:
//! f32 add, sub, mul, floor, sign-bit clear (`abs`), sign-bit xor, compare + select, f32 → i32
//! truncation of an already integral value, and u32 wrapping add/mul, xor, and, or and shifts.
//! No `mul_add`/FMA, no `min`/`max` (they differ on ±0 between `wide` and scalar), no libm
//! transcendentals. Expressions are written in a fixed order; a WGSL port must keep that order
//! (left to right as written in the comments of each function).
//!
//! # Lattice hash
//! No permutation table: each lattice corner's gradient comes from an integer hash, which
//! vectorises without gathers and ports to WGSL as plain `u32` arithmetic.
//! - Lattice integer per axis: `((floor(x) as i32) & 255) as u32` (period 256, as with Perlin's
//!   table). `as i32` saturates in Rust, and `wide`'s `trunc_int` saturates identically
//!   (≥ 2^31 → `i32::MAX`, ≤ −2^31 → `i32::MIN`, NaN → 0); WGSL `i32(f32)` clamps too.
//! - Corner key: `X | Y << 8 | Z << 16 | W << 24` (W = 0 in 3D), a bijection of the wrapped corner.
//! - Hash: Chris Wellons' `lowbias32`: `k ^= k >> 16; k *= 0x7feb352d; k ^= k >> 15;
//!   k *= 0x846ca68b; k ^= k >> 16` (u32 wrapping multiplies).
//! - 3D gradient: `h = hash >> 28` selects one of Perlin's 16 (12 distinct) edge directions
//!   exactly as in Perlin's 2002 reference `grad()`; 4D: `h = hash >> 27` selects one of the 32
//!   edge directions of the 4D hypercube as in Gustavson's `grad4()`. Signs are applied by xoring
//!   the hash bit into the f32 sign bit, identical in every path.
//!
//! # Fractional part
//! `fx = x - floor(x)`; for tiny negative `x` this rounds to exactly 1.0 (e.g. `x = -1e-30`),
//! which is harmless (the noise is continuous there). For `|x| ≥ 2^23` every f32 is an integer, so
//! `fx = 0`. Non-finite inputs give NaN from the raw noise functions and 0 from [`Detail`].

use crate::model::scene::DetailKind;
use crate::pixel::lane::Lane;

/// Perlin's quintic fade `6t^5 - 15t^4 + 10t^3`, evaluated as `((t*t)*t) * (t*(t*6 - 15) + 10)`.
#[inline(always)]
fn fade<L: Lane>(t: L) -> L {
    let t3 = t * t * t;
    let p = t * (t * L::splat(6.0) - L::splat(15.0)) + L::splat(10.0);
    t3 * p
}

/// `a + t * (b - a)`.
#[inline(always)]
pub(crate) fn lerp<L: Lane>(t: L, a: L, b: L) -> L {
    a + t * (b - a)
}

/// Splits a coordinate into (wrapped lattice integer, fractional part).
#[inline(always)]
fn split<L: Lane>(x: L) -> (L::U, L) {
    let fl = x.floor();
    let i = L::u_and(fl.trunc_u32(), L::u_splat(255));
    (i, x - fl)
}

/// `(i + 1) & 255`.
#[inline(always)]
fn next<L: Lane>(i: L::U) -> L::U {
    L::u_and(L::u_add(i, L::u_splat(1)), L::u_splat(255))
}

/// Perlin 2002 `grad()`: `h = hash >> 28`; `u = h<8 ? x : y`;
/// `v = h<4 ? y : (h==12||h==14 ? x : z)`; result `±u + ±v` with signs from bits 0 and 1 of h.
#[inline(always)]
fn grad3<L: Lane>(hash: L::U, x: L, y: L, z: L) -> L {
    let h = L::u_shr(hash, 28);
    let zero = L::u_splat(0);
    let u_is_x = L::u_eq(L::u_and(h, L::u_splat(8)), zero);
    let v_is_y = L::u_eq(L::u_and(h, L::u_splat(12)), zero);
    let v_is_x = L::u_eq(L::u_and(h, L::u_splat(13)), L::u_splat(12));
    let u = L::select(u_is_x, x, y);
    let v = L::select(v_is_y, y, L::select(v_is_x, x, z));
    let su = L::u_shl(L::u_and(h, L::u_splat(1)), 31);
    let sv = L::u_shl(L::u_and(h, L::u_splat(2)), 30);
    u.xor_bits(su) + v.xor_bits(sv)
}

/// Gustavson's `grad4()`: `h = hash >> 27`; `u = h<24 ? x : y`; `v = h<16 ? y : z`;
/// `w = h<8 ? z : t`; result `(±u + ±v) + ±w` with signs from bits 0, 1, 2 of h.
#[inline(always)]
fn grad4<L: Lane>(hash: L::U, x: L, y: L, z: L, t: L) -> L {
    let h = L::u_shr(hash, 27);
    let zero = L::u_splat(0);
    let h24 = L::u_and(h, L::u_splat(24));
    let u_is_y = L::u_eq(h24, L::u_splat(24));
    let v_is_y = L::u_eq(L::u_and(h, L::u_splat(16)), zero);
    let w_is_z = L::u_eq(h24, zero);
    let u = L::select(u_is_y, y, x);
    let v = L::select(v_is_y, y, z);
    let w = L::select(w_is_z, z, t);
    let su = L::u_shl(L::u_and(h, L::u_splat(1)), 31);
    let sv = L::u_shl(L::u_and(h, L::u_splat(2)), 30);
    let sw = L::u_shl(L::u_and(h, L::u_splat(4)), 29);
    u.xor_bits(su) + v.xor_bits(sv) + w.xor_bits(sw)
}

/// Improved Perlin noise (Perlin 2002) in 3D; 0 at lattice points, range about [-1, 1].
#[inline(always)]
pub fn improved_perlin3<L: Lane>(x: L, y: L, z: L) -> L {
    let one = L::splat(1.0);
    let (xi0, x0) = split(x);
    let (yi0, y0) = split(y);
    let (zi0, z0) = split(z);
    let xi1 = next::<L>(xi0);
    let yi0s = L::u_shl(yi0, 8);
    let yi1s = L::u_shl(next::<L>(yi0), 8);
    let zi0s = L::u_shl(zi0, 16);
    let zi1s = L::u_shl(next::<L>(zi0), 16);
    let x1 = x0 - one;
    let y1 = y0 - one;
    let z1 = z0 - one;
    let u = fade(x0);
    let v = fade(y0);
    let w = fade(z0);
    let key = |a: L::U, b: L::U, c: L::U| L::u_mix32(L::u_or(L::u_or(a, b), c));
    let g000 = grad3(key(xi0, yi0s, zi0s), x0, y0, z0);
    let g100 = grad3(key(xi1, yi0s, zi0s), x1, y0, z0);
    let g010 = grad3(key(xi0, yi1s, zi0s), x0, y1, z0);
    let g110 = grad3(key(xi1, yi1s, zi0s), x1, y1, z0);
    let g001 = grad3(key(xi0, yi0s, zi1s), x0, y0, z1);
    let g101 = grad3(key(xi1, yi0s, zi1s), x1, y0, z1);
    let g011 = grad3(key(xi0, yi1s, zi1s), x0, y1, z1);
    let g111 = grad3(key(xi1, yi1s, zi1s), x1, y1, z1);
    let a0 = lerp(u, g000, g100);
    let a1 = lerp(u, g010, g110);
    let a2 = lerp(u, g001, g101);
    let a3 = lerp(u, g011, g111);
    let b0 = lerp(v, a0, a1);
    let b1 = lerp(v, a2, a3);
    lerp(w, b0, b1)
}

/// Output scale of [`improved_perlin4`] (Gustavson's `noise1234` value).
///
/// Raw 4D noise with these gradients reaches ±1.5366 at worst (`Σ_c w_c max_g g·d_c`, maximised
/// over the cell) and has standard deviation 0.293; scaled by 0.87 its standard deviation (0.255)
/// is close to 3D noise's (0.270) and sampled values stay within about ±1 (worst case ±1.337).
/// 3D noise is unscaled: its worst case is ±1.0364.
pub const PERLIN4_SCALE: f32 = 0.87;

/// Improved Perlin noise in 4D (32 hypercube-edge gradients, scaled by [`PERLIN4_SCALE`]); 0 at
/// lattice points, range about [-1, 1].
#[inline(always)]
pub fn improved_perlin4<L: Lane>(x: L, y: L, z: L, t: L) -> L {
    let one = L::splat(1.0);
    let (xi0, x0) = split(x);
    let (yi0, y0) = split(y);
    let (zi0, z0) = split(z);
    let (ti0, t0) = split(t);
    let xi = [xi0, next::<L>(xi0)];
    let yi = [L::u_shl(yi0, 8), L::u_shl(next::<L>(yi0), 8)];
    let zi = [L::u_shl(zi0, 16), L::u_shl(next::<L>(zi0), 16)];
    let ti = [L::u_shl(ti0, 24), L::u_shl(next::<L>(ti0), 24)];
    let xs = [x0, x0 - one];
    let ys = [y0, y0 - one];
    let zs = [z0, z0 - one];
    let ts = [t0, t0 - one];
    let fx = fade(x0);
    let fy = fade(y0);
    let fz = fade(z0);
    let ft = fade(t0);
    // g[c] with corner bits c = x | y << 1 | z << 2 | t << 3.
    let corner = |c: usize| {
        let (a, b, d, e) = (c & 1, (c >> 1) & 1, (c >> 2) & 1, (c >> 3) & 1);
        let k = L::u_or(L::u_or(L::u_or(xi[a], yi[b]), zi[d]), ti[e]);
        grad4(L::u_mix32(k), xs[a], ys[b], zs[d], ts[e])
    };
    // Interpolate along x, then y, then z, then t, always lower corner first.
    let mut ax = [one; 8];
    for (j, slot) in ax.iter_mut().enumerate() {
        *slot = lerp(fx, corner(2 * j), corner(2 * j + 1));
    }
    let mut ay = [one; 4];
    for (j, slot) in ay.iter_mut().enumerate() {
        *slot = lerp(fy, ax[2 * j], ax[2 * j + 1]);
    }
    let az0 = lerp(fz, ay[0], ay[1]);
    let az1 = lerp(fz, ay[2], ay[3]);
    lerp(ft, az0, az1) * L::splat(PERLIN4_SCALE)
}

/// Clamps to [0, 1] with compares and selects: NaN and −0 map to +0 (noise.wgsl `clamp01`;
/// also the part of a slab a medium fills, `cpu::parity::slab_part`).
#[inline(always)]
pub fn clamp01<L: Lane>(v: L) -> L {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let r = L::select(v.gt(zero), v, zero);
    L::select(r.gt(one), one, r)
}

/// Host-prepared parameters: per-octave frequency and amplitude tables computed once, so no
/// `pow` runs per pixel.
///
/// Octave `i` samples noise at `(p·f_i)` in 3D, or at `(p·f_i, time·f_i)` in 4D (time is scaled
/// like a fourth coordinate, so each octave evolves at a rate proportional to its frequency).
/// No per-octave offsets: with lacunarity 2 the lattice points of octave 0 are lattice points of
/// every octave.
#[derive(Clone, Debug, PartialEq)]
pub struct Detail {
    /// The detail function.
    pub kind: DetailKind,
    /// Frequency of octave i: `frequency · lacunarity^i` (object-space cycles per unit).
    pub octave_frequency: Vec<f32>,
    /// Amplitude of octave i: `gain^i` (octave 0 has amplitude exactly 1).
    pub octave_amplitude: Vec<f32>,
    /// `1 / Σ |amplitude_i|` (f64 sum of the f32 amplitudes, rounded once).
    pub inv_amplitude_sum: f32,
    /// `None`: 3D noise; `Some(t)`: 4D noise at `(p, t)`.
    pub time: Option<f32>,
}

impl Detail {
    /// Builds the tables: octave i has frequency = frequency·lacunarity^i, amplitude = gain^i
    /// (octaves clamped to ≥ 1; `Perlin` always has exactly 1 octave).
    ///
    /// Powers are formed by repeated f64 multiplication (deterministic on every platform) and
    /// rounded to f32 once. Parameters are not validated here (the scene layer does that);
    /// non-finite tables make [`Detail::eval`] return 0, never panic.
    pub fn new(
        kind: DetailKind,
        frequency: f32,
        octaves: u32,
        lacunarity: f32,
        gain: f32,
        time: Option<f32>,
    ) -> Detail {
        let n = if kind == DetailKind::Perlin {
            1
        } else {
            octaves.max(1)
        } as usize;
        let mut octave_frequency = Vec::with_capacity(n);
        let mut octave_amplitude = Vec::with_capacity(n);
        let mut f = f64::from(frequency);
        let mut a = 1.0f64;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let a32 = a as f32;
            octave_frequency.push(f as f32);
            octave_amplitude.push(a32);
            sum += f64::from(a32).abs();
            f *= f64::from(lacunarity);
            a *= f64::from(gain);
        }
        Detail {
            kind,
            octave_frequency,
            octave_amplitude,
            inv_amplitude_sum: (1.0 / sum) as f32,
            time,
        }
    }

    /// Evaluation at an object-space point (per lane), result in [0, 1] (clamped; NaN → 0), 3D
    /// noise if `time` is `None`, else 4D noise at `(p, time)`.
    pub fn eval<L: Lane>(&self, p: [L; 3]) -> L {
        let [x, y, z] = p;
        let n_oct = self.octave_frequency.len().min(self.octave_amplitude.len());
        if n_oct == 0 {
            return L::splat(0.0);
        }
        let half = L::splat(0.5);
        let one = L::splat(1.0);
        let inv = L::splat(self.inv_amplitude_sum);
        let amp = |i: usize| L::splat(self.octave_amplitude[i]);
        let v = match self.kind {
            DetailKind::Perlin | DetailKind::Fbm => {
                // sum = a_0 n_0; sum = sum + a_i n_i; v = 0.5 + 0.5 * (sum * inv).
                let mut sum = amp(0) * self.octave(0, x, y, z);
                for i in 1..n_oct {
                    sum = sum + amp(i) * self.octave(i, x, y, z);
                }
                half + half * (sum * inv)
            }
            DetailKind::Turbulence => {
                let mut sum = amp(0) * self.octave(0, x, y, z).abs();
                for i in 1..n_oct {
                    sum = sum + amp(i) * self.octave(i, x, y, z).abs();
                }
                sum * inv
            }
            DetailKind::Ridged => {
                // s_0 = (1 - |n_0|)^2; s_i = (1 - |n_i|)^2 * clamp01(s_{i-1});
                // v = (Σ a_i s_i) * inv.
                let r = one - self.octave(0, x, y, z).abs();
                let mut signal = r * r;
                let mut sum = amp(0) * signal;
                for i in 1..n_oct {
                    let weight = clamp01(signal);
                    let r = one - self.octave(i, x, y, z).abs();
                    signal = r * r * weight;
                    sum = sum + amp(i) * signal;
                }
                sum * inv
            }
        };
        clamp01(v)
    }

    /// Noise of octave `i`.
    #[inline(always)]
    fn octave<L: Lane>(&self, i: usize, x: L, y: L, z: L) -> L {
        let f = L::splat(self.octave_frequency[i]);
        match self.time {
            None => improved_perlin3(x * f, y * f, z * f),
            Some(t) => improved_perlin4(x * f, y * f, z * f, L::splat(t) * f),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wide::f32x8;

    use convshadow_testkit::TestRng;

    /// A coordinate from a mix of hard categories.
    fn hard(rng: &mut TestRng) -> f32 {
        match rng.next_u64() % 16 {
            0 => rng.float_range(-300.0, 300.0).floor(),
            1 => rng.float_range(-300.0, 300.0).floor() + 0.5,
            2 => [1e6, -1e6, 999_999.9, -999_999.9][(rng.next_u64() % 4) as usize],
            3 => rng.float_range(-1e6, 1e6),
            4 => [1e-30, -1e-30, 1e-40, -1e-40, 0.0, -0.0][(rng.next_u64() % 6) as usize],
            5 => {
                let k = rng.float_range(-300.0, 300.0).floor();
                if rng.next_u64().is_multiple_of(2) {
                    k.next_up()
                } else {
                    k.next_down()
                }
            }
            6 => rng.float_range(-3.0, 3.0),
            7 => [255.0, 256.0, -256.0, -255.5, 255.999_98][(rng.next_u64() % 5) as usize],
            _ => rng.float_range(-300.0, 300.0),
        }
    }

    fn lanes(v: [f32; 8]) -> f32x8 {
        f32x8::new(v)
    }

    const ALL_KINDS: [DetailKind; 4] = [
        DetailKind::Perlin,
        DetailKind::Fbm,
        DetailKind::Ridged,
        DetailKind::Turbulence,
    ];

    /// Independent f64 reference written the textbook way (corner loop, product weights,
    /// Perlin's/Gustavson's `grad` with branches, `rem_euclid` wrap); the f32 implementation
    /// must agree to within f32 rounding (|p| ≤ 300 so fractional parts are exact in f32).
    fn reference(p: &[f32]) -> f64 {
        let dim = p.len();
        let fade = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let cell: Vec<i64> = p.iter().map(|&x| f64::from(x).floor() as i64).collect();
        let frac: Vec<f64> = p
            .iter()
            .zip(&cell)
            .map(|(&x, &c)| f64::from(x) - c as f64)
            .collect();
        let mut total = 0.0;
        for c in 0..(1usize << dim) {
            let mut key = 0u32;
            let mut w = 1.0;
            let mut d = [0.0f64; 4];
            for i in 0..dim {
                let bit = (c >> i) & 1;
                key |= ((cell[i] + bit as i64).rem_euclid(256) as u32) << (8 * i);
                d[i] = frac[i] - bit as f64;
                w *= if bit == 1 {
                    fade(frac[i])
                } else {
                    1.0 - fade(frac[i])
                };
            }
            let mut k = key;
            k ^= k >> 16;
            k = k.wrapping_mul(0x7feb352d);
            k ^= k >> 15;
            k = k.wrapping_mul(0x846ca68b);
            k ^= k >> 16;
            let g = if dim == 3 {
                let h = k >> 28;
                let u = if h < 8 { d[0] } else { d[1] };
                let v = if h < 4 {
                    d[1]
                } else if h == 12 || h == 14 {
                    d[0]
                } else {
                    d[2]
                };
                (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
            } else {
                let h = k >> 27;
                let u = if h < 24 { d[0] } else { d[1] };
                let v = if h < 16 { d[1] } else { d[2] };
                let t = if h < 8 { d[2] } else { d[3] };
                (if h & 1 == 0 { u } else { -u })
                    + (if h & 2 == 0 { v } else { -v })
                    + (if h & 4 == 0 { t } else { -t })
            };
            total += w * g;
        }
        if dim == 4 {
            total * f64::from(PERLIN4_SCALE)
        } else {
            total
        }
    }

    #[test]
    fn noise_matches_f64_reference() {
        let mut rng = TestRng::new(9);
        let mut worst = 0.0f64;
        for _ in 0..50_000 {
            let p: [f32; 4] = std::array::from_fn(|_| rng.float_range(-300.0, 300.0));
            let e3 = (f64::from(improved_perlin3(p[0], p[1], p[2])) - reference(&p[..3])).abs();
            let e4 = (f64::from(improved_perlin4(p[0], p[1], p[2], p[3])) - reference(&p)).abs();
            assert!(e3 < 2e-6 && e4 < 2e-6, "{p:?}: errors {e3:e} {e4:e}");
            worst = worst.max(e3).max(e4);
        }
        assert!(worst > 0.0);
    }

    #[test]
    fn noise_zero_at_lattice_points() {
        let mut rng = TestRng::new(1);
        for _ in 0..20_000 {
            let p: [f32; 4] = std::array::from_fn(|_| rng.float_range(-1000.0, 1000.0).floor());
            assert_eq!(improved_perlin3(p[0], p[1], p[2]), 0.0, "{p:?}");
            assert_eq!(improved_perlin4(p[0], p[1], p[2], p[3]), 0.0, "{p:?}");
        }
        for k in [-1e6f32, 1e6, 16_777_216.0, -3e38, 3e38, 0.0, -0.0] {
            assert_eq!(improved_perlin3(k, k, k), 0.0);
            assert_eq!(improved_perlin4(k, -k, 0.0, k), 0.0);
        }
    }

    /// At a lattice point improved noise behaves like g·d (fade has zero first and second
    /// derivative there), so one-sided difference quotients recover the corner gradient, which
    /// must be one of Perlin's 12 (3D) or the 32 hypercube-edge (4D) directions, and every one of
    /// them must occur.
    #[test]
    fn noise_gradients_at_lattice_are_edge_directions() {
        let h = 1.0f32 / 1024.0;
        let mut rng = TestRng::new(2);
        let mut seen3 = std::collections::HashMap::new();
        let mut seen4 = std::collections::HashMap::new();
        let round = |d: f32| {
            let r = d.round();
            // n(k + h e_i)/h = g_i + O(h^3) rounding included.
            assert!(
                (d - r).abs() < 1e-3,
                "difference quotient {d} not near an integer"
            );
            r as i32
        };
        for _ in 0..4000 {
            let p: [f32; 4] = std::array::from_fn(|_| rng.float_range(-500.0, 500.0).floor());
            let g3: [i32; 3] = std::array::from_fn(|i| {
                let mut q = [p[0], p[1], p[2]];
                q[i] += h;
                round(improved_perlin3(q[0], q[1], q[2]) / h)
            });
            assert_eq!(g3.iter().filter(|c| c.abs() == 1).count(), 2, "{g3:?}");
            assert_eq!(g3.iter().filter(|c| **c == 0).count(), 1, "{g3:?}");
            *seen3.entry(g3).or_insert(0u32) += 1;
            let g4: [i32; 4] = std::array::from_fn(|i| {
                let mut q = p;
                q[i] += h;
                round(improved_perlin4(q[0], q[1], q[2], q[3]) / PERLIN4_SCALE / h)
            });
            assert_eq!(g4.iter().filter(|c| c.abs() == 1).count(), 3, "{g4:?}");
            assert_eq!(g4.iter().filter(|c| **c == 0).count(), 1, "{g4:?}");
            *seen4.entry(g4).or_insert(0u32) += 1;
        }
        assert_eq!(seen3.len(), 12);
        assert_eq!(seen4.len(), 32);
        // 4000 corners: 3D expects 4000/16 per hash value (doubled directions get 2/16),
        // 4D expects 125 per direction; allow wide statistical slack.
        for (&g, &count) in &seen4 {
            assert!(
                (60..200).contains(&count),
                "4D gradient {g:?} seen {count} times"
            );
        }
        for (&g, &count) in &seen3 {
            assert!(
                (120..650).contains(&count),
                "3D gradient {g:?} seen {count} times"
            );
        }
    }

    #[test]
    fn noise_range_mean_and_variance() {
        let mut rng = TestRng::new(3);
        let n = 100_000;
        for dim4 in [false, true] {
            let (mut s, mut s2, mut lo, mut hi) = (0.0f64, 0.0f64, 0.0f32, 0.0f32);
            for _ in 0..n {
                let p: [f32; 4] = std::array::from_fn(|_| rng.float_range(-1000.0, 1000.0));
                let v = if dim4 {
                    improved_perlin4(p[0], p[1], p[2], p[3])
                } else {
                    improved_perlin3(p[0], p[1], p[2])
                };
                assert!((-1.05..=1.05).contains(&v), "{v} at {p:?}");
                lo = lo.min(v);
                hi = hi.max(v);
                s += f64::from(v);
                s2 += f64::from(v) * f64::from(v);
            }
            let mean = s / n as f64;
            let var = s2 / n as f64 - mean * mean;
            // Independent samples: std of the mean is sqrt(var/n) < 1e-3.
            assert!(mean.abs() < 0.01, "dim4={dim4} mean {mean}");
            // Measured over 2M points: 3D 0.0729, 4D 0.0649 (0.0857·0.87²); a constant or
            // mostly-zero noise fails this.
            assert!(var > 0.05 && var < 0.09, "dim4={dim4} variance {var}");
            assert!(
                lo < -0.6 && hi > 0.6,
                "dim4={dim4} range [{lo}, {hi}] too narrow"
            );
        }
    }

    /// Lipschitz bound: ∂n/∂x_i = Σ_c ∂w_c/∂x_i (g_c·d_c) + Σ_c w_c g_c,i, with Σ_c |∂w_c/∂x_i|
    /// = 2 fade'(x_i) ≤ 2·30/16 = 3.75, |g·d| ≤ (number of ±1 gradient components) = 2 (3D) or
    /// 3 (4D), Σ w_c = 1 and |g_c,i| ≤ 1. So |∂n/∂x_i| ≤ 8.5 (3D), 12.25·0.87 (4D, scaled),
    /// and |n(p+h) − n(p)| ≤ L·‖h‖₁. A small absolute slack covers f32 rounding (coordinates
    /// ≤ 300, so |p| has ulp ≤ 3e-5 and fractional parts are exact).
    #[test]
    fn noise_lipschitz_continuous_including_cell_boundaries() {
        let (l3, l4, slack) = (8.5f32, 12.25f32 * PERLIN4_SCALE, 2e-4f32);
        let mut rng = TestRng::new(4);
        let mut max_ratio3 = 0.0f32;
        for i in 0..100_000 {
            let mut p: [f32; 4] = std::array::from_fn(|_| rng.float_range(-300.0, 300.0));
            if i % 2 == 0 {
                // Straddle a cell boundary on one axis.
                let a = (rng.next_u64() % 4) as usize;
                p[a] = p[a].floor() - 0.0005;
            }
            let hmag = [1e-3, 1e-2, 0.1][i % 3];
            let d: [f32; 4] = std::array::from_fn(|_| rng.float_range(-hmag, hmag));
            let q: [f32; 4] = std::array::from_fn(|k| p[k] + d[k]);
            let hn3: f32 = (0..3).map(|k| (q[k] - p[k]).abs()).sum();
            let hn4: f32 = (0..4).map(|k| (q[k] - p[k]).abs()).sum();
            let dn3 =
                (improved_perlin3(q[0], q[1], q[2]) - improved_perlin3(p[0], p[1], p[2])).abs();
            let dn4 = (improved_perlin4(q[0], q[1], q[2], q[3])
                - improved_perlin4(p[0], p[1], p[2], p[3]))
            .abs();
            assert!(dn3 <= l3 * hn3 + slack, "3D jump {dn3} over {hn3} at {p:?}");
            assert!(dn4 <= l4 * hn4 + slack, "4D jump {dn4} over {hn4} at {p:?}");
            if hn3 > 1e-3 {
                max_ratio3 = max_ratio3.max(dn3 / hn3);
            }
        }
        // The bound is not vacuous: the noise really varies at order-1 slopes.
        assert!(max_ratio3 > 1.0, "max slope {max_ratio3}");
    }

    #[test]
    fn noise_wraps_with_period_256_and_handles_huge_coordinates() {
        let mut rng = TestRng::new(5);
        for _ in 0..10_000 {
            let p: [f32; 4] =
                std::array::from_fn(|_| rng.float_range(-100.0, 100.0).floor() + 0.25);
            let a = improved_perlin3(p[0], p[1], p[2]);
            assert_eq!(
                a,
                improved_perlin3(p[0] + 256.0, p[1] - 512.0, p[2] + 1024.0)
            );
            let b = improved_perlin4(p[0], p[1], p[2], p[3]);
            assert_eq!(
                b,
                improved_perlin4(p[0] - 256.0, p[1], p[2] + 256.0, p[3] + 768.0)
            );
        }
        for big in [
            1e6f32,
            -1e6,
            1e7,
            -1e7,
            1e10,
            -1e10,
            3.4e38,
            -3.4e38,
            2_147_483_648.0,
        ] {
            for f in [0.3f32, -0.7, 123.456] {
                let v3 = improved_perlin3(big, f, -f);
                let v4 = improved_perlin4(f, big, big, -f);
                assert!(v3.is_finite() && v3.abs() <= 1.05, "{big} {f}: {v3}");
                assert!(v4.is_finite() && v4.abs() <= 1.05, "{big} {f}: {v4}");
            }
        }
    }

    fn check_x8_3(p: [[f32; 3]; 8]) {
        let x = lanes(std::array::from_fn(|i| p[i][0]));
        let y = lanes(std::array::from_fn(|i| p[i][1]));
        let z = lanes(std::array::from_fn(|i| p[i][2]));
        let v = improved_perlin3(x, y, z).to_array();
        for i in 0..8 {
            let s = improved_perlin3(p[i][0], p[i][1], p[i][2]);
            assert!(
                s.to_bits() == v[i].to_bits() || (s.is_nan() && v[i].is_nan()),
                "perlin3 lane {i} at {:?}: {s} vs {}",
                p[i],
                v[i]
            );
        }
    }

    fn check_x8_4(p: [[f32; 4]; 8]) {
        let c = |k: usize| lanes(std::array::from_fn(|i| p[i][k]));
        let v = improved_perlin4(c(0), c(1), c(2), c(3)).to_array();
        for i in 0..8 {
            let s = improved_perlin4(p[i][0], p[i][1], p[i][2], p[i][3]);
            assert!(
                s.to_bits() == v[i].to_bits() || (s.is_nan() && v[i].is_nan()),
                "perlin4 lane {i} at {:?}: {s} vs {}",
                p[i],
                v[i]
            );
        }
    }

    #[test]
    fn noise_scalar_and_simd_bit_identical() {
        let mut rng = TestRng::new(6);
        for _ in 0..(120_000 / 8) {
            let p3: [[f32; 3]; 8] =
                std::array::from_fn(|_| std::array::from_fn(|_| hard(&mut rng)));
            check_x8_3(p3);
            let p4: [[f32; 4]; 8] =
                std::array::from_fn(|_| std::array::from_fn(|_| hard(&mut rng)));
            check_x8_4(p4);
        }
        // Saturating conversions and non-finite inputs (NaN results compared as NaN).
        let special = [
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            3.4e38,
            -3.4e38,
            2_147_483_648.0,
            -2_147_483_648.0,
            -2_147_483_904.0,
        ];
        for (i, &s) in special.iter().enumerate() {
            let p3: [[f32; 3]; 8] = std::array::from_fn(|j| [s, j as f32 * 0.37, -(i as f32)]);
            check_x8_3(p3);
            let p3: [[f32; 3]; 8] = std::array::from_fn(|j| [0.5, -0.25 * j as f32, s]);
            check_x8_3(p3);
            let p4: [[f32; 4]; 8] = std::array::from_fn(|j| [0.1, j as f32, 0.7, s]);
            check_x8_4(p4);
        }
    }

    fn details() -> Vec<Detail> {
        let mut v = Vec::new();
        for kind in ALL_KINDS {
            for time in [None, Some(0.0), Some(-17.25), Some(3.7)] {
                v.push(Detail::new(kind, 1.7, 5, 2.0, 0.5, time));
                v.push(Detail::new(kind, 0.013, 3, 2.17, 0.61, time));
            }
        }
        v.push(Detail::new(DetailKind::Ridged, 4.0, 8, 1.9, 0.8, None));
        v.push(Detail::new(DetailKind::Fbm, 1.0, 1, 2.0, 0.5, None));
        v
    }

    #[test]
    fn noise_detail_eval_scalar_simd_bit_identical_and_in_unit_range() {
        let mut rng = TestRng::new(7);
        for d in details() {
            for _ in 0..(104_000 / 8 / 4) {
                let p: [[f32; 3]; 8] =
                    std::array::from_fn(|_| std::array::from_fn(|_| hard(&mut rng)));
                let c = |k: usize| lanes(std::array::from_fn(|i| p[i][k]));
                let v = d.eval([c(0), c(1), c(2)]).to_array();
                for i in 0..8 {
                    let s = d.eval(p[i]);
                    assert_eq!(s.to_bits(), v[i].to_bits(), "{d:?} lane {i} at {:?}", p[i]);
                    assert!((0.0..=1.0).contains(&s) && s.to_bits() >> 31 == 0, "{s}");
                }
            }
            // Non-finite points: clamped to 0 on both paths.
            for s in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let x = lanes([s, 0.5, s, 1.0, -2.0, s, 0.0, 7.0]);
                let v = d.eval([x, x, f32x8::splat(0.25)]).to_array();
                for (i, &xi) in x.to_array().iter().enumerate() {
                    assert_eq!(d.eval([xi, xi, 0.25]).to_bits(), v[i].to_bits());
                }
            }
        }
    }

    #[test]
    fn noise_detail_mappings() {
        let mut rng = TestRng::new(8);
        let perlin = Detail::new(DetailKind::Perlin, 2.5, 7, 2.0, 0.5, None);
        assert_eq!(perlin.octave_frequency, vec![2.5]);
        assert_eq!(perlin.octave_amplitude, vec![1.0]);
        assert_eq!(perlin.inv_amplitude_sum, 1.0);
        let fbm1 = Detail::new(DetailKind::Fbm, 2.5, 1, 2.0, 0.5, None);
        let fbm1_t = Detail::new(DetailKind::Fbm, 2.5, 0, 2.0, 0.5, Some(1.25));
        assert_eq!(fbm1_t.octave_frequency.len(), 1, "octaves clamp to >= 1");
        let turb = Detail::new(DetailKind::Turbulence, 2.5, 1, 2.0, 0.5, None);
        let ridged = Detail::new(DetailKind::Ridged, 2.5, 1, 2.0, 0.5, None);
        let fbm3 = Detail::new(DetailKind::Fbm, 0.75, 3, 2.0, 0.5, None);
        let ridged2 = Detail::new(DetailKind::Ridged, 0.75, 2, 2.0, 0.5, None);
        for _ in 0..20_000 {
            let p: [f32; 3] = std::array::from_fn(|_| rng.float_range(-50.0, 50.0));
            let n = improved_perlin3(p[0] * 2.5, p[1] * 2.5, p[2] * 2.5);
            let expect = 0.5 + 0.5 * n;
            assert_eq!(fbm1.eval(p).to_bits(), expect.to_bits());
            assert_eq!(perlin.eval(p).to_bits(), expect.to_bits());
            let n4 = improved_perlin4(p[0] * 2.5, p[1] * 2.5, p[2] * 2.5, 1.25 * 2.5);
            assert_eq!(fbm1_t.eval(p).to_bits(), (0.5 + 0.5 * n4).to_bits());
            assert_eq!(turb.eval(p), n.abs().min(1.0));
            assert_eq!(
                ridged.eval(p),
                ((1.0 - n.abs()) * (1.0 - n.abs())).clamp(0.0, 1.0)
            );
            // Three octaves, lacunarity 2, gain 1/2: every product is exact or rounded once
            // per term; compare against the same order in f32.
            let o = |f: f32| improved_perlin3(p[0] * f, p[1] * f, p[2] * f);
            let (n0, n1, n2) = (o(0.75), o(1.5), o(3.0));
            let sum = 1.0 * n0 + 0.5 * n1 + 0.25 * n2;
            let expect = (0.5 + 0.5 * (sum * (1.0 / 1.75f64) as f32)).clamp(0.0, 1.0);
            assert_eq!(fbm3.eval(p).to_bits(), expect.to_bits());
            // Ridged, 2 octaves: s0 = (1-|n0|)^2, s1 = (1-|n1|)^2 * clamp(s0).
            let s0 = (1.0 - n0.abs()) * (1.0 - n0.abs());
            let s1 = (1.0 - n1.abs()) * (1.0 - n1.abs()) * s0.clamp(0.0, 1.0);
            let expect = ((1.0 * s0 + 0.5 * s1) * (1.0 / 1.5f64) as f32).clamp(0.0, 1.0);
            assert_eq!(ridged2.eval(p).to_bits(), expect.to_bits());
        }
        // All lattice octaves are 0 at the origin: fBm 0.5, turbulence 0, ridged 1.
        assert_eq!(fbm3.eval([0.0; 3]), 0.5);
        assert_eq!(
            Detail::new(DetailKind::Turbulence, 1.0, 4, 2.0, 0.5, None).eval([0.0; 3]),
            0.0
        );
        assert_eq!(ridged2.eval([0.0; 3]), 1.0);
    }

    #[test]
    fn noise_octave_tables_closed_form() {
        let d = Detail::new(DetailKind::Fbm, 1.5, 6, 2.0, 0.5, Some(2.0));
        for i in 0..6 {
            assert_eq!(d.octave_frequency[i], 1.5 * (1u32 << i) as f32);
            assert_eq!(d.octave_amplitude[i], 1.0 / (1u32 << i) as f32);
        }
        assert_eq!(d.inv_amplitude_sum, (1.0 / (2.0 - 1.0 / 32.0f64)) as f32);
        assert_eq!(d.time, Some(2.0));
        for (f, o, l, g) in [(0.37f32, 9u32, 2.17f32, 0.61f32), (3.0, 12, 1.87, 0.45)] {
            let d = Detail::new(DetailKind::Ridged, f, o, l, g, None);
            assert_eq!(d.octave_frequency.len(), o as usize);
            let mut sum = 0.0f64;
            for i in 0..o as usize {
                let ef = (f64::from(f) * f64::from(l).powi(i as i32)) as f32;
                let ea = f64::from(g).powi(i as i32) as f32;
                // Repeated f64 products vs powi: equal after rounding to f32, up to one ulp in
                // the rare double-rounding case.
                let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).abs();
                assert!(ulps(d.octave_frequency[i], ef) <= 1, "freq {i}");
                assert!(ulps(d.octave_amplitude[i], ea) <= 1, "amp {i}");
                sum += f64::from(d.octave_amplitude[i]);
            }
            assert_eq!(d.octave_amplitude[0], 1.0);
            assert_eq!(d.inv_amplitude_sum, (1.0 / sum) as f32);
        }
    }

    #[test]
    fn noise_detail_kind_deserializes_lowercase() {
        #[derive(serde::Deserialize)]
        struct K {
            k: Vec<DetailKind>,
        }
        let k: K = toml::from_str(r#"k = ["perlin", "fbm", "ridged", "turbulence"]"#).unwrap();
        assert_eq!(k.k, ALL_KINDS.to_vec());
        assert!(toml::from_str::<K>(r#"k = ["Perlin"]"#).is_err());
    }
}
