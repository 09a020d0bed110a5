//! Stages 4 and 5: front-to-back compositing and light attenuation with the explicit flush
//! (steps 4–5 of the per-pixel sweep). Mirrors `gpu/src/shaders/composite.wgsl`.
//!
//! Written once over [`Lane`]: the per-pixel stage (`crate::sweep::pixel`) calls the 1-lane
//! instance, the SIMD path's chunks the 8-lane one.

use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::FLUSH_BELOW;

/// `C += (1 − A)·α·c`, `A += (1 − A)·α`, in that order, applied only in the lanes of `lanes`
/// (planar colours: one lane value per channel).
#[inline(always)]
pub fn composite<L: Lane>(color: &mut [L; 3], alpha: &mut L, c: [L; 3], a: L, lanes: L::M) {
    let t = (L::splat(1.0) - *alpha) * a;
    for (dst, src) in color.iter_mut().zip(c) {
        *dst = L::select(lanes, *dst + t * src, *dst);
    }
    *alpha = L::select(lanes, *alpha + t, *alpha);
}

/// `Iout = Iin · attenuation`, flushed to zero below [`FLUSH_BELOW`].
#[inline(always)]
pub fn attenuate<L: Lane>(iin: L, attenuation: L) -> L {
    let v = iin * attenuation;
    L::select(v.lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// Distance penumbra: the occluder-depth plane after a slab, `D + slab · removed` (`removed`:
/// the light the slab took out, summed over channels), flushed like the light.
#[inline(always)]
pub fn deepen<L: Lane>(depth: L, slab: u32, removed: L) -> L {
    let v = depth + L::splat(slab as f32) * removed;
    L::select(v.lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}
