//! Gathers for the 8-lane type where the build has AVX2 (`.cargo/config.toml`): one bounds check
//! for all lanes, then unchecked loads, shuffles and `vgatherdps`; without AVX2, checked loads
//! lane by lane. Loads and shuffles do not change bits, so both give the same values.

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

/// [`Layout::acc_blocks`](super::Layout::acc_blocks) on pixel pairs: per half, the top row's
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

/// [`acc_blocks`] without its check: see [`super::Layout::acc_blocks_unchecked`].
///
/// # Safety
/// As [`super::Layout::acc_blocks_unchecked`].
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

/// [`super::Layout::pixel_order`]: a transpose by halves for 4 planes, unpacks for 2, one
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
                let [r, g, b] = [0, 1, 2].map(|c| _mm256_permutevar8x32_ps(p[c], cast(ROTATED[c])));
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

/// [`super::Layout::plane_order`]: the inverse of [`pixel_order`], the same way.
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

/// [`super::Layout::from_lane_pairs`]: a transpose by halves (C ≤ 4).
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

/// [`super::Layout::to_lane_pairs`]: the inverse of [`from_lane_pairs`] (slots from C on 0).
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

/// [`super::Layout::shift_lanes`]: one permute and one blend.
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

/// [`super::Layout::fetch_grid`] once the grid (`size` = [width, height], both > 0) has been
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
