//! The lane paths of the sweep: one row of one slab, either one pixel at a time (the scalar
//! path, the 1-lane instance of the stage) or eight at a time (the SIMD path, with quiet-chunk
//! skipping; the row's last `width mod 8` pixels go through the 1-lane instance).

use std::ops::Range;

use wide::f32x8;

use super::kit::{
    MAX_LIGHT_CHANNELS, Previous, Reach, RowState, SlabContext, jitter_row_hash, light_row_hashes,
};
use super::quiet::{ChunkCounts, ChunkState, ChunkWork, LANES, QuietRow, RowSpans};
use super::stage::{ChunkFn, chunk_fn};
use crate::parity::{NO_CROSSING, advance};
use convshadow_common::plan::LIT_LEVEL;

/// Processes one row of one slab, one pixel at a time.
pub(crate) fn sweep_row_scalar(
    ctx: &SlabContext<'_>,
    reach: &Reach,
    y: usize,
    prev: &Previous<'_>,
    mut row: RowState<'_>,
) {
    let w = ctx.plan.grid_width as usize;
    let row_hashes = light_row_hashes(ctx, y);
    let jitter_row = jitter_row_hash(ctx, y);
    let mut spans = RowSpans::EMPTY;
    let hashes = (&row_hashes, jitter_row);
    sweep_pixels(ctx, reach, y, 0..w, prev, &mut row, hashes, &mut spans);
}

/// Runs the 1-lane stage on pixels `xs` of row y (`hashes`: the row's light and jitter
/// hashes), recording their outgoing light in `spans`.
#[allow(clippy::too_many_arguments)]
fn sweep_pixels(
    ctx: &SlabContext<'_>,
    reach: &Reach,
    y: usize,
    xs: Range<usize>,
    prev: &Previous<'_>,
    row: &mut RowState<'_>,
    hashes: (&[u32; MAX_LIGHT_CHANNELS], u32),
    spans: &mut RowSpans,
) {
    let plan = ctx.plan;
    let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
    let pixel: ChunkFn = chunk_fn::<f32>(plan.lights.len() * plan.channels as usize);
    let (row_hashes, jitter_row) = hashes;
    for x in xs {
        let interior = reach.interior(x, 1, y, w, h);
        let out = pixel(ctx, y, x, prev, row, row_hashes, jitter_row, interior, None);
        spans.record(x, 1, out.not_one, out.not_zero);
    }
}

/// Processes one row of one slab, 8 pixels at a time (quiet chunks skipped when `quiet` is
/// given); the last `width mod 8` pixels go through the 1-lane stage.
pub(crate) fn sweep_row_simd(
    ctx: &SlabContext<'_>,
    reach: &Reach,
    y: usize,
    prev: &Previous<'_>,
    mut row: RowState<'_>,
    mut quiet: Option<QuietRow<'_>>,
    counts: Option<&ChunkCounts>,
) {
    let plan = ctx.plan;
    let w = plan.grid_width as usize;
    let h = plan.grid_height as usize;
    let planes = plan.lights.len() * plan.channels as usize;
    let all_planes = plan.lights.len() * plan.planes_per_light();
    let distance = plan.depth_planes() > 0;
    let row_hashes = light_row_hashes(ctx, y);
    let jitter_row = jitter_row_hash(ctx, y);
    let mut spans = RowSpans::EMPTY;
    let mut tally = [0u64; 3];
    let full_chunks = w / LANES;
    let chunk: ChunkFn = chunk_fn::<f32x8>(planes);

    for c in 0..full_chunks {
        let x0 = c * LANES;
        let work = match &quiet {
            Some(q) => q.classify(ctx, reach, y, c),
            None => ChunkWork::Full(None),
        };
        let moved = match work {
            ChunkWork::Unoccluded => {
                tally[1] += 1;
                for p in 0..all_planes {
                    // Light 1; a depth plane's unoccluded value is 0.
                    let v = if plan.is_depth_plane(p) { 0.0 } else { 1.0 };
                    row.light[p * w + x0..][..LANES].fill(v);
                }
                if distance {
                    for l in 0..plan.lights.len() {
                        row.levels[l * w + x0..][..LANES].fill(LIT_LEVEL);
                    }
                }
                spans.record(x0, LANES, false, true);
                continue;
            }
            ChunkWork::Dark => {
                tally[2] += 1;
                let mut moved = false;
                for x in x0..x0 + LANES {
                    let end = ctx.ldi.offsets[y * w + x + 1];
                    let first =
                        advance(ctx.ldi, &mut row.next[x], end, &mut row.inside[x], ctx.back);
                    moved |= first != NO_CROSSING;
                }
                for p in 0..all_planes {
                    row.light[p * w + x0..][..LANES].fill(0.0);
                }
                for (l, level) in ctx.dark_levels.iter().enumerate() {
                    row.levels[l * w + x0..][..LANES].fill(*level);
                }
                if plan.preintegration {
                    // The cursors may have crossed surfaces: forget the kept front values (a
                    // kept value is only a saved evaluation, see `stage::preintegrated`).
                    row.pre[x0..x0 + LANES].fill(f32::NAN);
                }
                spans.record(x0, LANES, true, false);
                moved
            }
            ChunkWork::Full(known_light) => {
                tally[0] += 1;
                let interior = reach.interior(x0, LANES, y, w, h);
                let out = chunk(
                    ctx,
                    y,
                    x0,
                    prev,
                    &mut row,
                    &row_hashes,
                    jitter_row,
                    interior,
                    known_light,
                );
                spans.record(x0, LANES, out.not_one, out.not_zero);
                out.moved
            }
        };
        // A chunk whose cursors, masks and alphas did not change keeps its summary.
        if let (Some(q), true) = (&mut quiet, moved) {
            q.chunks[c] = ChunkState::of(ctx.ldi, y, x0, row.next, row.inside, row.alpha);
        }
    }

    let tail = full_chunks * LANES..w;
    let hashes = (&row_hashes, jitter_row);
    sweep_pixels(ctx, reach, y, tail, prev, &mut row, hashes, &mut spans);
    if let Some(q) = quiet {
        *q.span_out = spans;
    }
    if let Some(c) = counts {
        c.add(tally);
    }
}
