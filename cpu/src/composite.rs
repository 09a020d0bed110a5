//! Stages 4 and 5: front-to-back compositing and light attenuation with the explicit flush
//! (DESIGN §2 steps 4–5). Mirrors `gpu/src/shaders/composite.wgsl`.

use convshadow_common::plan::FLUSH_BELOW;
use wide::f32x8;

/// `C += (1 − A)·α·c`, `A += (1 − A)·α`, in that order.
#[inline(always)]
pub fn composite(color: &mut [f32; 3], alpha: &mut f32, c: [f32; 3], a: f32) {
    let t = (1.0 - *alpha) * a;
    color[0] += t * c[0];
    color[1] += t * c[1];
    color[2] += t * c[2];
    *alpha += t;
}

/// `Iout = Iin · attenuation`, flushed to zero below [`FLUSH_BELOW`].
#[inline(always)]
pub fn attenuate(iin: f32, attenuation: f32) -> f32 {
    let v = iin * attenuation;
    if v < FLUSH_BELOW { 0.0 } else { v }
}

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}

/// 8-lane [`composite`] on planar colours, applied only in the all-ones lanes of `lanes`.
#[inline(always)]
pub fn composite8(
    color: &mut [f32x8; 3],
    alpha: &mut f32x8,
    c: [f32x8; 3],
    a: f32x8,
    lanes: f32x8,
) {
    let t = (f32x8::ONE - *alpha) * a;
    for (dst, src) in color.iter_mut().zip(c) {
        *dst = lanes.select(*dst + t * src, *dst);
    }
    *alpha = lanes.select(*alpha + t, *alpha);
}

/// 8-lane [`attenuate`].
#[inline(always)]
pub fn attenuate8(iin: f32x8, attenuation: f32x8) -> f32x8 {
    let v = iin * attenuation;
    v.simd_lt(f32x8::splat(FLUSH_BELOW)).select(f32x8::ZERO, v)
}
