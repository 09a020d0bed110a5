//! Sub-pixel shadows (`sweep.subpixel_shadows`, distance penumbra): the light a crossed opaque
//! surface is shaded with, read at its exact shift from the occluders that cast its shadow.
//! Mirrors `gpu/src/shaders/subpixel.wgsl` function for function (`exact_shift`,
//! `shifted_gather`, `removal_depth`); the per-pixel stage (`crate::sweep::pixel`) calls it,
//! and the SIMD path's chunks call it lane by lane for the lanes that cross such a surface.
//!
//! Why: where a light is narrow per slab the sweep carries its drift in whole pixels
//! (`KernelTable::slab_shift`), so an occluder in slab j reaches slab k shifted by
//! `round((k + 1)·μ) − round((j + 1)·μ)` instead of the exact drift over the distance between
//! the two surfaces — off by up to a pixel, plus up to μ for where each surface lies inside its
//! slab. The depth plane knows the mean occluder depth z̄ (its slab and, for an opaque crossing,
//! its place inside the slab: [`removal_depth`]), the crossing knows its own, so the surface's
//! light is read once, bilinearly, where the exact drift puts it. Only the shading read moves:
//! the buffer the next slab gathers from keeps the carried light.

use convshadow_common::pixel::levels::{LevelAt, pixel_level};
use convshadow_common::plan::{LightPlan, OCCLUSION_EPS};

use crate::kernels::{LightPlanes, TapOrigin};
use convshadow_common::plan::kernel::Tap;

/// The smallest part of its slab a crossing is recorded at: a crossing on the slab's front face
/// (part 0) would otherwise round its pixel's next level one up (`pixel_level`).
pub const MIN_PART: f32 = 1.0 / 256.0;

/// The depth (slabs) at which an opaque crossing in slab `slab` records the light it removes in
/// the depth plane: `slab + part − ½`, `part` the crossing's place inside the slab (0 at its
/// front face, at least [`MIN_PART`]). A medium's slab removes its light at `slab`, the middle
/// of the slab (part ½) in the same convention, so the levels (`k − z̄` rounded) are unchanged.
#[inline(always)]
pub fn removal_depth(slab: u32, part: f32) -> f32 {
    slab as f32 + (part.max(MIN_PART) - 0.5)
}

/// Where, relative to itself, a pixel that crossed an opaque surface in slab `slab` at `part`
/// of the slab (0 at its front face) must read light `light`'s buffer: `None` where the light
/// it gathered is unoccluded (`lit`: the sum of its channels, out of `channels`; `depth`: its
/// gathered depth plane), or where its occluders lie at several depths: the level of its mean
/// occluder depth is not `row_level`, the level it gathered through (the nearest occluder's in
/// its reach) — one mean depth then stands for none of them, and its drift would move every
/// shadow by the wrong amount. Else the offset (pixels) between the carried and the exact
/// drift from the mean occluder, `(ε_k − ε_j) + (part_j − part)·μ` per axis, with
/// z̄ + ½ = j + part_j (j clamped to the slabs, part_j to 0…1) and ε the light's
/// [`LightPlan::carry_residual`].
#[inline(always)]
pub fn exact_shift(
    light: &LightPlan,
    (slab, part): (u32, f32),
    (lit, channels): (f32, u32),
    depth: f32,
    row_level: u32,
) -> Option<[f32; 2]> {
    let occluded = channels as f32 - lit;
    // `!(occluded > ε)` as subpixel.wgsl writes it (NaN: no occluder, as in `pixel_level`).
    if occluded <= OCCLUSION_EPS || occluded.is_nan() {
        return None;
    }
    // A slab grid's (a point light's grid has no drift to shift by: no sub-pixel shadows).
    if pixel_level::<f32>(&light.table, occluded, depth, LevelAt::slab(slab)) != row_level {
        return None;
    }
    let residual = &light.carry_residual;
    let t = depth / occluded + 0.5;
    let last = residual.len() as f32 - 1.0;
    let j = t.floor().clamp(0.0, last);
    let part_j = (t - j).clamp(0.0, 1.0);
    let (ek, ej) = (residual[slab as usize], residual[j as usize]);
    let along = part_j - part;
    Some([0, 1].map(|a| (ek[a] - ej[a]) + along * light.drift[a]))
}

/// The light's channels gathered through `taps` at `at` moved by `shift` (pixels): the gathers
/// at the four whole-pixel origins around it, blended bilinearly as `a + f·(b − a)` along x,
/// then along y (a uniform light reads back exactly); an axis whose fraction is 0 gathers once.
/// Every read is bounds-checked (the moved taps may leave the sweep's interior). `gather` is
/// [`gather`] or a gather that reads some corners otherwise (`kernels::gather_held`).
#[inline(always)]
pub fn shifted_gather(
    planes: &LightPlanes<'_>,
    taps: &[Tap],
    at: TapOrigin,
    shift: [f32; 2],
    gather: impl Fn(&LightPlanes<'_>, &[Tap], TapOrigin) -> [f32; 4],
) -> [f32; 4] {
    let (ix, iy) = (shift[0].floor(), shift[1].floor());
    let (fx, fy) = (shift[0] - ix, shift[1] - iy);
    let origin = |dx: i32, dy: i32| TapOrigin {
        x: at.x + ix as i32 + dx,
        y: at.y + iy as i32 + dy,
        shift: at.shift,
        inside: false,
    };
    let along_x = |dy: i32| {
        let a = gather(planes, taps, origin(0, dy));
        if fx == 0.0 {
            return a;
        }
        let b = gather(planes, taps, origin(1, dy));
        lerp(a, b, fx)
    };
    let top = along_x(0);
    if fy == 0.0 {
        return top;
    }
    lerp(top, along_x(1), fy)
}

/// `a + f·(b − a)` per plane.
#[inline(always)]
fn lerp(a: [f32; 4], b: [f32; 4], f: f32) -> [f32; 4] {
    [0, 1, 2, 3].map(|c| a[c] + f * (b[c] - a[c]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::gather;

    #[test]
    fn a_crossing_on_the_front_face_keeps_its_level() {
        // Level h = trunc(k + 1 − z̄ + ½) (pixel_level): with z̄ = slab, h = k + 1 − slab.
        for part in [0.0f32, MIN_PART, 0.3, 0.5, 0.999] {
            let z = removal_depth(10, part);
            let h = (11.0 - z + 0.5).trunc();
            assert_eq!(h, 1.0, "part {part}: z̄ {z}");
        }
        // The medium's convention: part ½ is the slab itself.
        assert_eq!(removal_depth(7, 0.5), 7.0);
    }

    #[test]
    fn a_shifted_gather_reads_a_ramp_where_the_shift_puts_it() {
        // A plane v = x + 16·y through one tap of weight 1: bilinear reads of a linear function
        // are exact, so the read at (5, 5) moved by s is the ramp at (5 + sx, 5 + sy); beyond the
        // grid every read is the unoccluded light.
        let data: Vec<f32> = (0..256)
            .map(|i| (i % 16) as f32 + 16.0 * (i / 16) as f32)
            .collect();
        let planes = LightPlanes {
            data: &data,
            base: 0,
            channels: 1,
            light_channels: 1,
            row_stride: 16,
            pixel_step: 1,
            plane_step: 1,
            width: 16,
            height: 16,
        };
        let taps = [Tap {
            dx: 0,
            dy: 0,
            w: [1.0, 0.0, 0.0, 0.0],
        }];
        let at = TapOrigin {
            x: 5,
            y: 5,
            shift: [1, -2],
            inside: true,
        };
        for s in [[0.0f32, 0.0], [0.25, -0.5], [-1.75, 0.125], [2.0, 1.5]] {
            let want = (6.0 + s[0]) + 16.0 * (3.0 + s[1]);
            assert_eq!(
                shifted_gather(&planes, &taps, at, s, gather)[0],
                want,
                "shift {s:?}"
            );
        }
        let beyond = TapOrigin { x: 40, ..at };
        assert_eq!(
            shifted_gather(&planes, &taps, beyond, [0.5, 0.5], gather)[0],
            1.0
        );
    }

    #[test]
    fn a_uniform_light_reads_back_exactly() {
        for v in [0.0f32, 0.3, 1.0] {
            for f in [0.0f32, 0.25, 0.7, 0.999] {
                assert_eq!(lerp([v; 4], [v; 4], f), [v; 4]);
            }
        }
    }
}
