//! The SIMD path's fast paths. Each computes what the per-pixel stage (`super::pixel`) computes,
//! bit for bit, only faster, and a test holds it to that:
//!
//! - `row`: the 8-lane row: chunk by chunk, quiet chunks skipped, neighbouring chunks' gathers
//!   paired, the row's tail through the per-pixel stage. Tests: `tests/contract/determinism.rs` and
//!   `tests/contract/simd_quiet.rs` (every example scene and kernel, against the scalar path).
//! - `chunk`: the 8-lane chunk stage, in instances that know the plan's shape at compile time,
//!   and the chunk whose depth planes alone move. Tests: `chunk/tests.rs`, every instance against
//!   the per-pixel stage on random inputs, lane by lane.
//! - `quiet`: which chunks' results are known exactly without running the stages (unoccluded,
//!   dark, a known gather), from per-row spans and per-chunk cursor summaries. Tests: its own
//!   (the spans' hulls and hits against their definitions), the row's check of every summary in
//!   unit tests, and the scalar-path comparisons above.
//! - `gather`: the lane gathers through one tap row for every lane (contiguous loads, row runs
//!   at the grid's edge, two chunks at once); `per_lane`: the gather where each lane has its own
//!   row (tap tables by column, AVX2 gathers, two lanes' pixels to a value); `levels`: the level
//!   search for 8 lanes. Tests: `gather/tests.rs`, against the reference gather
//!   (`crate::kernels::gather`) and one another.
//! - `held`: the lanes that may read a held pixel from behind its surface, gathered through the
//!   per-pixel stage (`sweep.held_lit_side`).
//!
//! Imports go one way: `row` → `chunk` → `quiet`, the gathers → the per-pixel stage and its kit.

mod chunk;
mod gather;
mod held;
mod levels;
mod per_lane;
mod quiet;
mod row;

use convshadow_common::pixel::levels::{level_at, pixel_level};
use convshadow_common::plan::RenderPlan;

pub(crate) use per_lane::TapColumns;
pub use quiet::ChunkCounts;
pub(crate) use quiet::{ChunkState, QuietRow, QuietSetup, RowSpans, chunks_per_row, window_hulls};
pub(crate) use row::sweep_row_simd;

/// What the SIMD path reads in a slab besides the slab's context (`SlabContext`).
pub(crate) struct SimdSlab<'a> {
    /// Every light's tap table by column, for the per-lane gathers.
    pub columns: &'a [TapColumns],
    /// Distance penumbra: per light, the level a dark pixel (light 0, depth 0) starts the next
    /// slab with, for the quiet path's dark chunks (empty with the iterated penumbra).
    pub dark_levels: Vec<u32>,
}

impl<'a> SimdSlab<'a> {
    /// Slab `slab` of `plan`, whose lights' tap tables by column are `columns`.
    pub(crate) fn new(plan: &RenderPlan, columns: &'a [TapColumns], slab: u32) -> Self {
        SimdSlab {
            columns,
            dark_levels: dark_levels(plan, slab),
        }
    }
}

/// [`SimdSlab::dark_levels`] of slab `slab`: what [`pixel_level`] gives a pixel whose channels
/// are all 0 (occluded = channels) and whose depth plane is 0, as step 5 computes it.
fn dark_levels(plan: &RenderPlan, slab: u32) -> Vec<u32> {
    if plan.depth_planes() == 0 {
        return Vec::new();
    }
    let ch = plan.channels as f32;
    plan.lights
        .iter()
        .map(|l| pixel_level::<f32>(&l.table, ch, 0.0, level_at(plan, slab + 1)))
        .collect()
}
