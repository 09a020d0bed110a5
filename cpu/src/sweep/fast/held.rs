//! The lanes of an 8-lane chunk that may read a held pixel from behind its surface
//! (`convshadow_common::plan::surface_hold`, "Who reads the held light"): gathered again one by
//! one through the per-pixel stage's `convolve_held`, whose bits are the plain gather's wherever
//! no read is hidden. Tests: `chunk/tests.rs` (the chunk against the per-pixel stage) and the
//! accuracy tests that render with `sweep.held_lit_side` on both paths.

use convshadow_common::pixel::lane::{Layout, MAX_LANES};

use crate::sweep::kit::RowContext;
use crate::sweep::pixel::{LightIn, convolve_held, reads_held};

/// The lanes of the chunk at `x0` not held in the previous slab and near a pixel that was
/// ([`reads_held`]), gathered again lane by lane
/// through `pixel::convolve_held` into their lanes of `iin` (every light's channels) and
/// `depth_in` (every light's depth plane).
#[cold]
pub(super) fn held_lanes<L: Layout>(
    row: &RowContext<'_>,
    x0: usize,
    iin: &mut [L],
    depth_in: &mut [L],
) {
    let ctx = row.ctx;
    let lights = ctx.plan.lights.len();
    for i in 0..L::LANES {
        // A lane held itself, or whose own reach holds no pixel held in the previous slab,
        // keeps the chunk's gather: the same bits (`pixel::reads_held`).
        if !reads_held(row, x0 + i) {
            continue;
        }
        let mut light = LightIn::ZERO;
        convolve_held(row, x0 + i, false, &mut light);
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
