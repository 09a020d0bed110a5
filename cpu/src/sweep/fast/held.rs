//! The lanes of an 8-lane chunk that may read a held pixel from behind its surface
//! (`convshadow_common::plan::surface_hold`, "Who reads the held light"): gathered again one by
//! one through the per-pixel stage's `convolve_held` (through the tap rows the chunk's level
//! search found), whose bits are the plain gather's wherever no read is hidden. Tests:
//! `chunk/tests.rs` (the chunk against the per-pixel stage, with and without
//! `sweep.held_lit_side`) and the accuracy tests that render with it on both paths.

use convshadow_common::pixel::lane::{Layout, MAX_LANES};

use crate::sweep::kit::{MAX_LIGHTS, RowContext};
use crate::sweep::pixel::{LightIn, convolve_held_rows, reads_held};

/// The lanes of the chunk at `x0` not held in the previous slab and near a pixel that was
/// ([`reads_held`]), gathered again lane by lane
/// through `pixel::convolve_held_rows` into their lanes of `iin` (every light's channels) and
/// `depth_in` (every light's depth plane). `rows`: every light's tap rows by lane (light after
/// light) where the chunk's level search found them (the per-pixel stage's rows: no second
/// search).
#[cold]
pub(super) fn held_lanes<L: Layout>(
    row: &RowContext<'_>,
    x0: usize,
    iin: &mut [L],
    depth_in: &mut [L],
    rows: Option<&[L::U]>,
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
        // A lane held itself, or whose own reach holds no pixel held in the previous slab,
        // keeps the chunk's gather: the same bits (`pixel::reads_held`).
        if !reads_held(row, x0 + i) {
            continue;
        }
        let mut light = LightIn::ZERO;
        let mut lane_rows = [0u32; MAX_LIGHTS];
        for (r, lanes) in lane_rows.iter_mut().zip(&by_lane).take(lights) {
            *r = lanes[i];
        }
        let lane_rows = rows.is_some().then_some(&lane_rows[..lights]);
        convolve_held_rows(row, x0 + i, false, &mut light, lane_rows);
        let set = |v: &mut L, value: f32| {
            let mut lanes = [0.0f32; MAX_LANES];
            v.store(&mut lanes, 0);
            lanes[i] = value;
            *v = L::load(&lanes, 0);
        };
        for (v, &value) in iin.iter_mut().zip(&light.iin) {
            set(v, value);
        }
        for (v, &value) in depth_in.iter_mut().zip(&light.depth).take(lights) {
            set(v, value);
        }
    }
}
