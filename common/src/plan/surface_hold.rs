//! The surface hold: how many slabs a crossed opaque surface waits before it takes the light
//! out of its own pixel, per triangle, computed once on the host.
//!
//! **Why.** A surface oblique to the slabs is crossed by neighbouring pixels in different slabs.
//! Where an opaque surface zeroed a pixel's light as soon as it was crossed, a neighbour crossed
//! a few slabs later gathered some of those zeros and the surface shadowed itself in bands (one
//! per slab it rises across the kernel's reach). Light reaching a point of a surface that faces
//! the light travels in front of the surface, never through the columns behind it; the zeros the
//! gather read were the surface's own, seen from behind.
//!
//! **What.** The surface takes its light out `B` slabs late: the pixel keeps passing the light it
//! gathers for `B` slabs after the crossing (they are hidden behind the opaque surface in the
//! image), then removes it at once. Its neighbours, crossed later, gather the light that would be
//! there without the surface, which is the light travelling in front of it. Shadow maps call the
//! same fix slope-scaled depth bias; here the shadows that *other* occluders cast on the surface
//! are untouched (the surface reads the light at its own crossing), and the shadow the surface
//! casts keeps its depth (the distance penumbra records the crossing slab, not the release).
//!
//! **How many.** Let `g` be the surface's depth gradient in slabs per pixel, `m` the gather's
//! drift per slab (towards the light, pixels) and `Σ` its covariance per slab (pixels²). Light
//! reaching a pixel gathered `t` slabs earlier from offsets `t·m ± ξ`, `ξ` of covariance `t·Σ`;
//! the neighbour at offset `o` was crossed `g·o` slabs later than the pixel (earlier where
//! negative) and zeroes its light `B` slabs after that. None of those zeros is read within
//! [`HOLD_SIGMAS`] standard deviations when `k·√(t·gᵀΣg) + r ≤ a·t + B` for every `t`, with
//! `a = 1 + g·m` (`a ≤ 0`: the light comes from behind the surface, which does shadow itself —
//! no hold) and `r = 2·(|gx| + |gy|)` for the pixel a tap's whole-pixel carry of the mean and the
//! pixel its bilinear corner read beyond the Gaussian footprint (measured: with one pixel, a 60°
//! receiver under the distance penumbra kept 0.5 % bands): the largest left side minus
//! `a·t` is at `√t = k·√(gᵀΣg) / (2a)`, so `B = ⌈k²·gᵀΣg / (4a) + r⌉`. With the distance penumbra
//! a released neighbour gathers through the level of its own distance, `h = B + 1` slabs, whose
//! covariance step is `(2h − 1)·Σ1`: `B ≥ u·(2B + 1) + r` with `u = k²·gᵀΣ1g / (4a)`, i.e.
//! `B = ⌈(u + r) / (1 − 2u)⌉` while `u < ½`. The largest over lights, at most
//! [`MAX_SURFACE_HOLD`]; 0 (no hold: today's bits) where the surface rises less than
//! [`MIN_RISE`] slabs across the reach, as a surface facing the camera does.

use crate::model::scene::Penumbra;
use crate::plan::kernel::KernelMoments;

/// Standard deviations of the gather's footprint the hold keeps clear of the surface's own zeros.
pub const HOLD_SIGMAS: f64 = 4.0;

/// The longest hold (slabs): grazing surfaces (a → 0 or a steep rise under a wide kernel) are
/// held this long and may still band a little; it also bounds how far such a surface's shadow
/// lets light through behind it.
pub const MAX_SURFACE_HOLD: u32 = 1023;

/// Below this rise (slabs across the reach) a surface is held 0 slabs: no neighbour in reach is
/// crossed a slab earlier, so there is nothing to hold back (a surface facing the camera).
pub const MIN_RISE: f64 = 1.0e-3;

/// The hold, in slabs, of a triangle whose plane depth changes by `depth_dx` and `depth_dy`
/// world units per pixel, in a sweep of slab thickness `slab_distance` whose lights gather with
/// `moments` per slab (the iterated kernel's, or the distance penumbra's smallest level's);
/// `compensation`: the kernels include the bilinear reads' variance (else up to ¼ px² per axis
/// more). See the module documentation.
pub fn surface_hold(
    moments: &[KernelMoments],
    penumbra: Penumbra,
    compensation: bool,
    depth_dx: f32,
    depth_dy: f32,
    slab_distance: f64,
) -> u32 {
    let g = [
        f64::from(depth_dx) / slab_distance,
        f64::from(depth_dy) / slab_distance,
    ];
    // A tap's whole-pixel carry and its bilinear corner each read one pixel further.
    let reach = 2.0 * (g[0].abs() + g[1].abs());
    if reach.is_nan() || reach < MIN_RISE {
        return 0;
    }
    let k2 = HOLD_SIGMAS * HOLD_SIGMAS;
    let mut hold = 0.0f64;
    for m in moments {
        // The gather reads against the impulse response's motion.
        let a = 1.0 - (g[0] * m.mean[0] + g[1] * m.mean[1]);
        if a <= 0.0 {
            continue;
        }
        let extra = if compensation { 0.0 } else { 0.25 };
        let (sxx, sxy, syy) = (m.cov[0][0] + extra, m.cov[0][1], m.cov[1][1] + extra);
        let spread = g[0] * g[0] * sxx + 2.0 * g[0] * g[1] * sxy + g[1] * g[1] * syy;
        let u = k2 * spread / (4.0 * a);
        let b = match penumbra {
            Penumbra::Iterated => u + reach,
            Penumbra::Distance if 2.0 * u < 1.0 => (u + reach) / (1.0 - 2.0 * u),
            Penumbra::Distance => f64::INFINITY,
        };
        hold = hold.max(b);
    }
    if hold.is_nan() {
        return MAX_SURFACE_HOLD;
    }
    (hold.ceil().min(f64::from(MAX_SURFACE_HOLD))) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(mean: [f64; 2], var: f64) -> KernelMoments {
        KernelMoments {
            mean,
            cov: [[var, 0.0], [0.0, var]],
        }
    }

    #[test]
    fn a_surface_facing_the_camera_is_not_held() {
        let l = [light([0.3, 0.0], 2.0)];
        assert_eq!(
            surface_hold(&l, Penumbra::Iterated, true, 0.0, 0.0, 0.01),
            0
        );
        assert_eq!(
            surface_hold(&l, Penumbra::Distance, true, 0.0, 0.0, 0.01),
            0
        );
    }

    #[test]
    fn the_hold_follows_the_bound_in_closed_form() {
        // g = (0, 2) slabs per pixel, Σ = 1 px², no drift: B = ⌈16·4/4 + 2·2⌉ = 20.
        let l = [light([0.0, 0.0], 1.0)];
        let hold = |l: &[KernelMoments], p, comp| surface_hold(l, p, comp, 0.0, 0.02, 0.01);
        assert_eq!(hold(&l, Penumbra::Iterated, true), 20);
        // Without compensation the bilinear reads add ¼ px²: B = ⌈16·4·1.25/4 + 4⌉ = 24.
        assert_eq!(hold(&l, Penumbra::Iterated, false), 24);
        // Distance: u = 16·4·0.01/4 = 0.16, B = ⌈(0.16 + 4)/(1 − 0.32)⌉ = ⌈6.12⌉ = 7.
        let l = [light([0.0, 0.0], 0.01)];
        assert_eq!(hold(&l, Penumbra::Distance, true), 7);
    }

    #[test]
    fn a_surface_lit_from_behind_its_plane_is_not_held() {
        // The impulse response moves −0.75 px in y per slab (the gather reads +0.75 px), the
        // surface rises 2 slabs per pixel towards −y: a = 1 − 2·0.75·… < 0.
        let l = [light([0.0, 0.75], 0.5)];
        assert_eq!(
            surface_hold(&l, Penumbra::Iterated, true, 0.0, 0.02, 0.01),
            0
        );
        // The other way round it faces the light and is held.
        assert!(surface_hold(&l, Penumbra::Iterated, true, 0.0, -0.02, 0.01) > 0);
    }
}
