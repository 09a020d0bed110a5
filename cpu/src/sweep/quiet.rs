//! Quiet-chunk skipping on the 8-lane path: which 8-pixel chunks' results are known exactly
//! without running the stages, and the per-row and per-chunk summaries that tell.
//!
//! **Quiet chunks** are skipped without changing a bit of the result:
//! - *unoccluded*: every light value the chunk's kernels can read is exactly 1, no lane is inside
//!   a mesh and no lane crosses a fragment in this slab. Every phase's f32 weights sum to exactly 1
//!   in the gather's order (checked here, per table), so the gather gives 1, nothing is shaded, and
//!   the light out is `1 · 1 = 1`.
//! - *dark*: every lane is opaque (alpha exactly 1) and every value its kernels can read is exactly
//!   0: the gather gives 0, compositing adds `(1 − 1)·α·c = 0`, and the light out is 0. The cursors
//!   still advance, so a chunk that wakes up has the scalar path's state.
//! - *known light*: a chunk with a mesh whose kernels read only exact 1s (or only exact 0s) is
//!   shaded as usual, but its gather is replaced by that constant (the same bits, as above).
//!
//! What can be read is known from per-row spans of the previous buffer (where it is not exactly
//! 1, where it is not exactly 0) and the kernel tables' reach; these spans are this path's model
//! of "the region the scene and its shadows can reach", updated every slab.

use std::sync::atomic::{AtomicU64, Ordering};

use convshadow_common::lane::Lane;
use convshadow_common::plan::RenderPlan;
use wide::f32x8;

use super::kit::{Reach, SlabContext};
use crate::ldi::Ldi;

/// Lanes per chunk.
pub(crate) const LANES: usize = <f32x8 as Lane>::LANES;

/// Per row of a light buffer (all lights and channels): the x range `[lo, hi)` of values that
/// are not exactly 1, and of values that are not exactly 0 (empty when `lo >= hi`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RowSpans {
    pub not_one: (i32, i32),
    pub not_zero: (i32, i32),
}

impl RowSpans {
    /// No value recorded.
    pub(crate) const EMPTY: RowSpans = RowSpans {
        not_one: (i32::MAX, i32::MIN),
        not_zero: (i32::MAX, i32::MIN),
    };

    /// Records the values of pixels `x..x + n` (not-one / not-zero flags of the whole group).
    #[inline(always)]
    pub(crate) fn record(&mut self, x: usize, n: usize, not_one: bool, not_zero: bool) {
        let (lo, hi) = (x as i32, (x + n) as i32);
        if not_one {
            self.not_one = (self.not_one.0.min(lo), self.not_one.1.max(hi));
        }
        if not_zero {
            self.not_zero = (self.not_zero.0.min(lo), self.not_zero.1.max(hi));
        }
    }
}

/// Whether span `[lo, hi)` meets the closed range `a..=b`.
#[inline(always)]
fn meets(span: (i32, i32), a: i64, b: i64) -> bool {
    i64::from(span.0) <= b && i64::from(span.1) > a
}

/// A chunk's cursor summary, refreshed whenever its cursors move.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ChunkState {
    /// Smallest depth of a lane's next fragment (+∞ when no lane has one).
    pub event_depth: f32,
    /// Union of the lanes' inside masks.
    pub inside_any: u32,
    /// Every lane's alpha is exactly 1.
    pub opaque: bool,
}

impl ChunkState {
    /// The summary of lanes x0..x0+8 of row y.
    pub(crate) fn of(
        ldi: &Ldi,
        y: usize,
        x0: usize,
        next: &[u32],
        inside: &[u32],
        alpha: &[f32],
    ) -> Self {
        let w = ldi.width as usize;
        let mut s = ChunkState {
            event_depth: f32::INFINITY,
            inside_any: 0,
            opaque: true,
        };
        for x in x0..x0 + LANES {
            let end = ldi.offsets[y * w + x + 1];
            if next[x] < end {
                s.event_depth = s.event_depth.min(ldi.depth[next[x] as usize]);
            }
            s.inside_any |= inside[x];
            s.opaque &= alpha[x] == 1.0;
        }
        s
    }
}

/// What the quiet-chunk test needs besides the current rows: set up once per sweep.
pub(crate) struct QuietSetup {
    /// Every table's phases sum to exactly 1 in the gather's order (else no unoccluded skips).
    ones_exact: bool,
    /// Spans of the initial light buffer.
    pub initial_spans: Vec<RowSpans>,
    /// Chunk summaries at the start (`max(width / 8, 1)` per row).
    pub chunks: Vec<ChunkState>,
}

impl QuietSetup {
    /// Scans the tables and the initial buffer.
    pub(crate) fn new(plan: &RenderPlan, ldi: &Ldi, initial: &[f32]) -> QuietSetup {
        let ones_exact = plan.lights.iter().all(|l| {
            let t = &l.table;
            (0..t.rows()).all(|p| {
                let mut s = 0.0f32;
                for tap in t.phase(p) {
                    for w in tap.w {
                        s += w * 1.0;
                    }
                }
                s == 1.0
            })
        });
        let w = plan.grid_width as usize;
        let h = plan.grid_height as usize;
        let row_len = plan.light_row_len();
        let planes = row_len / w.max(1);
        let initial_spans = (0..h)
            .map(|y| {
                let mut s = RowSpans::EMPTY;
                for p in 0..planes {
                    for x in 0..w {
                        let v = initial[y * row_len + p * w + x];
                        // A depth plane is quiet at 0 in the light and in the dark.
                        if plan.is_depth_plane(p) {
                            s.record(x, 1, v != 0.0, v != 0.0);
                        } else {
                            s.record(x, 1, v != 1.0, v != 0.0);
                        }
                    }
                }
                s
            })
            .collect();
        let per_row = (w / LANES).max(1);
        let next = &ldi.offsets[..w * h];
        let zeros = vec![0u32; w];
        let alpha = vec![0.0f32; w];
        let mut chunks = vec![ChunkState::default(); per_row * h];
        for y in 0..h {
            for c in 0..w / LANES {
                chunks[y * per_row + c] =
                    ChunkState::of(ldi, y, c * LANES, &next[y * w..(y + 1) * w], &zeros, &alpha);
            }
        }
        QuietSetup {
            ones_exact,
            initial_spans,
            chunks,
        }
    }
}

/// One row's view of the quiet-chunk state.
pub(crate) struct QuietRow<'a> {
    pub setup: &'a QuietSetup,
    /// Spans of the previous buffer, every row.
    pub spans_prev: &'a [RowSpans],
    /// This row's spans in the buffer being written.
    pub span_out: &'a mut RowSpans,
    /// This row's chunk summaries.
    pub chunks: &'a mut [ChunkState],
}

/// What a chunk needs this slab.
pub(crate) enum ChunkWork {
    /// All five stages; the gather's result if it is known (every value read is 1, or 0).
    Full(Option<f32>),
    /// Unoccluded and empty: light out 1.
    Unoccluded,
    /// Opaque in the dark: advance the cursors, light out 0.
    Dark,
}

impl QuietRow<'_> {
    /// Classifies chunk `c` (pixels x0..x0+8) of row y.
    #[inline(always)]
    pub(crate) fn classify(
        &self,
        ctx: &SlabContext<'_>,
        reach: &Reach,
        y: usize,
        c: usize,
    ) -> ChunkWork {
        let state = self.chunks[c];
        let w = ctx.plan.grid_width as usize;
        let h = ctx.plan.grid_height as usize;
        let x0 = (c * LANES) as i64;
        let (a, b) = (
            x0 + i64::from(reach.x0),
            x0 + LANES as i64 - 1 + i64::from(reach.x1),
        );
        let rows = |f: &dyn Fn(&RowSpans) -> bool| {
            let lo = (y as i64 + i64::from(reach.y0)).max(0);
            let hi = (y as i64 + i64::from(reach.y1)).min(h as i64 - 1);
            (lo..=hi).any(|yy| f(&self.spans_prev[yy as usize]))
        };
        let all_ones = self.setup.ones_exact && !rows(&|s| meets(s.not_one, a, b));
        // Exactly the negation of the cursor's advance test `depth < back` (NaN never advances).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let no_crossing = !(state.event_depth < ctx.back);
        if all_ones && state.inside_any == 0 && no_crossing {
            return ChunkWork::Unoccluded;
        }
        let all_zeros = !all_ones
            && reach.interior(c * LANES, LANES, y, w, h)
            && !rows(&|s| meets(s.not_zero, a, b));
        if all_zeros && state.opaque {
            return ChunkWork::Dark;
        }
        // A mesh is here: shade it, but the gather's result may still be known.
        ChunkWork::Full(if all_ones {
            Some(1.0)
        } else if all_zeros {
            Some(0.0)
        } else {
            None
        })
    }
}

/// How the SIMD path processed its 8-pixel chunks, summed over slabs and rows.
#[derive(Debug, Default)]
pub struct ChunkCounts {
    /// Chunks that ran all five stages.
    pub full: AtomicU64,
    /// Chunks skipped as unoccluded and empty (light out exactly 1).
    pub unoccluded: AtomicU64,
    /// Chunks skipped as opaque in the dark (light out exactly 0, cursors advanced).
    pub dark: AtomicU64,
}

impl ChunkCounts {
    /// `[full, unoccluded, dark]` now.
    pub fn snapshot(&self) -> [u64; 3] {
        [
            self.full.load(Ordering::Relaxed),
            self.unoccluded.load(Ordering::Relaxed),
            self.dark.load(Ordering::Relaxed),
        ]
    }

    /// Adds one row's `[full, unoccluded, dark]` tally.
    pub(crate) fn add(&self, tally: [u64; 3]) {
        self.full.fetch_add(tally[0], Ordering::Relaxed);
        self.unoccluded.fetch_add(tally[1], Ordering::Relaxed);
        self.dark.fetch_add(tally[2], Ordering::Relaxed);
    }
}
