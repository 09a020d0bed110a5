//! Stages 4 and 5: front-to-back compositing and light attenuation with the explicit flush
//! (steps 4–5 of the per-pixel sweep). Mirrors `gpu/src/shaders/composite.wgsl`.
//!
//! Written once over [`Lane`]: the per-pixel stage (`crate::sweep::pixel`) calls the 1-lane
//! instance, the SIMD path's chunks the 8-lane one.

use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::{FLUSH_BELOW, MaterialPlan, RenderPlan, surface_hold};

use crate::shading::{LightTerms, Surface, TfLanes, shade_with};

/// One slab's sample of `material` with entry `tf` shaded and composited into (`color`, `alpha`)
/// in the lanes of `lanes` (composite.wgsl `shade_sample`): `tf` scaled to the part of the slab
/// inside the medium (`inside`, `lit_from`: [`part_of_slab`], which leaves `tf` as the slab's
/// scaled entry, its attenuation for the light buffers), shaded with the incoming light `iin` —
/// at crossed surfaces (`surface`: the normals and the lanes that crossed one) with the highlight
/// and, where opaque, the Lambert cosine, judged by the entry's opacity before scaling —, times
/// the light inside the slab, composited. The grid's sweep (both paths) and the eye pass share it.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn shade_sample<L: Lane>(
    plan: &RenderPlan,
    material: &MaterialPlan,
    tf: &mut TfLanes<L>,
    (inside, lit_from): (L, L),
    iin: &[L],
    surface: Option<([L; 3], L::M)>,
    (color, alpha): (&mut [L; 3], &mut L),
    lanes: L::M,
) {
    let terms = |l: usize| LightTerms::of(plan, material, l);
    shade_sample_with(
        plan,
        material,
        tf,
        (inside, lit_from),
        iin,
        surface,
        (color, alpha),
        lanes,
        terms,
    );
}

/// [`shade_sample`] with each light's shading terms given by `terms` (`shade_with`): the eye
/// pass's point lights, whose direction and falloff change from sample to sample.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn shade_sample_with<L: Lane>(
    plan: &RenderPlan,
    material: &MaterialPlan,
    tf: &mut TfLanes<L>,
    (inside, lit_from): (L, L),
    iin: &[L],
    surface: Option<([L; 3], L::M)>,
    (color, alpha): (&mut [L; 3], &mut L),
    lanes: L::M,
    terms: impl Fn(usize) -> LightTerms,
) {
    let surface = surface.map(|(normal, lanes)| Surface {
        normal,
        lanes,
        alpha: tf.alpha,
    });
    let light = part_of_slab(tf, inside, lit_from);
    let lights = material.light_color.len();
    let ch = plan.channels as usize;
    let shaded = shade_with(
        ch,
        lights,
        terms,
        material,
        tf.color,
        iin,
        surface.as_ref(),
        &plan.horizon,
    );
    let shaded = [0, 1, 2].map(|c| shaded[c] * light[c]);
    composite(color, alpha, shaded, tf.alpha, lanes, plan.turned_round);
}

/// Front to back, `C += (1 − A)·α·c`, `A += (1 − A)·α`, in that order; with `back_to_front`
/// (a turned-round pass, the viewer at the sweep's far end) `C = α·c + (1 − α)·C`,
/// `A = α + (1 − α)·A`. Applied only in the lanes of `lanes` (planar colours: one lane value
/// per channel).
#[inline(always)]
pub fn composite<L: Lane>(
    color: &mut [L; 3],
    alpha: &mut L,
    c: [L; 3],
    a: L,
    lanes: L::M,
    back_to_front: bool,
) {
    if back_to_front {
        let keep = L::splat(1.0) - a;
        for (dst, src) in color.iter_mut().zip(c) {
            *dst = L::select(lanes, a * src + keep * *dst, *dst);
        }
        *alpha = L::select(lanes, a + keep * *alpha, *alpha);
        return;
    }
    let t = (L::splat(1.0) - *alpha) * a;
    for (dst, src) in color.iter_mut().zip(c) {
        *dst = L::select(lanes, *dst + t * src, *dst);
    }
    *alpha = L::select(lanes, *alpha + t, *alpha);
}

/// What a fraction `f` of a slab takes out where the whole slab takes out `s` (an opacity, or
/// `1 − attenuation`): `1 − (1 − s)^f` to second order in `s`, `f·s·(1 + (1 − f)·s/2)`, exact at
/// `f` = 0 and 1 and between those two values for every `s` in 0…1 (powers are not bit-exact
/// across CPU and GPU, these four products and sums are).
#[inline(always)]
pub fn taken_out<L: Lane>(s: L, f: L) -> L {
    let one = L::splat(1.0);
    f * s * (one + (one - f) * s * L::splat(0.5))
}

/// A medium's slab as the part of it the pixel spends inside (`crate::parity::slab_part`):
/// its opacity and attenuation scaled to the fraction `inside` of the slab ([`taken_out`]), so
/// that a medium's entry and exit slabs take out only what lies inside it (a strip of thickness
/// t is t/e slabs thick, not t/e + 1); and returns, per channel, the light's attenuation over
/// the fraction `lit_from` of the slab, the way the light has come through the slab's medium
/// where it lights the sample (the middle of the part inside: without it a medium's colour
/// converged at first order in e). Lanes with opacity 1 (surfaces) keep every bit and get factor
/// 1; `inside` = 1 keeps the entry's opacity and attenuation, `lit_from` = 0 gives factor 1.
#[inline(always)]
pub fn part_of_slab<L: Lane>(tf: &mut TfLanes<L>, inside: L, lit_from: L) -> [L; 3] {
    let one = L::splat(1.0);
    let medium = tf.alpha.lt(one);
    let light = tf
        .attenuation
        .map(|a| L::select(medium, one - taken_out(one - a, lit_from), one));
    let partial = inside.lt(one);
    let part = |new: L, old: L| L::select(medium, L::select(partial, new, old), old);
    tf.alpha = part(taken_out(tf.alpha, inside), tf.alpha);
    for a in tf.attenuation.iter_mut() {
        *a = part(one - taken_out(one - *a, inside), *a);
    }
    light
}

/// `Iout = Iin · attenuation`, flushed to zero below [`FLUSH_BELOW`].
#[inline(always)]
pub fn attenuate<L: Lane>(iin: L, attenuation: L) -> L {
    let v = iin * attenuation;
    L::select(v.lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// Distance penumbra: the occluder-depth plane after a slab, `D + at · removed` (`removed`:
/// the light the slab took out, summed over channels, at depth `at` (slabs) per lane: this
/// slab, where a held surface was crossed (see [`hold_step`]), or an opaque crossing's
/// `crate::subpixel::removal_depth`), flushed where its magnitude is below [`FLUSH_BELOW`]
/// (D is negative where light was removed before slab 0's middle).
#[inline(always)]
pub fn deepen<L: Lane>(depth: L, at: L, removed: L) -> L {
    let v = depth + at * removed;
    L::select(v.abs().lt(L::splat(FLUSH_BELOW)), L::splat(0.0), v)
}

/// Distance penumbra at a held surface's release: the surface owns the pixel's darkness, so the
/// occluder-depth plane becomes `at · occluded` (`occluded`: channels − Σ outgoing light, all
/// of it once released), not [`deepen`]'s `D + at · removed`. Behind an opaque surface every
/// shadow edge is the surface's own, and the hold (`RenderPlan::surface_hold`) is sized for a
/// released pixel whose level is its own distance; a mean with
/// an occluder whose penumbra fell on the surface gave it a larger level, which its neighbours'
/// level search took up, gathering the surface's own zeros (measured on a receiver 60° to the
/// slabs: RMSE 0.015 → 0.009 against the closed form; docs/accuracy.md §2b).
#[inline(always)]
pub fn owned_depth<L: Lane>(at: L, occluded: L) -> L {
    deepen(L::splat(0.0), at, occluded)
}

/// A pixel's surface hold (`RenderPlan::surface_hold`), packed in one `u32`: 0 when it holds
/// nothing, else the slab its surface was crossed in (the low [`HOLD_SHIFT`] bits: slabs are
/// fewer than 2¹⁶), how many slabs it passes the light (10 bits) and how many slabs of barrier
/// follow its release (the bits from [`HOLD_BARRIER_SHIFT`]).
pub const HOLD_SHIFT: u32 = 16;

/// Where a pixel's hold state keeps its barrier ([`HOLD_SHIFT`]).
pub const HOLD_BARRIER_SHIFT: u32 = 26;

/// A pixel's hold state's crossing slab bits.
pub const HOLD_SLAB_MASK: u32 = (1 << HOLD_SHIFT) - 1;

/// A pixel's hold state's hold length bits, below [`HOLD_SHIFT`] once shifted.
pub const HOLD_LENGTH_MASK: u32 = (1 << (HOLD_BARRIER_SHIFT - HOLD_SHIFT)) - 1;

/// A pixel's hold state of crossing slab `crossed`, hold `hold` and barrier `barrier`.
#[inline(always)]
pub const fn hold_state(crossed: u32, hold: u32, barrier: u32) -> u32 {
    crossed | (hold << HOLD_SHIFT) | (barrier << HOLD_BARRIER_SHIFT)
}

/// The slab in which a pixel's hold state `state` (non-zero) releases its light: from there on
/// it removes it, through its barrier.
#[inline(always)]
pub const fn release_slab(state: u32) -> u32 {
    (state & HOLD_SLAB_MASK) + ((state >> HOLD_SHIFT) & HOLD_LENGTH_MASK)
}

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

/// Advances a pixel's packed surface hold `hold` ([`HOLD_SHIFT`]) through slab `slab`, in
/// which its cursor crossed a triangle whose packed hold word
/// (`convshadow_common::plan::surface_hold::pack_holds`) is `crossed` (0: no crossing, or one
/// that neither holds nor bars). A pending hold passes the light until its release slab, or
/// until `ends_hold` — the pixel crossed a fragment in this slab and has more ahead: its column
/// leaves the held mesh (or meets another surface) with something behind, which light held on
/// would reach through the mesh (a thin plate steep to a soft point light lost its whole shadow
/// on a sheet behind it to a 1023-slab hold), and the light is removed in that slab only. A
/// release at the hold's end removes it in that slab and then, outside every closed mesh
/// (`inside`: the pixel is in one, whose slabs remove it; a crossing there starts a hold as
/// anywhere), through a thin shell's **barrier** (`surface_hold::barrier`); a shell's crossing
/// that holds nothing starts its barrier in the slab after it (its own attenuation removes the
/// light in its slab). Else a crossing with a hold starts one. Every lane path runs it in every
/// slab from a hold's release to its barrier's end and where a pixel crosses a fragment, so its
/// state never goes stale.
#[inline(always)]
pub fn hold_step(hold: &mut u32, slab: u32, crossed: u32, ends_hold: bool, inside: bool) -> Held {
    let entry = surface_hold::entry_of(crossed);
    let barrier = surface_hold::barrier_of(crossed);
    let packed = *hold;
    if packed != 0 {
        let start = packed & ((1 << HOLD_SHIFT) - 1);
        let (mut release, mut bar) = (release_slab(packed), packed >> HOLD_BARRIER_SHIFT);
        if slab < release {
            if !ends_hold {
                return Held::Pass;
            }
            (release, bar) = (slab, 0);
        }
        if slab <= release + bar {
            if slab == release + bar {
                *hold = 0;
            }
            if slab == release || !inside {
                return Held::Release { removed_at: start };
            }
            // Inside a closed mesh: its slabs remove the light; a crossing may hold anew.
            if entry == 0 {
                return Held::Free;
            }
        }
        *hold = 0;
    }
    if entry != 0 {
        *hold = hold_state(slab, entry, barrier);
        return Held::Pass;
    }
    if barrier != 0 && !inside {
        *hold = hold_state(slab, 0, barrier);
    }
    Held::Free
}

mod held;

pub use held::{
    HELD_CELL, HELD_PART_MAX, HELD_SLOT_WORDS, HELD_WORDS, HIDER_WORDS, HeldPlanes, HeldRecords,
    HeldSlot, NO_HELD_SLAB,
};

/// The final `C += (1 − A)·background`.
#[inline(always)]
pub fn finish(color: &mut [f32; 3], alpha: f32, background: [f32; 3]) {
    let t = 1.0 - alpha;
    color[0] += t * background[0];
    color[1] += t * background[1];
    color[2] += t * background[2];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hold_passes_until_its_release_or_a_crossing_with_something_behind() {
        // Crossed in slab 10 with a hold of 5: passes through slab 14, released in 15.
        let mut hold = 0;
        let step =
            |hold: &mut u32, slab, crossed, ends| hold_step(hold, slab, crossed, ends, false);
        assert_eq!(step(&mut hold, 10, 5, false), Held::Pass);
        for slab in 11..15 {
            assert_eq!(step(&mut hold, slab, 0, false), Held::Pass, "{slab}");
        }
        let released = Held::Release { removed_at: 10 };
        assert_eq!(step(&mut hold, 15, 0, false), released);
        assert_eq!((hold, step(&mut hold, 16, 0, false)), (0, Held::Free));
        // The mesh's far face with nothing behind it (a floor) does not end the hold.
        assert_eq!(step(&mut hold, 10, 5, false), Held::Pass);
        assert_eq!(step(&mut hold, 12, 0, false), Held::Pass);
        // A crossing with fragments behind it ends it there, at the first crossing's depth,
        // and starts no new hold (the light is gone).
        assert_eq!(step(&mut hold, 13, 7, true), released);
        assert_eq!((hold, step(&mut hold, 14, 0, false)), (0, Held::Free));
    }

    #[test]
    fn a_released_light_stays_out_through_the_barrier_outside_closed_meshes() {
        use surface_hold::pack_holds;
        // A shell held 5 with barrier 3: passes 10..=14, removed 15..=18 (at its depth), free.
        let mut hold = 0;
        let shell = pack_holds(5, 0, 3);
        assert_eq!(hold_step(&mut hold, 10, shell, false, false), Held::Pass);
        for slab in 11..15 {
            assert_eq!(hold_step(&mut hold, slab, 0, false, false), Held::Pass);
        }
        let released = Held::Release { removed_at: 10 };
        for slab in 15..19 {
            assert_eq!(
                hold_step(&mut hold, slab, 0, false, false),
                released,
                "{slab}"
            );
        }
        assert_eq!(
            (hold, hold_step(&mut hold, 19, 0, false, false)),
            (0, Held::Free)
        );
        // Inside a closed mesh the barrier leaves the light to the mesh's slabs (the release
        // slab itself removes it), and a crossing there holds anew.
        hold_step(&mut hold, 10, shell, false, false);
        assert_eq!(hold_step(&mut hold, 15, 0, false, true), released);
        assert_eq!(hold_step(&mut hold, 16, 0, false, true), Held::Free);
        assert_eq!(hold_step(&mut hold, 17, 0, false, false), released);
        assert_eq!(hold_step(&mut hold, 18, 4, false, true), Held::Pass);
        assert_eq!(release_slab(hold), 22);
        // A crossing that cuts a hold short removes the light in its slab only.
        let mut hold = 0;
        hold_step(&mut hold, 10, pack_holds(50, 0, 4), false, false);
        assert_eq!(
            hold_step(&mut hold, 20, pack_holds(0, 0, 2), true, false),
            released
        );
        assert_eq!(
            (hold, hold_step(&mut hold, 21, 0, false, false)),
            (0, Held::Free)
        );
        // A shell's crossing that holds nothing bars the slabs after its own, outside closed
        // meshes only.
        let bars = pack_holds(0, 0, 2);
        assert_eq!(hold_step(&mut hold, 30, bars, false, false), Held::Free);
        let released = Held::Release { removed_at: 30 };
        assert_eq!(hold_step(&mut hold, 31, 0, false, false), released);
        assert_eq!(hold_step(&mut hold, 32, 0, false, false), released);
        assert_eq!(
            (hold, hold_step(&mut hold, 33, 0, false, false)),
            (0, Held::Free)
        );
        assert_eq!(hold_step(&mut hold, 30, bars, false, true), Held::Free);
        assert_eq!(hold, 0);
    }

    #[test]
    fn a_part_of_a_slab_takes_out_the_power_to_second_order() {
        for s in [0.0f32, 0.01, 0.1, 0.3, 0.7, 1.0] {
            // Exact at the ends: nothing, and the whole slab.
            assert_eq!(taken_out(s, 0.0), 0.0);
            assert_eq!(taken_out(s, 1.0), s);
            for f in [0.1f32, 0.25, 0.5, 0.9] {
                let got = f64::from(taken_out(s, f));
                let exact = 1.0 - (1.0 - f64::from(s)).powf(f64::from(f));
                // The neglected terms all take out more, each at most s times the one before:
                // the first, f(1 − f)(2 − f)s³/6, over (1 − s) bounds them (plus f32 rounding).
                if s < 1.0 {
                    let first = f64::from(f * (1.0 - f) * (2.0 - f) * s * s * s) / 6.0;
                    let bound = first / (1.0 - f64::from(s)) + 1e-6;
                    assert!(got <= exact + 1e-6 && exact - got <= bound, "s {s} f {f}");
                }
                // Between the ends' values, for every s.
                assert!((0.0..=f64::from(s) + 1e-7).contains(&got));
            }
        }
    }

    #[test]
    fn only_a_translucent_slab_is_scaled() {
        let entry = |alpha: f32| TfLanes {
            color: [0.5f32; 3],
            alpha,
            attenuation: [0.2, 0.6, 1.0],
        };
        // An opaque entry (a surface) keeps its bits and its light.
        let mut opaque = entry(1.0);
        assert_eq!(part_of_slab(&mut opaque, 0.3, 0.15), [1.0; 3]);
        assert_eq!((opaque.alpha, opaque.attenuation), (1.0, [0.2, 0.6, 1.0]));
        // A whole slab lit at its front is the entry itself.
        let mut whole = entry(0.4);
        assert_eq!(part_of_slab(&mut whole, 1.0, 0.0), [1.0; 3]);
        assert_eq!((whole.alpha, whole.attenuation), (0.4, [0.2, 0.6, 1.0]));
        // A third of a slab, lit in its middle.
        let mut part = entry(0.4);
        let light = part_of_slab(&mut part, 1.0 / 3.0, 1.0 / 6.0);
        assert_eq!(part.alpha, taken_out(0.4, 1.0 / 3.0));
        for (c, a) in [0.2f32, 0.6, 1.0].iter().enumerate() {
            assert_eq!(part.attenuation[c], 1.0 - taken_out(1.0 - a, 1.0 / 3.0));
            assert_eq!(light[c], 1.0 - taken_out(1.0 - a, 1.0 / 6.0));
        }
        assert_eq!(part.color, [0.5; 3]);
        assert_eq!(light[2], 1.0, "a clear channel loses no light");
    }
}
