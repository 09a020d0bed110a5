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
//! - *dark with depth* (distance penumbra): as *dark*, but the depth planes read are not all 0
//!   (an occluder's depth stays in the dark behind it): the light planes are 0 as above, and only
//!   the depth planes and levels are computed (`super::chunk::dark_depth_chunk`); counted as dark.
//! - *known light*: a chunk with a mesh whose kernels read only exact 1s (or only exact 0s) is
//!   shaded as usual, but its gather is replaced by that constant (the same bits, as above).
//!
//! What can be read is known from per-row spans of the previous buffer (where it is not exactly
//! 1, where it is not exactly 0) and the kernel tables' reach; these spans are this path's model
//! of "the region the scene and its shadows can reach", updated every slab.

use std::sync::atomic::{AtomicU64, Ordering};

use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::RenderPlan;
use wide::f32x8;

use crate::composite::release_slab;
use crate::ldi::Ldi;
use crate::sweep::kit::{Reach, RowState, SlabContext};

/// Lanes per chunk.
pub(crate) const LANES: usize = <f32x8 as Lane>::LANES;

/// Per row of a light buffer (all lights and channels): the x range `[lo, hi)` of values that
/// are not exactly 1, and of values that are not exactly 0 (empty when `lo >= hi`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RowSpans {
    pub not_one: (i32, i32),
    pub not_zero: (i32, i32),
    /// Values of the light planes alone (not the depth planes) that are not exactly 0.
    pub light_not_zero: (i32, i32),
}

impl RowSpans {
    /// No value recorded.
    pub(crate) const EMPTY: RowSpans = RowSpans {
        not_one: (i32::MAX, i32::MIN),
        not_zero: (i32::MAX, i32::MIN),
        light_not_zero: (i32::MAX, i32::MIN),
    };

    /// Records the values of pixels `x..x + n` (the whole group's flags).
    #[inline(always)]
    pub(crate) fn record(&mut self, x: usize, n: usize, values: Values) {
        let (lo, hi) = (x as i32, (x + n) as i32);
        let grow = |span: &mut (i32, i32), flag: bool| {
            if flag {
                *span = join(*span, (lo, hi));
            }
        };
        grow(&mut self.not_one, values.not_one);
        grow(&mut self.not_zero, values.not_zero);
        grow(&mut self.light_not_zero, values.light_not_zero);
    }
}

impl RowSpans {
    /// Kind by kind, the smallest span holding both `self` and `other` (an empty span adds
    /// nothing: its `lo` is `i32::MAX` and its `hi` `i32::MIN`).
    fn hull(self, other: RowSpans) -> RowSpans {
        RowSpans {
            not_one: join(self.not_one, other.not_one),
            not_zero: join(self.not_zero, other.not_zero),
            light_not_zero: join(self.light_not_zero, other.light_not_zero),
        }
    }
}

/// The smallest span `(lo, hi)` holding spans `a` and `b`.
#[inline(always)]
fn join(a: (i32, i32), b: (i32, i32)) -> (i32, i32) {
    (a.0.min(b.0), a.1.max(b.1))
}

/// Per row y, the [`RowSpans::hull`] of `spans[y + y0 ..= y + y1]` (rows outside the buffer add
/// nothing; `y0 ≤ y1`): one span per kind holding every value that the rows within a kernel's
/// vertical reach hold, so that a row's quiet test reads one span per kind, not one per row in
/// reach. In O(rows) for any reach (van Herk / Gil-Werman: hulls from the start and to the end
/// of blocks of `y1 − y0 + 1` rows; a window is the end of one block and the start of the next).
/// `scratch` keeps its buffers from one slab to the next.
pub(crate) fn window_hulls(
    spans: &[RowSpans],
    y0: i32,
    y1: i32,
    out: &mut Vec<RowSpans>,
    scratch: &mut [Vec<RowSpans>; 2],
) {
    // Offsets beyond ±h rows read only rows outside the buffer: clamped there, every window keeps
    // its rows and the scratch stays within 3·h rows whatever the kernels' reach.
    let rows = i32::try_from(spans.len()).unwrap_or(i32::MAX);
    let (y0, y1) = (y0.clamp(-rows, rows), y1.clamp(-rows, rows));
    let (h, width) = (spans.len(), (i64::from(y1) - i64::from(y0) + 1) as usize);
    // Row k of the padded sequence is buffer row k + y0 (EMPTY outside the buffer); window y is
    // padded rows y ..= y + width − 1.
    let padded = h + width - 1;
    let row = |k: usize| {
        let r = k as i64 + i64::from(y0);
        if (0..h as i64).contains(&r) {
            spans[r as usize]
        } else {
            RowSpans::EMPTY
        }
    };
    let [from_start, to_end] = scratch;
    from_start.clear();
    to_end.clear();
    from_start.extend((0..padded).map(row));
    to_end.extend((0..padded).map(row));
    for k in 1..padded {
        if k % width != 0 {
            from_start[k] = from_start[k - 1].hull(from_start[k]);
        }
    }
    for k in (0..padded.saturating_sub(1)).rev() {
        if (k + 1) % width != 0 {
            to_end[k] = to_end[k].hull(to_end[k + 1]);
        }
    }
    out.clear();
    out.extend((0..h).map(|y| to_end[y].hull(from_start[y + width - 1])));
}

/// What a group of pixels wrote to the light buffer, as [`RowSpans::record`] takes it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Values {
    /// Some light value is not exactly 1, or some depth value not exactly 0.
    pub not_one: bool,
    /// Some light or depth value is not exactly 0.
    pub not_zero: bool,
    /// Some light value (depth planes aside) is not exactly 0.
    pub light_not_zero: bool,
}

impl Values {
    /// Nothing written.
    pub(crate) const NONE: Values = Values {
        not_one: false,
        not_zero: false,
        light_not_zero: false,
    };
    /// Unoccluded: light 1, depth 0.
    pub(crate) const UNOCCLUDED: Values = Values {
        not_one: false,
        not_zero: true,
        light_not_zero: true,
    };
    /// Dark: light 0, depth 0.
    pub(crate) const DARK: Values = Values {
        not_one: true,
        not_zero: false,
        light_not_zero: false,
    };

    /// What a pixel wrote to one light's planes `pixel` (its `channels` light planes, quiet at
    /// exactly 1 or exactly 0, then its depth plane if any, quiet at exactly 0).
    #[inline(always)]
    pub(crate) fn of_planes(pixel: &[f32], channels: usize) -> Values {
        let mut v = Values::NONE;
        for (p, &value) in pixel.iter().enumerate() {
            let not_zero = value != 0.0;
            v.not_zero |= not_zero;
            if p < channels {
                v.not_one |= value != 1.0;
                v.light_not_zero |= not_zero;
            } else {
                v.not_one |= not_zero;
            }
        }
        v
    }

    /// Flag by flag, whether `self` or `other` has it.
    #[inline(always)]
    pub(crate) fn or(self, other: Values) -> Values {
        Values {
            not_one: self.not_one | other.not_one,
            not_zero: self.not_zero | other.not_zero,
            light_not_zero: self.light_not_zero | other.light_not_zero,
        }
    }
}

/// Whether span `[lo, hi)` meets the closed range `a..=b` (the per-chunk test [`RowHits`]
/// answers for a whole row at once).
#[cfg(test)]
fn meets(span: (i32, i32), a: i64, b: i64) -> bool {
    i64::from(span.0) <= b && i64::from(span.1) > a
}

/// What a chunk's stages may have changed of its [`ChunkState`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Moved {
    /// Nothing: no lane crossed a fragment or was shaded.
    Nothing,
    /// Alphas only: some lane was shaded, none crossed a fragment.
    Alphas,
    /// Cursors and inside masks (and alphas): some lane crossed a fragment.
    Cursors,
}

impl Moved {
    /// From whether some lane crossed a fragment and whether some lane was shaded.
    pub(crate) fn of(crossed: bool, shaded: bool) -> Moved {
        match (crossed, shaded) {
            (true, _) => Moved::Cursors,
            (false, true) => Moved::Alphas,
            (false, false) => Moved::Nothing,
        }
    }
}

/// A chunk's cursor summary, refreshed whenever its cursors move (only its `opaque` flag when
/// its lanes were shaded without crossing a fragment).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ChunkState {
    /// Smallest depth of a lane's next fragment (+∞ when no lane has one).
    pub event_depth: f32,
    /// Union of the lanes' inside masks.
    pub inside_any: u32,
    /// Every lane's alpha is exactly 1.
    pub opaque: bool,
    /// The first slab in which a lane's surface hold releases (`u32::MAX`: none holds): the
    /// chunk is not skipped as unoccluded from there while the hold lasts (its barrier), where a
    /// lane's light drops to 0.
    pub release: u32,
}

/// What of a row's per-pixel state a chunk summary reads: the cursors, inside masks and alphas.
#[derive(Clone, Copy)]
pub(crate) struct Cursors<'a> {
    pub next: &'a [u32],
    pub inside: &'a [u32],
    pub alpha: &'a [f32],
    /// Surface holds (shorter than the row when the plan has none).
    pub hold: &'a [u32],
}

impl<'a> Cursors<'a> {
    /// The cursors, inside masks and alphas of `row`.
    pub(crate) fn of(row: &'a RowState<'_>) -> Self {
        Cursors {
            next: row.next,
            inside: row.inside,
            alpha: row.alpha,
            hold: row.hold,
        }
    }
}

impl ChunkState {
    /// The summary of pixels x0..x0 + lanes of row y (8 lanes, fewer for a row's tail), whose
    /// state is `row`.
    pub(crate) fn of(ldi: &Ldi, y: usize, x0: usize, lanes: usize, row: Cursors<'_>) -> Self {
        let Cursors {
            next,
            inside,
            alpha,
            hold,
        } = row;
        let w = ldi.width as usize;
        let mut s = ChunkState {
            event_depth: f32::INFINITY,
            inside_any: 0,
            opaque: true,
            release: u32::MAX,
        };
        if hold.len() == w {
            for &h in &hold[x0..x0 + lanes] {
                if h != 0 {
                    s.release = s.release.min(release_slab(h));
                }
            }
        }
        for x in x0..x0 + lanes {
            let end = ldi.offsets[y * w + x + 1];
            if next[x] < end {
                s.event_depth = s.event_depth.min(ldi.depth[next[x] as usize]);
            }
            s.inside_any |= inside[x];
        }
        s.opaque = ChunkState::all_opaque(&alpha[x0..x0 + lanes]);
        s
    }

    /// Whether every alpha of `alpha` (a chunk's) is exactly 1, as [`ChunkState::opaque`] says.
    #[inline(always)]
    fn all_opaque(alpha: &[f32]) -> bool {
        alpha.iter().fold(true, |all, &a| all & (a == 1.0))
    }

    /// The summary of pixels x0..x0 + lanes of row y after the chunk's stages changed `moved`
    /// of them: recomputed when a cursor moved, its `opaque` flag alone when only alphas may
    /// have changed (no cursor moved, so the fragment depth and inside masks stay), else kept.
    #[inline(always)]
    pub(crate) fn refresh(
        &mut self,
        moved: Moved,
        ldi: &Ldi,
        y: usize,
        (x0, lanes): (usize, usize),
        row: Cursors<'_>,
    ) {
        match moved {
            Moved::Cursors => *self = ChunkState::of(ldi, y, x0, lanes, row),
            Moved::Alphas => self.opaque = ChunkState::all_opaque(&row.alpha[x0..x0 + lanes]),
            Moved::Nothing => {}
        }
    }

    /// Whether no lane's cursor crosses a fragment before `back_face`: exactly the negation of
    /// the cursor's advance test `depth < back_face` at the nearest next fragment (NaN never
    /// advances).
    #[inline(always)]
    pub(crate) fn crosses_nothing(&self, back_face: f32) -> bool {
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let none = !(self.event_depth < back_face);
        none
    }
}

/// Chunk summaries per row: one per 8 pixels, the last for the row's `width mod 8` tail pixels
/// if any (at least one, so that every row has a slice).
pub(crate) fn chunks_per_row(width: usize) -> usize {
    width.div_ceil(LANES).max(1)
}

/// What the quiet-chunk test needs besides the current rows: set up once per sweep.
pub(crate) struct QuietSetup {
    /// Every table's phases sum to exactly 1 in the gather's order (else no unoccluded skips).
    ones_exact: bool,
    /// The plan has depth planes (distance penumbra): dark chunks with depth may be skipped in
    /// part ([`ChunkWork::DarkDepth`]).
    depth_planes: bool,
    /// Spans of the initial light buffer.
    pub initial_spans: Vec<RowSpans>,
    /// Chunk summaries at the start ([`chunks_per_row`] per row: the last one is the row's tail
    /// of `width mod 8` pixels, if any).
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
                        let values = if plan.is_depth_plane(p) {
                            Values {
                                not_one: v != 0.0,
                                not_zero: v != 0.0,
                                light_not_zero: false,
                            }
                        } else {
                            Values {
                                not_one: v != 1.0,
                                not_zero: v != 0.0,
                                light_not_zero: v != 0.0,
                            }
                        };
                        s.record(x, 1, values);
                    }
                }
                s
            })
            .collect();
        let per_row = chunks_per_row(w);
        let next = &ldi.offsets[..w * h];
        let zeros = vec![0u32; w];
        let alpha = vec![0.0f32; w];
        let mut chunks = vec![ChunkState::default(); per_row * h];
        for y in 0..h {
            for c in 0..w.div_ceil(LANES) {
                let (x0, next) = (c * LANES, &next[y * w..(y + 1) * w]);
                let lanes = LANES.min(w - x0);
                let row = Cursors {
                    next,
                    inside: &zeros,
                    alpha: &alpha,
                    hold: &[],
                };
                chunks[y * per_row + c] = ChunkState::of(ldi, y, x0, lanes, row);
            }
        }
        QuietSetup {
            ones_exact,
            depth_planes: plan.depth_planes() > 0,
            initial_spans,
            chunks,
        }
    }
}

/// One row's view of the quiet-chunk state.
pub(crate) struct QuietRow<'a> {
    pub setup: &'a QuietSetup,
    /// The hull of the previous buffer's spans in the rows within reach of this row
    /// ([`window_hulls`]).
    pub window: &'a RowSpans,
    /// This row's spans in the buffer being written.
    pub span_out: &'a mut RowSpans,
    /// This row's chunk summaries.
    pub chunks: &'a mut [ChunkState],
    /// This row's chunks' fill bits: bit `slab mod 2` set when the buffer this slab writes
    /// already holds the chunk's unoccluded fill (light 1, depth 0, no level), written two slabs
    /// ago and not overwritten since (each buffer is written only by every other slab). An
    /// unoccluded chunk then skips its stores: the values are the same bits.
    pub filled: &'a mut [u8],
}

/// What a chunk needs this slab.
pub(crate) enum ChunkWork {
    /// All five stages; the gather's result if it is known (every value read is 1, or 0).
    Full(Option<f32>),
    /// Unoccluded and empty: light out 1.
    Unoccluded,
    /// Opaque in the dark: advance the cursors, light out 0.
    Dark,
    /// Opaque, every light value read exactly 0 but some depth value not (distance penumbra):
    /// advance the cursors, light out 0, compute only the depth planes and levels
    /// (`super::chunk::dark_depth_chunk`).
    DarkDepth,
}

/// For every chunk of one row, whether some row within the kernels' vertical reach has values
/// that are not exactly 1 (not exactly 0) within the chunk's horizontal reach: what
/// [`QuietRow::classify`] asks of the previous buffer's spans, answered from the row's
/// [`window_hulls`] span per kind (a hull may hold chunks no row's span meets: then a chunk is
/// computed that could have been skipped, never the reverse).
pub(crate) struct RowHits {
    /// Per kind (0 not one, 1 not zero, 2 light not zero: the order of [`RowHits::kinds`]), the
    /// chunks `first..=last` whose reach meets the window's span (empty when first > last).
    ranges: [(i64, i64); 3],
}

impl RowHits {
    /// A row's spans in the order of [`RowHits::ranges`] (light not zero only with depth planes).
    fn kinds(spans: &RowSpans, depth_planes: bool) -> [(i32, i32); 3] {
        let light = if depth_planes {
            spans.light_not_zero
        } else {
            RowSpans::EMPTY.light_not_zero
        };
        [spans.not_one, spans.not_zero, light]
    }

    /// The hits of a row whose rows in reach hold `window` (its [`window_hulls`] entry), for a row
    /// of `chunks` chunks.
    fn of(window: &RowSpans, depth_planes: bool, reach: &Reach, chunks: usize) -> RowHits {
        let ranges = Self::kinds(window, depth_planes).map(|span| {
            let (first, last) = Self::chunk_range(span, reach);
            (first.max(0), last.min(chunks as i64 - 1))
        });
        RowHits { ranges }
    }

    /// Whether chunk c's reach meets kind k's span.
    fn hit(&self, k: usize, c: usize) -> bool {
        let (first, last) = self.ranges[k];
        (first..=last).contains(&(c as i64))
    }

    /// Chunk c's bit for spans not exactly 1.
    fn not_one(&self, c: usize) -> bool {
        self.hit(0, c)
    }

    /// Chunk c's bit for spans not exactly 0.
    fn not_zero(&self, c: usize) -> bool {
        self.hit(1, c)
    }

    /// Chunk c's bit for light (not depth) spans not exactly 0.
    fn light_not_zero(&self, c: usize) -> bool {
        self.hit(2, c)
    }

    /// The chunks `c` (pixels `8c..8c + 8`) whose reach `[8c + x0, 8c + 7 + x1]` meets `span`:
    /// `lo ≤ 8c + 7 + x1` and `hi > 8c + x0`, as an inclusive chunk range (empty when first > last).
    fn chunk_range(span: (i32, i32), reach: &Reach) -> (i64, i64) {
        let lanes = LANES as i64;
        let (lo, hi) = (i64::from(span.0), i64::from(span.1));
        // ⌈(lo − 7 − x1) / 8⌉ and ⌊(hi − x0 − 1) / 8⌋.
        let first = -((lanes - 1 + i64::from(reach.x1) - lo).div_euclid(lanes));
        let last = (hi - i64::from(reach.x0) - 1).div_euclid(lanes);
        (first, last)
    }
}

impl QuietRow<'_> {
    /// Which of this row's `chunks` chunks can read a value that is not exactly 1 (not exactly 0)
    /// in the previous buffer.
    pub(crate) fn hits(&self, reach: &Reach, chunks: usize) -> RowHits {
        RowHits::of(self.window, self.setup.depth_planes, reach, chunks)
    }

    /// Classifies chunk `c` (pixels x0..x0 + lanes, x0 = 8c; fewer than 8 lanes for the row's
    /// tail) of row y (`hits`: the row's [`QuietRow::hits`], which asks of a tail the reach of 8
    /// pixels: more than it reads, so it may work where it could skip, never the reverse).
    #[inline(always)]
    pub(crate) fn classify(
        &self,
        ctx: &SlabContext<'_>,
        y: usize,
        c: usize,
        lanes: usize,
        hits: &RowHits,
    ) -> ChunkWork {
        let state = self.chunks[c];
        let reach = &ctx.reach;
        let w = ctx.plan.grid_width as usize;
        let h = ctx.plan.grid_height as usize;
        let all_ones = self.setup.ones_exact && !hits.not_one(c);
        // From a lane's release through its barrier (its state then ends) the light drops to 0.
        let releases = state.release <= ctx.slab;
        if all_ones && state.inside_any == 0 && state.crosses_nothing(ctx.back) && !releases {
            return ChunkWork::Unoccluded;
        }
        let interior = reach.interior(c * LANES, lanes, y, w, h);
        let all_zeros = !all_ones && interior && !hits.not_zero(c);
        // A released lane owns its depth plane (`owned_depth`), which the dark paths leave out.
        if all_zeros && state.opaque && !releases {
            return ChunkWork::Dark;
        }
        let dark_light =
            self.setup.depth_planes && !all_ones && interior && !hits.light_not_zero(c);
        if dark_light && state.opaque && !releases {
            return ChunkWork::DarkDepth;
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

#[cfg(test)]
mod tests {
    use super::*;
    use convshadow_testkit::TestRng;

    /// A random span of one kind: empty one time in five.
    fn random_span(rng: &mut TestRng) -> (i32, i32) {
        match rng.below(5) {
            0 => RowSpans::EMPTY.not_one,
            _ => {
                let lo = rng.below(120) as i32 - 10;
                (lo, lo + 1 + rng.below(40) as i32)
            }
        }
    }

    fn random_spans(rng: &mut TestRng) -> RowSpans {
        RowSpans {
            not_one: random_span(rng),
            not_zero: random_span(rng),
            light_not_zero: random_span(rng),
        }
    }

    fn kinds(s: &RowSpans) -> [(i32, i32); 3] {
        [s.not_one, s.not_zero, s.light_not_zero]
    }

    /// Chunk c's reach `[8c + x0, 8c + 7 + x1]`.
    fn chunk_reach(c: usize, reach: &Reach) -> (i64, i64) {
        (
            (c * LANES) as i64 + i64::from(reach.x0),
            (c * LANES + LANES - 1) as i64 + i64::from(reach.x1),
        )
    }

    #[test]
    fn window_hulls_are_the_hulls_of_the_rows_in_reach() {
        // Against the direct fold over the rows `y + y0 ..= y + y1` inside the buffer.
        let mut rng = TestRng::new(7);
        let mut scratch = [Vec::new(), Vec::new()];
        let mut out = Vec::new();
        for _ in 0..500 {
            let h = 1 + rng.below(40) as usize;
            // Windows around the row, beside it, wholly outside the buffer, and (one in ten)
            // reaches of millions of rows, which must cost no more scratch than short ones.
            let (mut y0, mut y1) = (rng.below(121) as i32 - 60, rng.below(61) as i32);
            y1 += y0;
            if rng.below(10) == 0 {
                (y0, y1) = (y0 * 10_000_000, y1 * 10_000_000);
                (y0, y1) = (y0.min(y1), y0.max(y1));
            }
            let spans: Vec<RowSpans> = (0..h).map(|_| random_spans(&mut rng)).collect();
            window_hulls(&spans, y0, y1, &mut out, &mut scratch);
            assert_eq!(out.len(), h);
            assert!(
                scratch[0].len() <= 3 * h,
                "scratch of {} rows",
                scratch[0].len()
            );
            for (y, got) in out.iter().enumerate() {
                let lo = (y as i64 + i64::from(y0)).max(0);
                let hi = (y as i64 + i64::from(y1)).min(h as i64 - 1);
                let mut want = kinds(&RowSpans::EMPTY);
                let rows = if lo <= hi {
                    &spans[lo as usize..=hi as usize]
                } else {
                    &[][..]
                };
                for row in rows {
                    for (w, r) in want.iter_mut().zip(kinds(row)) {
                        *w = (w.0.min(r.0), w.1.max(r.1));
                    }
                }
                assert_eq!(kinds(got), want, "row {y} of {h}, reach {y0}..={y1}");
            }
        }
    }

    #[test]
    fn row_hits_answer_the_per_chunk_span_test() {
        // Against the direct test: the window's span meets the chunk's reach [8c + x0, 8c + 7 + x1].
        let mut rng = TestRng::new(5);
        for _ in 0..2000 {
            let reach = Reach {
                x0: -(rng.below(20) as i32),
                x1: rng.below(20) as i32,
                y0: 0,
                y1: 0,
            };
            let chunks = 1 + rng.below(12) as usize;
            let window = random_spans(&mut rng);
            let hits = RowHits::of(&window, true, &reach, chunks);
            for c in 0..chunks {
                let (a, b) = chunk_reach(c, &reach);
                let got = [hits.not_one(c), hits.not_zero(c), hits.light_not_zero(c)];
                for (k, &hit) in got.iter().enumerate() {
                    let direct = meets(kinds(&window)[k], a, b);
                    assert_eq!(
                        hit, direct,
                        "chunk {c} of {chunks}, kind {k}, {window:?}, {reach:?}"
                    );
                }
            }
            // Without depth planes the light-not-zero kind is never asked: no hits.
            let no_depth = RowHits::of(&window, false, &reach, chunks);
            assert!((0..chunks).all(|c| !no_depth.light_not_zero(c)));
        }
    }

    #[test]
    fn a_chunk_that_some_row_in_reach_meets_is_a_hit() {
        // The skip's safety: every chunk whose reach meets a span of any row within the vertical
        // reach is a hit (the hull may add chunks, never drop one).
        let mut rng = TestRng::new(11);
        let (mut scratch, mut windows) = ([Vec::new(), Vec::new()], Vec::new());
        for _ in 0..300 {
            let h = 1 + rng.below(20) as usize;
            let reach = Reach {
                x0: -(rng.below(20) as i32),
                x1: rng.below(20) as i32,
                y0: -(rng.below(6) as i32),
                y1: rng.below(6) as i32,
            };
            let chunks = 1 + rng.below(12) as usize;
            let spans: Vec<RowSpans> = (0..h).map(|_| random_spans(&mut rng)).collect();
            window_hulls(&spans, reach.y0, reach.y1, &mut windows, &mut scratch);
            for (y, window) in windows.iter().enumerate() {
                let hits = RowHits::of(window, true, &reach, chunks);
                let lo = (y as i64 + i64::from(reach.y0)).max(0) as usize;
                let hi = (y as i64 + i64::from(reach.y1)).min(h as i64 - 1) as usize;
                for c in 0..chunks {
                    let (a, b) = chunk_reach(c, &reach);
                    let got = [hits.not_one(c), hits.not_zero(c), hits.light_not_zero(c)];
                    for (k, &hit) in got.iter().enumerate() {
                        let some_row = spans[lo..=hi].iter().any(|r| meets(kinds(r)[k], a, b));
                        assert!(hit || !some_row, "row {y}, chunk {c}, kind {k}, {reach:?}");
                    }
                }
            }
        }
    }
}
