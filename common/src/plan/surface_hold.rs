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
//!
//! **Who reads the held light.** The light a held pixel passes is the light *in front of* its
//! surface, right for a neighbour on the surface's lit side and wrong for one behind it: light
//! stepped from held pixels sideways into columns behind a thin plate turned towards the light
//! (its whole umbra half lit), and past a surface's far edge into columns that never cross it.
//! So a gather reading a pixel held in the previous slab (by an entry hold) reads no light
//! there (and the depth plane the crossing's depth, as if the light had been removed) when the
//! reader, not held itself, lies more than [`HELD_BEHIND_MARGIN`] slabs behind the held pixel's
//! surface plane at its own column and the light reaching the held pixel crossed that plane
//! where the surface is: the column the light came from, `t = (k − 1 − z₀ + ½)/(1 − g·m)` slabs
//! back along the drift `m`, crossed a surface within [`SAME_SURFACE_SLABS`] of the plane there
//! (else the light passed beside the surface: a light grazing it). Each pixel records the plane
//! of its last two holds (`cpu::composite::HeldPlanes`, composite.wgsl); the slopes per triangle
//! are [`RenderPlan::hold_slopes`](crate::plan::RenderPlan::hold_slopes), clamped to
//! ±[`MAX_HOLD_SLOPE`] slabs per pixel.
//!
//! **Released light served on its own surface.** Once a held pixel releases, it holds no light
//! and (distance penumbra) its own crossing as the occluder of all of it; a neighbour on the
//! same surface, held or not yet crossed, whose gather reaches it, read those zeros and that
//! depth: in another occluder's penumbra on a 60° receiver the mean occluder depth of the
//! receiver's pixels rose by up to 17 slabs and the half-shadow line moved up to 1 px
//! (docs/accuracy.md §2b). So each released pixel keeps the light and depth plane it gathered in
//! its release slab (the light in front of its surface then), and for [`served_release_slabs`]
//! slabs a gather whose pixel lies on the same plane reads those instead: the reader's surface
//! (its held crossing, else the next fragment its cursor will cross) lies within
//! [`SAME_SURFACE_SLABS`] of the released pixel's plane extended to the reader, with slopes
//! within [`SERVED_SLOPE_TOLERANCE`] of the plane's. A reader elsewhere — behind the surface,
//! on another surface, on a curved surface turning away near its outline — reads the zeros as
//! before: they are the surface's shadow.

use crate::model::scene::Penumbra;
use crate::plan::kernel::KernelMoments;

/// Slabs a reader must lie behind a held neighbour's surface plane before it reads no light from
/// it (see the module documentation): a convex surface lies behind its neighbouring triangles'
/// planes by its curvature, and a reader on it must still read its neighbours' held light
/// (measured on the `floor` scene's torus: 1 slab left dark speckles on it, 3 none).
pub const HELD_BEHIND_MARGIN: f32 = 3.0;

/// How far (slabs) the surface a column crossed may lie from a held neighbour's plane extended
/// to that column and still count as the neighbour's surface.
pub const SAME_SURFACE_SLABS: f32 = 1.5;

/// Slabs after its release during which a released pixel's light is served to gathers on its
/// surface (see "Released light served on its own surface" above), in a sweep of up to 512
/// slabs: long enough for the neighbours a 60° receiver's gathers reach at 512 slabs (4 needed,
/// measured), short enough that the served light has not drifted far. With more slabs the same
/// depth ([`served_release_slabs`]): a receiver rises by more slabs across a gather's reach.
pub const SERVED_RELEASE_SLABS: u32 = 8;

/// Slabs of a sweep per slab of [`served_release_slabs`] beyond its first
/// [`SERVED_RELEASE_SLABS`].
pub const SWEEP_SLABS_PER_SERVED_SLAB: u32 = 64;

/// Slabs after its release during which a released pixel's light is served, in a sweep of
/// `slabs` slabs: [`SERVED_RELEASE_SLABS`], or 1/64 of the sweep where that is more (the 60°
/// receiver at 2048 slabs needs 16; with 8 its RMSE was 0.0043 against 0.0007).
pub fn served_release_slabs(slabs: u32) -> u32 {
    SERVED_RELEASE_SLABS.max(slabs.div_ceil(SWEEP_SLABS_PER_SERVED_SLAB))
}

/// How much a reader's surface slopes may differ from a released neighbour's plane (sum of both
/// axes, slabs per pixel) while still counting as one plane: this plus the same fraction of the
/// plane's own slopes (a curved surface near its outline turns faster).
pub const SERVED_SLOPE_TOLERANCE: f32 = 0.05;

/// Words per slot of a pixel's served release (`cpu::composite::HeldPlanes`, composite.wgsl)
/// before its light's values: the slab it released in.
pub const SERVED_HEAD_WORDS: usize = 1;

/// The largest depth slope (slabs per pixel) kept in `RenderPlan::hold_slopes`: a triangle seen
/// edge on has an unbounded one, and every product in the read test must stay finite.
pub const MAX_HOLD_SLOPE: f64 = 65536.0;

/// Words per slot of a pixel's held-plane record (`cpu::composite::HeldPlanes`, composite.wgsl): the slab its hold started
/// (its crossing), the slab it stopped passing, the crossing's depth in slabs (f32 bits) and
/// the crossed triangle.
pub const HELD_SLOT_WORDS: usize = 4;

/// Words per pixel of the held-plane records: two slots.
pub const HELD_WORDS: usize = 2 * HELD_SLOT_WORDS;

/// A slot's `from` while it records nothing (every word starts at this value).
pub const NO_HELD_SLAB: u32 = u32::MAX;

/// The largest part of its slab a held crossing's recorded depth adds to its slab
/// (`HeldSlot::z0`): below 1, so that the slab stays the depth's whole part.
pub const HELD_PART_MAX: f32 = 0.99;

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
    let g = slopes(depth_dx, depth_dy, slab_distance);
    // The gather reads against the impulse response's motion.
    hold_slabs(moments, penumbra, compensation, g, |gm| 1.0 - gm)
}

/// The **exit hold** of the same triangle: how many slabs before a pixel leaves a light-blocking
/// mesh through it the pixel passes the light it gathers, where the light reaches the surface
/// from outside the mesh — from the side the pixel's column reaches after the crossing (where
/// the entry's `a` above is ≤ 0). The sweep sees such a face from inside (the turned-round pass's view
/// of a floor's top face): the light reaching it comes only from columns that left the mesh
/// earlier, and where a narrow light's drift is carried in whole pixels (0 in some slabs) the
/// crossing read its own column, still inside the mesh — a black row. Passing the light for
/// these slabs gives the columns in front of the face the light as if the mesh were not there,
/// as the hold does behind an entry; the same bound with the mirrored `a = g·m − 1`. 0 where the
/// light reaches the face from inside or the face rises less than [`MIN_RISE`].
pub fn exit_hold(
    moments: &[KernelMoments],
    penumbra: Penumbra,
    compensation: bool,
    depth_dx: f32,
    depth_dy: f32,
    slab_distance: f64,
) -> u32 {
    let g = slopes(depth_dx, depth_dy, slab_distance);
    hold_slabs(moments, penumbra, compensation, g, |gm| gm - 1.0)
}

/// The longest barrier (slabs, [`barrier`]): it fits the 6 bits a pixel's hold state keeps.
pub const MAX_BARRIER: u32 = 63;

/// The **barrier** of a thin shell's triangle (an open mesh, [`crate::plan::RenderPlan`]'s
/// triangles outside the parity test): how many slabs after the slab that removes its light (a
/// hold's release, or the crossing itself where it holds nothing) the pixel keeps removing the
/// light it gathers. A shell is one slab thick in its column, and a gather reading a column
/// upstream of the light, which the shell crosses `g·d` slabs later, reads light from in front
/// of the shell into the column behind it: a tilted opaque shell let up to half the light
/// through (a grey shadow; the teapot's on its wall). The pixel keeps its light out until every
/// column it reads has removed its own, so that the columns' dark stretches join in a wall the
/// light cannot step over: the largest `g·d` over the reads — `−g·m` for the mean read (the
/// gather reads against the impulse response's motion `m`), [`HOLD_SIGMAS`] of its spread and
/// a bilinear corner's pixel on each axis. With the distance penumbra a released column
/// gathers through the level of its distance, `h = B + 1 + X` slabs from the surface (`B`: the
/// hold before, `entry`), whose spread is `(2h − 1)` single levels'. The largest over lights,
/// those reaching the shell's far side included; 0 (one slab, as a surface facing the camera
/// needs) where that needs no more or the surface rises less than [`MIN_RISE`]; at most
/// [`MAX_BARRIER`]. A closed mesh needs none: its inside removes the
/// light behind every entry.
pub fn barrier(
    moments: &[KernelMoments],
    penumbra: Penumbra,
    compensation: bool,
    (depth_dx, depth_dy): (f32, f32),
    slab_distance: f64,
    entry: u32,
) -> u32 {
    let g = slopes(depth_dx, depth_dy, slab_distance);
    let corners = g[0].abs() + g[1].abs();
    if corners.is_nan() || 2.0 * corners < MIN_RISE {
        return 0;
    }
    let k2 = HOLD_SIGMAS * HOLD_SIGMAS;
    let mut most = 0.0f64;
    for m in moments {
        let spread = spread(m, compensation, g);
        // Every light counts, one reaching the shell's far side too (a = 1 − g·m ≤ 0): skipping
        // those let a quad turned 75° under a light at 55° leak (0.073 against 0.025).
        let ahead = corners - (g[0] * m.mean[0] + g[1] * m.mean[1]);
        let x = match penumbra {
            Penumbra::Iterated => ahead + (k2 * spread).sqrt(),
            // X = A + k·√((2(B + X) + 1)·s), solved for X (the larger root).
            Penumbra::Distance => {
                let s = k2 * spread;
                let c = (2.0 * (f64::from(entry) + ahead) + 1.0).max(0.0);
                ahead + s + (s * s + s * c).sqrt()
            }
        };
        most = most.max(x);
    }
    if most.is_nan() {
        return MAX_BARRIER;
    }
    (most.ceil().clamp(0.0, f64::from(MAX_BARRIER))) as u32
}

/// Where the exit hold starts in a packed per-triangle hold word ([`pack_holds`]); the entry
/// hold lies below it.
pub const EXIT_HOLD_SHIFT: u32 = 10;

/// Where the barrier starts in a packed per-triangle hold word ([`pack_holds`]).
pub const BARRIER_SHIFT: u32 = 20;

/// The entry hold's bits of a packed per-triangle hold word ([`pack_holds`]).
pub const ENTRY_HOLD_MASK: u32 = (1 << EXIT_HOLD_SHIFT) - 1;

/// The entry hold of a packed per-triangle hold word ([`pack_holds`]).
pub const fn entry_of(word: u32) -> u32 {
    word & ENTRY_HOLD_MASK
}

/// The exit hold of a packed per-triangle hold word ([`pack_holds`]).
pub const fn exit_of(word: u32) -> u32 {
    (word >> EXIT_HOLD_SHIFT) & ((1 << (BARRIER_SHIFT - EXIT_HOLD_SHIFT)) - 1)
}

/// The barrier of a packed per-triangle hold word ([`pack_holds`]).
pub const fn barrier_of(word: u32) -> u32 {
    (word >> BARRIER_SHIFT) & MAX_BARRIER
}

/// One triangle's holds in one word, as the sweep and `sweep.wgsl` read them: the entry hold
/// ([`surface_hold`]) in the low [`EXIT_HOLD_SHIFT`] bits, the exit hold ([`exit_hold`]) above
/// (both at most [`MAX_SURFACE_HOLD`]), and a thin shell's barrier ([`barrier`]) above
/// [`BARRIER_SHIFT`].
pub fn pack_holds(entry: u32, exit: u32, barrier: u32) -> u32 {
    entry | (exit << EXIT_HOLD_SHIFT) | (barrier << BARRIER_SHIFT)
}

/// The depth gradient in slabs per pixel.
fn slopes(depth_dx: f32, depth_dy: f32, slab_distance: f64) -> [f64; 2] {
    [
        f64::from(depth_dx) / slab_distance,
        f64::from(depth_dy) / slab_distance,
    ]
}

/// The bound of the module documentation for gradient `g` (slabs per pixel), with `a` given by
/// `side` from `g·m`: the largest over lights, at most [`MAX_SURFACE_HOLD`].
fn hold_slabs(
    moments: &[KernelMoments],
    penumbra: Penumbra,
    compensation: bool,
    g: [f64; 2],
    side: impl Fn(f64) -> f64,
) -> u32 {
    // A tap's whole-pixel carry and its bilinear corner each read one pixel further.
    let reach = 2.0 * (g[0].abs() + g[1].abs());
    if reach.is_nan() || reach < MIN_RISE {
        return 0;
    }
    let k2 = HOLD_SIGMAS * HOLD_SIGMAS;
    let mut hold = 0.0f64;
    for m in moments {
        let a = side(g[0] * m.mean[0] + g[1] * m.mean[1]);
        if a <= 0.0 {
            continue;
        }
        let spread = spread(m, compensation, g);
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

/// `gᵀΣg` (slabs²): the variance of the crossing slab over one slab's reads of `m`, with the
/// bilinear reads' ¼ px² per axis where the kernels do not include it.
fn spread(m: &KernelMoments, compensation: bool, g: [f64; 2]) -> f64 {
    let extra = if compensation { 0.0 } else { 0.25 };
    let (sxx, sxy, syy) = (m.cov[0][0] + extra, m.cov[0][1], m.cov[1][1] + extra);
    g[0] * g[0] * sxx + 2.0 * g[0] * g[1] * sxy + g[1] * g[1] * syy
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
    fn a_face_lit_from_outside_is_held_before_its_exit_and_not_after_its_entry() {
        // Drift 0.3 px per slab along x, variance 2 px²; depth rising 5 slabs per pixel along x:
        // g·m = 1.5, so the light reaches the face from the side the column reaches after it.
        let l = [light([0.3, 0.0], 2.0)];
        type Hold = fn(&[KernelMoments], Penumbra, bool, f32, f32, f64) -> u32;
        let at = |f: Hold, dx: f32| f(&l, Penumbra::Iterated, true, dx, 0.0, 0.01);
        assert_eq!(at(surface_hold, 0.05), 0);
        // a = g·m − 1 = ½: u = 4²·(25·2)/(4·½) = 400, plus the reach 2·5: 410 slabs.
        assert_eq!(at(exit_hold, 0.05), 410);
        // The face turned the other way is an entry lit from the front: held after, not before.
        assert!(at(surface_hold, -0.05) > 0);
        assert_eq!(at(exit_hold, -0.05), 0);
        let word = pack_holds(3, 410, 63);
        assert_eq!(
            (entry_of(word), exit_of(word), barrier_of(word)),
            (3, 410, 63)
        );
    }

    #[test]
    fn the_barrier_follows_its_bound_in_closed_form() {
        // g = (2, 0) slabs per pixel; the impulse response moves −0.5 px in x per slab (the
        // gather reads columns crossed 1 slab later), Σ = ¼ px²: gᵀΣg = 1.
        let l = [light([-0.5, 0.0], 0.25)];
        let bar = |l: &[KernelMoments], p, entry| barrier(l, p, true, (0.02, 0.0), 0.01, entry);
        // Iterated: X = ⌈2 (corners) + 1 (mean) + 4·1⌉ = 7.
        assert_eq!(bar(&l, Penumbra::Iterated, 0), 7);
        // Distance after a hold of 5: X = 3 + 16 + √(16² + 16·(2·(5 + 3) + 1)) = 41.98 → 42.
        assert_eq!(bar(&l, Penumbra::Distance, 5), 42);
        // A light reaching the far side (a = 1 − g·m = −1): X = ⌈2 − 2 + 4⌉ = 4; none for a
        // shell facing the camera.
        assert_eq!(bar(&[light([1.0, 0.0], 0.25)], Penumbra::Iterated, 0), 4);
        let flat = barrier(&l, Penumbra::Iterated, true, (0.0, 0.0), 0.01, 0);
        assert_eq!(flat, 0);
        // A grazing shell is capped.
        let steep = barrier(&l, Penumbra::Iterated, true, (5.0, 0.0), 0.01, 0);
        assert_eq!(steep, MAX_BARRIER);
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
