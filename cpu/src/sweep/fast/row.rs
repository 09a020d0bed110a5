//! The 8-lane row: one row of one slab, 8 pixels at a time. Per chunk, what it needs this slab
//! (`super::quiet`: skipped as unoccluded or dark, its depth planes alone, or all five stages
//! with its gather's result known or not); neighbouring chunks' gathers computed together where
//! every lane shares a tap row (`super::chunk::gather_pair`); the row's last `width mod 8`
//! pixels through the per-pixel stage (`crate::sweep::pixel`).

use std::ops::Range;

use wide::f32x8;

use super::SimdSlab;
use super::chunk::{
    Chunk, ChunkFn, chunk_fn, dark_depth_chunk, gather_pair, pairs_gathers, shape_of,
};
use super::quiet::{ChunkCounts, ChunkWork, Cursors, LANES, Moved, QuietRow, RowSpans, Values};
use crate::composite::Held;
use crate::parity::{NO_CROSSING, advance};
use crate::sweep::kit::{MAX_LIGHT_CHANNELS, RowContext, RowState, light_block};
use crate::sweep::pixel;
use convshadow_common::plan::LIT_LEVEL;

/// Processes one row of one slab, 8 pixels at a time (quiet chunks skipped when `quiet` is
/// given); the last `width mod 8` pixels go through the per-pixel stage, or are skipped as one
/// quiet chunk.
pub(crate) fn sweep_row_simd(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    mut state: RowState<'_>,
    mut quiet: Option<QuietRow<'_>>,
    counts: Option<&ChunkCounts>,
) {
    let (ctx, y) = (row.ctx, row.y);
    let (plan, reach) = (ctx.plan, &ctx.reach);
    let w = plan.grid_width as usize;
    let h = plan.grid_height as usize;
    let planes = plan.lights.len() * plan.channels as usize;
    let mut spans = RowSpans::EMPTY;
    let mut tally = [0u64; 3];
    // The SIMD path takes the instance that knows the plan's shape, where there is one.
    let sweep_chunk: ChunkFn = chunk_fn::<f32x8>(planes, shape_of(plan));
    let hits = quiet.as_ref().map(|q| q.hits(reach, w.div_ceil(LANES)));
    let pairs = pairs_gathers(plan);
    // The gathers of a chunk and its right neighbour, computed together when both need them
    // (`super::chunk::gather_pair`); `paired` names the chunk whose result waits in `pair[1]`.
    // Only where pairs are gathered (3 KiB to zero per row and slab otherwise).
    let mut pair = if pairs {
        Some([[0.0f32; 8 * MAX_LIGHT_CHANNELS]; 2])
    } else {
        None
    };
    let mut paired = usize::MAX;
    let full_chunks = w / LANES;

    for c in 0..w.div_ceil(LANES) {
        let x0 = c * LANES;
        let lanes = LANES.min(w - x0);
        // Unit tests hold every summary to its definition before it is used.
        #[cfg(test)]
        if let Some(q) = &quiet {
            let fresh = super::quiet::ChunkState::of(ctx.ldi, y, x0, lanes, Cursors::of(&state));
            assert_eq!(
                q.chunks[c], fresh,
                "slab {}, row {y}, chunk {c}: a stale summary",
                ctx.slab
            );
        }
        // Near a held pixel a lane's gather may read it from behind its surface
        // (`pixel::convolve_held`): no quiet shortcut, which would assume the values it reads.
        let held = pixel::held_near(row, x0, lanes);
        let work = match (&quiet, &hits) {
            _ if held => ChunkWork::Full(None),
            (Some(q), Some(hits)) => q.classify(ctx, y, c, lanes, hits),
            _ => ChunkWork::Full(None),
        };
        // This slab's buffer's bit in the chunk's fill bits (see `QuietRow::filled`).
        let buffer_bit = 1u8 << (ctx.slab & 1);
        let already_filled = match &mut quiet {
            Some(q) => {
                let was = q.filled[c] & buffer_bit != 0;
                let now = matches!(work, ChunkWork::Unoccluded);
                q.filled[c] = if now {
                    q.filled[c] | buffer_bit
                } else {
                    q.filled[c] & !buffer_bit
                };
                was
            }
            None => false,
        };
        // What of the chunk's cursor summary its stages may have changed.
        let moved = match work {
            ChunkWork::Unoccluded => {
                tally[1] += 1;
                if !already_filled {
                    fill_quiet(simd, row, &mut state, x0..x0 + lanes, false);
                }
                spans.record(x0, lanes, Values::UNOCCLUDED);
                continue;
            }
            ChunkWork::Dark => {
                tally[2] += 1;
                let moved = advance_dark(row, &mut state, x0..x0 + lanes);
                fill_quiet(simd, row, &mut state, x0..x0 + lanes, true);
                spans.record(x0, lanes, Values::DARK);
                Moved::of(moved, false)
            }
            ChunkWork::DarkDepth if lanes == LANES => {
                tally[2] += 1;
                let moved = advance_dark(row, &mut state, x0..x0 + LANES);
                let interior = reach.interior(x0, LANES, y, w, h);
                let not_zero = dark_depth_chunk(simd, row, &mut state, x0, interior);
                let values = Values {
                    not_zero,
                    ..Values::DARK
                };
                spans.record(x0, LANES, values);
                Moved::of(moved, false)
            }
            ChunkWork::Full(known_light) if lanes == LANES => {
                tally[0] += 1;
                let interior = reach.interior(x0, LANES, y, w, h);
                let gathered = match &mut pair {
                    Some(pair) if paired == c => Some(&pair[1][..]),
                    Some(pair) if known_light.is_none() && interior && c + 1 < full_chunks => {
                        // The neighbour's class does not depend on this chunk's work: ask now.
                        let next = match (&quiet, &hits) {
                            (Some(q), Some(hits)) => q.classify(ctx, y, c + 1, LANES, hits),
                            _ => ChunkWork::Full(None),
                        };
                        let next_interior = reach.interior(x0 + LANES, LANES, y, w, h);
                        if matches!(next, ChunkWork::Full(None)) && next_interior {
                            gather_pair(simd, row, x0, pair);
                            paired = c + 1;
                            Some(&pair[0][..])
                        } else {
                            None
                        }
                    }
                    _ => None,
                };
                let chunk = Chunk {
                    x0,
                    interior,
                    known_light,
                    gathered,
                    held,
                    // The chunk's cursor summary, current: refreshed whenever its cursors move.
                    summary: quiet.as_ref().map(|q| q.chunks[c]),
                };
                let out = sweep_chunk(simd, row, &mut state, chunk);
                spans.record(x0, LANES, out.values());
                Moved::of(out.crossed, out.shaded)
            }
            // The row's tail: the per-pixel stage, pixel by pixel.
            ChunkWork::Full(_) | ChunkWork::DarkDepth => {
                tally[0] += 1;
                sweep_tail(row, x0..w, &mut state, &mut spans)
            }
        };
        if let Some(q) = &mut quiet {
            let cursors = Cursors::of(&state);
            q.chunks[c].refresh(moved, ctx.ldi, y, (x0, lanes), cursors);
        }
    }

    if let Some(q) = quiet {
        *q.span_out = spans;
    }
    if let Some(c) = counts {
        c.add(tally);
    }
}

/// The row's tail (pixels `xs`, fewer than a chunk): the per-pixel stage, pixel by pixel, each
/// pixel's outgoing light recorded in `spans`. Returns what of the tail's summary the stage
/// changed: a pixel's cursor and inside mask move only together, its alpha alone where it was
/// shaded without crossing a fragment. (Not inlined: inlined into the row's loop, the per-pixel
/// stage cost the 8-lane row 0.4 % more instructions than the call.)
#[inline(never)]
fn sweep_tail(
    row: &RowContext<'_>,
    xs: Range<usize>,
    state: &mut RowState<'_>,
    spans: &mut RowSpans,
) -> Moved {
    let plan = row.ctx.plan;
    let (w, h) = (plan.grid_width as usize, plan.grid_height as usize);
    let (ch, planes, lights) = (
        plan.channels as usize,
        plan.planes_per_light(),
        plan.lights.len(),
    );
    let (mut crossed, mut shaded) = (false, false);
    for x in xs {
        let (next, alpha) = (state.next[x], state.alpha[x]);
        let hold = state.hold.get(x).copied();
        let inside = row.ctx.reach.interior(x, 1, row.y, w, h);
        pixel::sweep_pixel(row, state, x, inside);
        // What it wrote: each light's planes side by side (light l's pixel x at `(l·w + x)·planes`).
        let written = (0..lights)
            .map(|l| Values::of_planes(&state.light[(l * w + x) * planes..][..planes], ch))
            .fold(Values::NONE, Values::or);
        spans.record(x, 1, written);
        // A hold that started or ended moves the summary like a crossing.
        crossed |= state.next[x] != next || state.hold.get(x).copied() != hold;
        shaded |= state.alpha[x].to_bits() != alpha.to_bits();
    }
    Moved::of(crossed, shaded)
}

/// A quiet chunk's outgoing light for pixels `xs`: 1 (unoccluded) or 0 (dark) in every light
/// plane, 0 in every depth plane, and the levels the stage would have given (see [`ChunkWork`]).
fn fill_quiet(
    simd: &SimdSlab<'_>,
    row: &RowContext<'_>,
    state: &mut RowState<'_>,
    xs: Range<usize>,
    dark: bool,
) {
    let plan = row.ctx.plan;
    let w = plan.grid_width as usize;
    let planes = plan.planes_per_light();
    let (x0, lanes) = (xs.start, xs.len());
    // One pixel's planes: its channels at 1 (0 when dark), its depth plane at 0.
    let pixel: [f32; 4] = std::array::from_fn(|k| {
        if dark || plan.is_depth_plane(k) {
            0.0
        } else {
            1.0
        }
    });
    // Pixel-interleaved (see `LightPlanes`): each light's pixels x0.. are one run.
    for l in 0..plan.lights.len() {
        let run = &mut state.light[light_block(plan, l) + x0 * planes..][..lanes * planes];
        match planes {
            1 => fill_pixels::<1>(run, pixel),
            2 => fill_pixels::<2>(run, pixel),
            3 => fill_pixels::<3>(run, pixel),
            4 => fill_pixels::<4>(run, pixel),
            n => panic!("a light has 1 or 3 channels and at most one depth plane, not {n} planes"),
        }
    }
    if plan.depth_planes() > 0 {
        for l in 0..plan.lights.len() {
            let level = if dark { simd.dark_levels[l] } else { LIT_LEVEL };
            state.levels[l * w + x0..][..lanes].fill(level);
        }
    }
}

/// `run`'s pixels of `P` planes each set to `pixel`'s first `P` values (fixed-length copies: a
/// plane test per value cost two integer divisions).
#[inline(always)]
fn fill_pixels<const P: usize>(run: &mut [f32], pixel: [f32; 4]) {
    let pixel: [f32; P] = std::array::from_fn(|k| pixel[k]);
    for px in run.chunks_exact_mut(P) {
        px.copy_from_slice(&pixel);
    }
}

/// A dark chunk's cursors (pixels `xs`) advanced through this slab; returns whether one crossed
/// a fragment.
fn advance_dark(row: &RowContext<'_>, state: &mut RowState<'_>, xs: Range<usize>) -> bool {
    let ctx = row.ctx;
    let w = ctx.plan.grid_width as usize;
    let mut moved = false;
    for x in xs.clone() {
        let end = ctx.ldi.offsets[row.y * w + x + 1];
        let before = state.inside[x];
        let first = advance(
            ctx.ldi,
            &mut state.next[x],
            end,
            &mut state.inside[x],
            ctx.back,
        );
        moved |= first != NO_CROSSING;
        // The surface hold moves as in the full stage (the light it passes or removes is 0).
        moved |= matches!(
            pixel::hold(ctx, state, (x, row.y), (first, before)),
            Held::Release { .. }
        );
    }
    if ctx.plan.preintegration {
        // The cursors may have crossed surfaces: forget the kept front values (a kept value is
        // only a saved evaluation, see `super::chunk::preintegrated`).
        state.pre[xs].fill(f32::NAN);
    }
    moved
}
