//! The SIMD path of the slab sweep: the five stages of `sweep.rs` on 8 pixels at a time
//! (`wide` f32x8/u32x8), bit-identical to the scalar path lane by lane.
//!
//! Vector work: the gather's arithmetic (and its loads, when a slab's phase is the same for
//! every pixel), the phase hash, the detail function, the transfer-function interpolation,
//! shading, compositing and attenuation. Per lane: the layer cursor (a short data-dependent
//! loop) and table look-ups. Chunks whose lanes hit different meshes, and the row's last
//! `width mod 8` pixels, run the scalar stage functions.
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

use convshadow_common::hash::{pixel_hash, unit_float};
use convshadow_common::kernel::PhaseMode;
use convshadow_common::plan::RenderPlan;
use std::sync::atomic::Ordering;

use wide::f32x8;

use crate::composite::{attenuate, attenuate8, composite8};
use crate::kernels::{LightPlanes, gather8_lanes, gather8_uniform, phases8};
use crate::ldi::Ldi;
use crate::parity::{NO_CROSSING, advance, first_mesh};
use crate::shading::{Specular8, detail_value8, shade8, to_detail8, transfer8};
use crate::sweep::{
    ChunkCounts, MAX_LIGHT_CHANNELS, RowState, SlabContext, jitter_row_hash, light_row_hashes,
    shade_pixel, sweep_pixel,
};

/// Lanes per chunk.
const LANES: usize = 8;

/// How far the gather of any light, phase and slab reads from the pixel it writes (bilinear
/// corners and mean-carry shifts included): x in `x + x0 ..= x + x1`, y in `y + y0 ..= y + y1`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Reach {
    pub x0: i32,
    pub x1: i32,
    pub y0: i32,
    pub y1: i32,
}

impl Reach {
    /// The reach of every light's table over all its phases and slabs.
    pub(crate) fn of(plan: &RenderPlan) -> Reach {
        let mut r = Reach {
            x0: 0,
            x1: 0,
            y0: 0,
            y1: 0,
        };
        for light in &plan.lights {
            let t = &light.table;
            for tap in &t.taps {
                for s in &t.slab_shift {
                    r.x0 = r.x0.min(tap.dx + s[0]);
                    r.x1 = r.x1.max(tap.dx + s[0] + 1);
                    r.y0 = r.y0.min(tap.dy + s[1]);
                    r.y1 = r.y1.max(tap.dy + s[1] + 1);
                }
            }
        }
        r
    }

    /// Whether every read of the chunk at x0..x0+8 in row y lies inside the grid.
    #[inline(always)]
    fn interior(&self, x0: usize, y: usize, w: usize, h: usize) -> bool {
        let (x0, y) = (x0 as i64, y as i64);
        x0 + i64::from(self.x0) >= 0
            && x0 + LANES as i64 - 1 + i64::from(self.x1) < w as i64
            && y + i64::from(self.y0) >= 0
            && y + i64::from(self.y1) < h as i64
    }
}

/// Per row of a light buffer (all lights and channels): the x range `[lo, hi)` of values that
/// are not exactly 1, and of values that are not exactly 0 (empty when `lo >= hi`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct RowSpans {
    pub not_one: (i32, i32),
    pub not_zero: (i32, i32),
}

impl RowSpans {
    /// No value recorded.
    const EMPTY: RowSpans = RowSpans {
        not_one: (i32::MAX, i32::MIN),
        not_zero: (i32::MAX, i32::MIN),
    };

    /// Records the values of pixels `x..x + n` (not-one / not-zero flags of the whole group).
    #[inline(always)]
    fn record(&mut self, x: usize, n: usize, not_one: bool, not_zero: bool) {
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
    fn of(ldi: &Ldi, y: usize, x0: usize, next: &[u32], inside: &[u32], alpha: &[f32]) -> Self {
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
            (0..t.phase_count).all(|p| {
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
                        s.record(x, 1, v != 1.0, v != 0.0);
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
enum ChunkWork {
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
    fn classify(&self, ctx: &SlabContext<'_>, reach: &Reach, y: usize, c: usize) -> ChunkWork {
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
        let all_zeros =
            !all_ones && reach.interior(c * LANES, y, w, h) && !rows(&|s| meets(s.not_zero, a, b));
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

/// Processes one row of one slab, 8 pixels at a time; the last `width mod 8` pixels go through
/// the scalar [`sweep_pixel`].
pub(crate) fn sweep_row_simd(
    ctx: &SlabContext<'_>,
    reach: &Reach,
    y: usize,
    prev: &[f32],
    mut row: RowState<'_>,
    mut quiet: Option<QuietRow<'_>>,
    counts: Option<&ChunkCounts>,
) {
    let plan = ctx.plan;
    let w = plan.grid_width as usize;
    let h = plan.grid_height as usize;
    let planes = plan.lights.len() * plan.channels as usize;
    let row_hashes = light_row_hashes(ctx, y);
    let jitter_row = jitter_row_hash(ctx, y);
    let mut spans = RowSpans::EMPTY;
    let mut tally = [0u64; 3];
    let full_chunks = w / LANES;
    let chunk_fn: ChunkFn = match planes {
        0..=2 => sweep_chunk::<2>,
        3..=6 => sweep_chunk::<6>,
        7..=12 => sweep_chunk::<12>,
        _ => sweep_chunk::<MAX_LIGHT_CHANNELS>,
    };

    for c in 0..full_chunks {
        let x0 = c * LANES;
        let work = match &quiet {
            Some(q) => q.classify(ctx, reach, y, c),
            None => ChunkWork::Full(None),
        };
        match work {
            ChunkWork::Unoccluded => {
                tally[1] += 1;
                for p in 0..planes {
                    row.light[p * w + x0..][..LANES].fill(1.0);
                }
                spans.record(x0, LANES, false, true);
                continue;
            }
            ChunkWork::Dark => {
                tally[2] += 1;
                for x in x0..x0 + LANES {
                    let end = ctx.ldi.offsets[y * w + x + 1];
                    advance(ctx.ldi, &mut row.next[x], end, &mut row.inside[x], ctx.back);
                }
                for p in 0..planes {
                    row.light[p * w + x0..][..LANES].fill(0.0);
                }
                spans.record(x0, LANES, true, false);
            }
            ChunkWork::Full(known_light) => {
                tally[0] += 1;
                let interior = reach.interior(x0, y, w, h);
                let (not_one, not_zero) = chunk_fn(
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
                spans.record(x0, LANES, not_one, not_zero);
            }
        }
        if let Some(q) = &mut quiet {
            q.chunks[c] = ChunkState::of(ctx.ldi, y, x0, row.next, row.inside, row.alpha);
        }
    }

    for x in full_chunks * LANES..w {
        sweep_pixel(ctx, y, x, prev, &mut row, &row_hashes, jitter_row);
        for p in 0..planes {
            let v = row.light[p * w + x];
            spans.record(x, 1, v != 1.0, v != 0.0);
        }
    }
    if let Some(q) = quiet {
        *q.span_out = spans;
    }
    if let Some(c) = counts {
        c.full.fetch_add(tally[0], Ordering::Relaxed);
        c.unoccluded.fetch_add(tally[1], Ordering::Relaxed);
        c.dark.fetch_add(tally[2], Ordering::Relaxed);
    }
}

/// [`sweep_chunk`] instantiated for one light-channel capacity.
type ChunkFn = fn(
    &SlabContext<'_>,
    usize,
    usize,
    &[f32],
    &mut RowState<'_>,
    &[u32; MAX_LIGHT_CHANNELS],
    u32,
    bool,
    Option<f32>,
) -> (bool, bool);

/// All five stages for the 8 pixels x0..x0+8 of row y. Returns whether any outgoing light value
/// is not exactly 1, and whether any is not exactly 0.
#[allow(clippy::too_many_arguments)]
fn sweep_chunk<const N: usize>(
    ctx: &SlabContext<'_>,
    y: usize,
    x0: usize,
    prev: &[f32],
    row: &mut RowState<'_>,
    row_hashes: &[u32; MAX_LIGHT_CHANNELS],
    jitter_row: u32,
    interior: bool,
    known_light: Option<f32>,
) -> (bool, bool) {
    let plan = ctx.plan;
    let ldi = ctx.ldi;
    let w = plan.grid_width as usize;
    let ch = plan.channels as usize;
    let slab = ctx.slab as usize;
    let n = plan.lights.len() * ch;

    // 1. Convolution of every light buffer.
    // N ≥ lights × channels, as small as possible: zeroing a 48-vector array per chunk costs.
    let mut iin = [f32x8::ZERO; N];
    if let Some(v) = known_light {
        iin[..n].fill(f32x8::splat(v));
    }
    for (l, light) in plan.lights.iter().enumerate() {
        if known_light.is_some() {
            break;
        }
        let t = &light.table;
        let planes = LightPlanes {
            data: prev,
            base: l * ch * w,
            channels: ch,
            row_stride: plan.light_row_len(),
            width: w as i32,
            height: plan.grid_height as i32,
        };
        let shift = t.slab_shift[slab];
        let acc = &mut iin[l * ch..(l + 1) * ch];
        let uniform = match t.phase_mode {
            PhaseMode::PerPixel => None,
            PhaseMode::PerSlab => Some(crate::kernels::phase_at(
                t,
                ctx.slab,
                light.slab_hash[slab],
                0,
                0,
            )),
            PhaseMode::Schedule => Some(t.slab_phase[slab]),
        };
        match uniform {
            Some(p) => {
                gather8_uniform(
                    &planes,
                    t.phase(p),
                    shift,
                    x0 as i32,
                    y as i32,
                    interior,
                    acc,
                );
            }
            None => {
                let phases = phases8(t, row_hashes[l], x0 as u32);
                gather8_lanes(
                    &planes, t, &phases, shift, x0 as i32, y as i32, interior, acc,
                );
            }
        }
    }

    // 2. Intersection: every lane's cursor.
    let mut crossed = [NO_CROSSING; LANES];
    let mut mesh = [None; LANES];
    for i in 0..LANES {
        let x = x0 + i;
        let end = ldi.offsets[y * w + x + 1];
        crossed[i] = advance(ldi, &mut row.next[x], end, &mut row.inside[x], ctx.back);
        mesh[i] = if crossed[i] != NO_CROSSING {
            Some(u32::from(ldi.mesh[crossed[i] as usize]))
        } else {
            first_mesh(row.inside[x])
        };
    }

    // 3–4. Shading and compositing.
    let mut attenuation = [f32x8::ONE; 3];
    let first = mesh.iter().flatten().next().copied();
    if let Some(m) = first {
        if mesh.iter().all(|&k| k.is_none() || k == Some(m)) {
            attenuation = shade_chunk(ctx, y, x0, row, &iin, m, &mesh, &crossed, jitter_row);
        } else {
            // Lanes on different meshes: the scalar stage, lane by lane.
            let mut att = [[1.0f32; 8]; 3];
            for i in 0..LANES {
                let x = x0 + i;
                let mut lane_iin = [0.0f32; MAX_LIGHT_CHANNELS];
                for (k, v) in iin.iter().take(n).enumerate() {
                    lane_iin[k] = v.to_array()[i];
                }
                let mut c = [row.color[x], row.color[w + x], row.color[2 * w + x]];
                let a = shade_pixel(
                    ctx,
                    x,
                    jitter_row,
                    y,
                    crossed[i],
                    row.inside[x],
                    &lane_iin[..n],
                    &mut c,
                    &mut row.alpha[x],
                );
                row.color[x] = c[0];
                row.color[w + x] = c[1];
                row.color[2 * w + x] = c[2];
                for k in 0..3 {
                    att[k][i] = a[k];
                }
            }
            attenuation = att.map(f32x8::new);
        }
    }

    // 5. Attenuate (and flush) into this slab's outgoing light buffer.
    let mut not_one = f32x8::ZERO;
    let mut not_zero = f32x8::ZERO;
    for l in 0..plan.lights.len() {
        for c in 0..ch {
            let out = attenuate8(iin[l * ch + c], attenuation[c]);
            not_one |= out.simd_ne(f32x8::ONE);
            not_zero |= out.simd_ne(f32x8::ZERO);
            let dst: &mut [f32; 8] = (&mut row.light[(l * ch + c) * w + x0..][..LANES])
                .try_into()
                .expect("8 lanes");
            *dst = out.to_array();
        }
    }
    debug_assert_eq!(attenuate(1.0, 1.0), 1.0);
    (not_one.any(), not_zero.any())
}

/// Stages 3–4 for a chunk whose shaded lanes all lie in mesh `m`: vector shading and
/// compositing. Returns the attenuation per channel (1 in lanes without a mesh).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn shade_chunk(
    ctx: &SlabContext<'_>,
    y: usize,
    x0: usize,
    row: &mut RowState<'_>,
    iin: &[f32x8],
    m: u32,
    mesh: &[Option<u32>; LANES],
    crossed: &[u32; LANES],
    jitter_row: u32,
) -> [f32x8; 3] {
    let plan = ctx.plan;
    let ldi = ctx.ldi;
    let w = plan.grid_width as usize;
    let n = plan.lights.len() * plan.channels as usize;
    let lane_mask = |f: &dyn Fn(usize) -> bool| {
        f32x8::new(std::array::from_fn(|i| {
            if f(i) { f32::from_bits(u32::MAX) } else { 0.0 }
        }))
    };
    let active = lane_mask(&|i| mesh[i].is_some());
    let z = f32x8::new(std::array::from_fn(|i| {
        if crossed[i] != NO_CROSSING {
            ldi.depth[crossed[i] as usize]
        } else if plan.jitter {
            ctx.front + unit_float(pixel_hash(jitter_row, (x0 + i) as u32)) * plan.slab_distance
        } else {
            ctx.front + 0.5 * plan.slab_distance
        }
    }));
    let material = &plan.materials[plan.mesh_material[m as usize] as usize];
    let value = if material.tf.len() > 1 {
        let xs = f32x8::new(std::array::from_fn(|i| (x0 + i) as f32 + 0.5));
        let ys = f32x8::splat(y as f32 + 0.5);
        let q = to_detail8(&plan.mesh_to_detail[m as usize], xs, ys, z);
        detail_value8(material, q)
    } else {
        f32x8::ZERO
    };
    let tf = transfer8(&material.tf, value);
    let spec = material.specular.and_then(|(strength, exponent)| {
        if crossed.iter().all(|&c| c == NO_CROSSING) {
            return None;
        }
        let normals: [[f32; 3]; LANES] = std::array::from_fn(|i| {
            if crossed[i] != NO_CROSSING {
                ctx.raster.triangles[ldi.triangle[crossed[i] as usize] as usize].normal
            } else {
                [0.0, 0.0, 1.0]
            }
        });
        Some(Specular8 {
            strength,
            exponent,
            normal: std::array::from_fn(|k| f32x8::new(normals.map(|nv| nv[k]))),
            lanes: lane_mask(&|i| crossed[i] != NO_CROSSING),
        })
    });
    let shaded = shade8(plan, tf.color, &iin[..n], spec.as_ref());

    let load = |s: &[f32]| f32x8::new(s[..LANES].try_into().expect("8 lanes"));
    let mut color = [
        load(&row.color[x0..]),
        load(&row.color[w + x0..]),
        load(&row.color[2 * w + x0..]),
    ];
    let mut alpha = load(&row.alpha[x0..]);
    composite8(&mut color, &mut alpha, shaded, tf.alpha, active);
    for (k, v) in color.iter().enumerate() {
        row.color[k * w + x0..][..LANES].copy_from_slice(&v.to_array());
    }
    row.alpha[x0..x0 + LANES].copy_from_slice(&alpha.to_array());
    tf.attenuation.map(|a| active.select(a, f32x8::ONE))
}
