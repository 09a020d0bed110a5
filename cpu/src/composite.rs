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
/// the light the slab took out, summed over channels, at depth `slab` per lane: this slab, or
/// where a held surface was crossed, see [`hold_step`]), flushed like the light.
#[inline(always)]
pub fn deepen<L: Lane>(depth: L, slab: L, removed: L) -> L {
    let v = depth + slab * removed;
    L::select(v.lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// A pixel's surface hold (`RenderPlan::surface_hold`), packed in one `u32`: 0 when it holds
/// nothing, else the slab that releases it (the low [`HOLD_SHIFT`] bits) and how many slabs it
/// holds (the bits above).
pub const HOLD_SHIFT: u32 = 20;

/// What step 5 does with a pixel's light, given its surface hold ([`hold_step`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Held {
    /// No hold: the slab's own attenuation.
    Free,
    /// Held: the light passes (attenuation 1) — behind a light-blocking surface crossed fewer
    /// than its hold's slabs ago, or at its crossing.
    Pass,
    /// Released: the light is removed (attenuation 0), and the distance penumbra records it at
    /// the crossing's slab `removed_at`, where the surface is.
    Release {
        /// The slab the held surface was crossed in.
        removed_at: u32,
    },
}

/// Advances a pixel's packed surface hold `hold` through slab `slab`, in which its cursor
/// crossed a surface whose hold is `crossed_hold` slabs (0: no crossing, or one that does not
/// hold): a pending hold passes the light until its release slab and is cleared there; else a
/// crossing with a hold starts one. Every lane path runs it in every slab where a pixel crosses
/// a fragment or is released, so its state never goes stale.
#[inline(always)]
pub fn hold_step(hold: &mut u32, slab: u32, crossed_hold: u32) -> Held {
    let packed = *hold;
    if packed != 0 {
        let release = packed & ((1 << HOLD_SHIFT) - 1);
        if slab < release {
            return Held::Pass;
        }
        *hold = 0;
        return Held::Release {
            removed_at: release - (packed >> HOLD_SHIFT),
        };
    }
    if crossed_hold != 0 {
        *hold = (slab + crossed_hold) | (crossed_hold << HOLD_SHIFT);
        return Held::Pass;
    }
    Held::Free
}

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}
