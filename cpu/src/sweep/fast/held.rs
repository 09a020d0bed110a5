//! The lanes of an 8-lane chunk that the per-pixel stage serves one by one: those whose gathers
//! may read a pixel otherwise than from the light buffer (`convshadow_common::plan::surface_hold`:
//! a held pixel read from behind its surface, a released pixel serving its light on its surface),
//! gathered again through the per-pixel stage's `convolve_held` (through the tap rows the chunk's
//! level search found), whose bits are the plain gather's wherever no corner is read otherwise;
//! the lanes with sub-pixel shadows; and the released lanes, which keep the light they gathered.
//! Tests: `chunk/tests.rs` (the chunk against the per-pixel stage, with and without
//! `sweep.held_lit_side`) and the accuracy tests that render with it on both paths.

use convshadow_common::pixel::lane::{Layout, MAX_LANES};
use convshadow_common::plan::OCCLUSION_EPS;

use crate::composite::Held;
use crate::parity::NO_CROSSING;
use crate::sweep::kit::{MAX_LIGHTS, RowContext, RowState};
use crate::sweep::pixel::{
    LightIn, Reader, convolve, convolve_held_rows, exact_light, held_near, keep_release,
    next_fragment, serves_any,
};

/// Every lane's fragment ahead of its cursor before this slab (`pixel::next_fragment`), read
/// after step 2: the first fragment a lane crossed, else the one its cursor still points at.
pub(super) fn lane_aheads<L: Layout>(
    row: &RowContext<'_>,
    state: &RowState<'_>,
    x0: usize,
    crossed: &[u32; MAX_LANES],
) -> [Option<u32>; MAX_LANES] {
    std::array::from_fn(|i| match crossed[i] {
        _ if i >= L::LANES => None,
        NO_CROSSING => next_fragment(row.ctx, state, (x0 + i, row.y)),
        first => Some(first),
    })
}

/// Lane `i` of `v` set to `value`.
fn set_lane<L: Layout>(v: &mut L, i: usize, value: f32) {
    let mut lanes = [0.0f32; MAX_LANES];
    v.store(&mut lanes, 0);
    lanes[i] = value;
    *v = L::load(&lanes, 0);
}

/// The lanes of the chunk at `x0` whose gathers may read a pixel otherwise ([`held_near`]),
/// gathered again lane by lane through `pixel::convolve_held_rows` into their lanes of `iin`
/// (every light's channels) and `depth_in` (every light's depth plane). `rows`: every light's
/// tap rows by lane (light after light) where the chunk's level search found them (the
/// per-pixel stage's rows: no second search); `aheads`: [`lane_aheads`].
#[cold]
pub(super) fn held_lanes<L: Layout>(
    row: &RowContext<'_>,
    x0: usize,
    (iin, depth_in): (&mut [L], &mut [L]),
    rows: Option<&[L::U]>,
    aheads: &[Option<u32>; MAX_LANES],
) {
    let ctx = row.ctx;
    let lights = ctx.plan.lights.len();
    let mut by_lane = [[0u32; MAX_LANES]; MAX_LIGHTS];
    if let Some(rows) = rows {
        for (lanes, &r) in by_lane.iter_mut().zip(rows) {
            L::u_store(r, lanes);
        }
    }
    for i in 0..L::LANES {
        // A lane whose own reach holds no such pixel, or that reads none otherwise (on no
        // surface, and not reading held light from its lit side only), keeps the chunk's
        // gather: the same bits.
        if !held_near(row, x0 + i, 1) {
            continue;
        }
        let reader = Reader::of(row, x0 + i, aheads[i]);
        if !reader.reads_otherwise(ctx) {
            continue;
        }
        let mut light = LightIn::ZERO;
        let mut lane_rows = [0u32; MAX_LIGHTS];
        for (r, lanes) in lane_rows.iter_mut().zip(&by_lane).take(lights) {
            *r = lanes[i];
        }
        // Where the level search found the lane's rows and held light is read from everywhere:
        // whether any corner they read is served at all.
        let lane_rows = &lane_rows[..lights];
        if rows.is_some() && !ctx.plan.held_lit_side && !serves_any(row, reader, lane_rows) {
            continue;
        }
        let lane_rows = rows.is_some().then_some(lane_rows);
        convolve_held_rows(row, x0 + i, false, &mut light, lane_rows, reader);
        for (v, &value) in iin.iter_mut().zip(&light.iin) {
            set_lane(v, i, value);
        }
        for (v, &value) in depth_in.iter_mut().zip(&light.depth).take(lights) {
            set_lane(v, i, value);
        }
    }
}

/// Sub-pixel shadows for the lanes at pixels x0.. with a part in `parts`: each one's light
/// gathered again by the per-pixel stage and read at its exact shift (`pixel::exact_light`),
/// into its lane of `shade_in` (every light's channels).
#[cold]
pub(super) fn exact_lanes<L: Layout>(
    row: &RowContext<'_>,
    x0: usize,
    (parts, aheads): (&[Option<f32>; MAX_LANES], &[Option<u32>; MAX_LANES]),
    shade_in: &mut [L],
) {
    let plan = row.ctx.plan;
    let ch = plan.channels as usize;
    for (i, part) in parts.iter().enumerate().take(L::LANES) {
        let Some(part) = *part else { continue };
        // A lane whose every light is unoccluded reads nothing again (`exact_shift`'s first
        // test, on the chunk's own gathered values: the per-pixel stage's bits).
        let occluded = (0..plan.lights.len()).any(|l| {
            let lit = (0..ch).fold(0.0f32, |a, c| a + shade_in[l * ch + c].lane(i));
            ch as f32 - lit > OCCLUSION_EPS
        });
        if !occluded {
            continue;
        }
        let mut light = LightIn::ZERO;
        convolve(row, x0 + i, false, &mut light, aheads[i]);
        let mut lane_in = light.iin;
        exact_light(row, x0 + i, &light, (part, aheads[i]), &mut lane_in);
        for (v, &value) in shade_in.iter_mut().zip(&lane_in) {
            set_lane(v, i, value);
        }
    }
}

/// The released lanes of the chunk at `x0` keep the light they gathered in this slab
/// (`pixel::keep_release`): lane by lane from `iin` and `depth_in`.
#[cold]
pub(super) fn keep_released_lanes<L: Layout>(
    row: &RowContext<'_>,
    x0: usize,
    held: &[Held; MAX_LANES],
    (iin, depth_in): (&[L], &[L]),
) {
    let lights = row.ctx.plan.lights.len();
    for (i, h) in held.iter().enumerate().take(L::LANES) {
        if !matches!(h, Held::Release { .. }) {
            continue;
        }
        let mut light = LightIn::ZERO;
        for (value, v) in light.iin.iter_mut().zip(iin) {
            *value = v.lane(i);
        }
        for (value, v) in light.depth.iter_mut().zip(depth_in).take(lights) {
            *value = v.lane(i);
        }
        keep_release(row, x0 + i, &light);
    }
}
