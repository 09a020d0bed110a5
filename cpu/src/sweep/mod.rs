//! The front-to-back slab sweep (DESIGN §2 "Per slab, per pixel"; paper §4.2). Mirrors
//! `gpu/src/shaders/sweep.wgsl`.
//!
//! Per slab, rows are processed in parallel; each pixel convolves every light buffer (reading
//! the previous slab's buffer, ping-pong), advances its layer cursor, shades one point if it is
//! inside a mesh or crossed a surface, composites front to back and attenuates its light.
//! A pixel's result depends only on the previous slab and its own state, so the image is the
//! same bits for any thread count.
//!
//! Two code paths run the same stages: [`SweepPath::Scalar`], one pixel at a time (the readable
//! reference, in this file), and [`SweepPath::Simd`], eight pixels at a time with `wide`
//! (`crate::sweep_simd`), which gives the same bits and may skip provably quiet pixels.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use convshadow_common::hash::row_hash;
use convshadow_common::plan::RenderPlan;
use convshadow_common::raster::RasterSetup;
use rayon::prelude::*;

use crate::composite::{attenuate, composite, finish};
use crate::kernels::{Plane, gather, light_row_hash, phase_at};
use crate::ldi::Ldi;
use crate::parity::{NO_CROSSING, advance, first_mesh};
use crate::shading::{material_at, shade, shading_depth};
use crate::sweep_simd::{QuietRow, QuietSetup, Reach, sweep_row_simd};

/// Largest light count × channels handled per pixel on the stack.
pub const MAX_LIGHT_CHANNELS: usize = 48;

/// Why a sweep stopped early.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SweepError {
    /// The cancel flag was raised (Ctrl-C / SIGTERM).
    #[error("interrupted")]
    Interrupted,
}

/// The result of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOutput {
    /// Linear RGB, `width·height·3`, the guard band cropped away.
    pub image: Vec<f32>,
    /// The light buffers after the last slab (grid-sized, row-major `[row][light][channel][x]`).
    pub light: Vec<f32>,
}

/// Which CPU code path runs the sweep. Both give the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SweepPath {
    /// One pixel at a time: the readable reference.
    Scalar,
    /// Eight pixels at a time (`wide` f32x8/u32x8), with quiet-pixel skipping.
    #[default]
    Simd,
}

/// Options of a sweep run.
pub struct SweepOptions<'a> {
    /// Called after every slab with the slab index.
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Checked between slabs; when raised the sweep stops with [`SweepError::Interrupted`].
    pub cancel: Option<&'a AtomicBool>,
    /// Initial light value per light and channel (`None` = 1, the unoccluded light).
    pub initial_light: Option<&'a [f32]>,
    /// The CPU code path (the GPU port ignores it).
    pub path: SweepPath,
    /// SIMD path only: skip 8-pixel chunks whose result is known exactly without computing it
    /// (unoccluded light and no mesh, or opaque pixels in the dark). On by default; off only to
    /// measure what it saves.
    pub skip_quiet: bool,
    /// SIMD path: counts of how 8-pixel chunks were processed, if wanted.
    pub chunk_counts: Option<&'a ChunkCounts>,
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
}

impl Default for SweepOptions<'_> {
    fn default() -> Self {
        SweepOptions {
            progress: &|_| {},
            cancel: None,
            initial_light: None,
            path: SweepPath::default(),
            skip_quiet: true,
            chunk_counts: None,
        }
    }
}

/// What every pixel of one slab shares.
pub(crate) struct SlabContext<'a> {
    pub plan: &'a RenderPlan,
    pub raster: &'a RasterSetup,
    pub ldi: &'a Ldi,
    pub slab: u32,
    /// Back face of the slab (the cursor advances past fragments in front of it).
    pub back: f32,
    /// Front face of the slab.
    pub front: f32,
}

/// One row's mutable per-pixel state. Colours are planar per row: `[R…][G…][B…]`.
pub(crate) struct RowState<'a> {
    pub light: &'a mut [f32],
    pub next: &'a mut [u32],
    pub inside: &'a mut [u32],
    pub color: &'a mut [f32],
    pub alpha: &'a mut [f32],
}

/// Runs the sweep on the current rayon pool with the path chosen in `options`.
pub fn sweep(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, SweepError> {
    let w = plan.grid_width as usize;
    let h = plan.grid_height as usize;
    let ch = plan.channels as usize;
    let lights = plan.lights.len();
    let row_len = plan.light_row_len();
    assert!(
        lights * ch <= MAX_LIGHT_CHANNELS,
        "scene validation caps the light count"
    );

    let mut prev = match options.initial_light {
        Some(v) => v.to_vec(),
        None => vec![1.0f32; row_len * h],
    };
    let mut cur = vec![0.0f32; row_len * h];
    let mut next: Vec<u32> = ldi.offsets[..w * h].to_vec();
    let mut inside = vec![0u32; w * h];
    let mut color = vec![0.0f32; w * h * 3];
    let mut alpha = vec![0.0f32; w * h];

    // SIMD path: per-row spans of the light that is not exactly 1 / not exactly 0, and per-chunk
    // cursor summaries, so quiet chunks can be recognised without touching their pixels.
    let quiet = (options.path == SweepPath::Simd && options.skip_quiet)
        .then(|| QuietSetup::new(plan, ldi, &prev));
    let chunks_per_row = (w / 8).max(1);
    let (mut spans_prev, mut spans_cur, mut chunk_states) = match &quiet {
        Some(q) => (
            q.initial_spans.clone(),
            q.initial_spans.clone(),
            q.chunks.clone(),
        ),
        None => (Vec::new(), Vec::new(), Vec::new()),
    };
    let reach = Reach::of(plan);

    for slab in 0..plan.slabs {
        if options.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(SweepError::Interrupted);
        }
        let ctx = SlabContext {
            plan,
            raster,
            ldi,
            slab,
            back: plan.slab_back[slab as usize],
            front: plan.slab_front[slab as usize],
        };
        let prev_ref = &prev;
        let rows = cur
            .par_chunks_mut(row_len)
            .zip(next.par_chunks_mut(w))
            .zip(inside.par_chunks_mut(w))
            .zip(color.par_chunks_mut(w * 3))
            .zip(alpha.par_chunks_mut(w))
            .enumerate()
            .map(|(y, ((((light, next), inside), color), alpha))| {
                (
                    y,
                    RowState {
                        light,
                        next,
                        inside,
                        color,
                        alpha,
                    },
                )
            });
        match (options.path, &quiet) {
            (SweepPath::Scalar, _) => rows.for_each(|(y, row)| {
                sweep_row_scalar(&ctx, y, prev_ref, row);
            }),
            (SweepPath::Simd, None) => rows.for_each(|(y, row)| {
                sweep_row_simd(&ctx, &reach, y, prev_ref, row, None, options.chunk_counts);
            }),
            (SweepPath::Simd, Some(q)) => {
                let spans_prev_ref = &spans_prev;
                rows.zip(spans_cur.par_iter_mut())
                    .zip(chunk_states.par_chunks_mut(chunks_per_row))
                    .for_each(|(((y, row), span_out), chunks)| {
                        let quiet_row = QuietRow {
                            setup: q,
                            spans_prev: spans_prev_ref,
                            span_out,
                            chunks,
                        };
                        sweep_row_simd(
                            &ctx,
                            &reach,
                            y,
                            prev_ref,
                            row,
                            Some(quiet_row),
                            options.chunk_counts,
                        );
                    });
                std::mem::swap(&mut spans_prev, &mut spans_cur);
            }
        }
        std::mem::swap(&mut prev, &mut cur);
        (options.progress)(slab);
    }

    let g = plan.guard as usize;
    let (iw, ih) = (plan.width as usize, plan.height as usize);
    let mut image = vec![0.0f32; iw * ih * 3];
    image
        .par_chunks_mut(iw * 3)
        .enumerate()
        .for_each(|(y, row)| {
            let gy = y + g;
            let colors = &color[gy * w * 3..(gy + 1) * w * 3];
            for x in 0..iw {
                let gx = x + g;
                let mut c = [colors[gx], colors[w + gx], colors[2 * w + gx]];
                finish(&mut c, alpha[gy * w + gx], plan.background);
                row[3 * x..3 * x + 3].copy_from_slice(&c);
            }
        });
    Ok(SweepOutput { image, light: prev })
}

/// Every light's row hash for row `y` of the slab (the prefix of each per-pixel phase hash).
pub(crate) fn light_row_hashes(ctx: &SlabContext<'_>, y: usize) -> [u32; MAX_LIGHT_CHANNELS] {
    let mut row_hashes = [0u32; MAX_LIGHT_CHANNELS];
    for (l, light) in ctx.plan.lights.iter().enumerate() {
        row_hashes[l] = light_row_hash(light.slab_hash[ctx.slab as usize], y as u32);
    }
    row_hashes
}

/// The jitter row hash of row `y` of the slab.
pub(crate) fn jitter_row_hash(ctx: &SlabContext<'_>, y: usize) -> u32 {
    row_hash(ctx.plan.jitter_slab_hash[ctx.slab as usize], y as u32)
}

/// Processes one row of one slab, one pixel at a time (the scalar reference path).
fn sweep_row_scalar(ctx: &SlabContext<'_>, y: usize, prev: &[f32], mut row: RowState<'_>) {
    let w = ctx.plan.grid_width as usize;
    let row_hashes = light_row_hashes(ctx, y);
    let jitter_row = jitter_row_hash(ctx, y);
    for x in 0..w {
        sweep_pixel(ctx, y, x, prev, &mut row, &row_hashes, jitter_row);
    }
}

/// All five stages for pixel (x, y) of one slab.
#[inline(always)]
pub(crate) fn sweep_pixel(
    ctx: &SlabContext<'_>,
    y: usize,
    x: usize,
    prev: &[f32],
    row: &mut RowState<'_>,
    row_hashes: &[u32; MAX_LIGHT_CHANNELS],
    jitter_row: u32,
) {
    let plan = ctx.plan;
    let w = plan.grid_width as usize;
    let ch = plan.channels as usize;
    let n = plan.lights.len() * ch;
    let mut iin = [0.0f32; MAX_LIGHT_CHANNELS];
    // 1. Convolution of every light buffer.
    gather_pixel(ctx, prev, x, y, row_hashes, &mut iin);

    // 2. Intersection: advance the layer cursor to the slab's back face.
    let p = y * w + x;
    let end = ctx.ldi.offsets[p + 1];
    let crossed = advance(ctx.ldi, &mut row.next[x], end, &mut row.inside[x], ctx.back);

    // 3–4. Shading and compositing, if inside a mesh or a surface was crossed.
    let mut c = [row.color[x], row.color[w + x], row.color[2 * w + x]];
    let attenuation = shade_pixel(
        ctx,
        x,
        jitter_row,
        y,
        crossed,
        row.inside[x],
        &iin[..n],
        &mut c,
        &mut row.alpha[x],
    );
    row.color[x] = c[0];
    row.color[w + x] = c[1];
    row.color[2 * w + x] = c[2];

    // 5. Attenuate (and flush) into this slab's outgoing light buffer.
    for l in 0..plan.lights.len() {
        for c in 0..ch {
            row.light[(l * ch + c) * w + x] = attenuate(iin[l * ch + c], attenuation[c]);
        }
    }
}

/// Stage 1 for one pixel: every light and channel through its kernel into `iin`.
#[inline(always)]
fn gather_pixel(
    ctx: &SlabContext<'_>,
    prev: &[f32],
    x: usize,
    y: usize,
    row_hashes: &[u32; MAX_LIGHT_CHANNELS],
    iin: &mut [f32; MAX_LIGHT_CHANNELS],
) {
    let plan = ctx.plan;
    let slab = ctx.slab as usize;
    let ch = plan.channels as usize;
    for (l, light) in plan.lights.iter().enumerate() {
        let t = &light.table;
        let phase = phase_at(t, ctx.slab, light.slab_hash[slab], row_hashes[l], x as u32);
        let taps = t.phase(phase);
        let shift = t.slab_shift[slab];
        for c in 0..ch {
            let plane = Plane {
                data: prev,
                base: (l * ch + c) * plan.grid_width as usize,
                row_stride: plan.light_row_len(),
                width: plan.grid_width as i32,
                height: plan.grid_height as i32,
            };
            iin[l * ch + c] = gather(&plane, taps, shift, x as i32, y as i32);
        }
    }
}

/// Stages 3–4 for one pixel: shades one point if the pixel is inside a mesh or crossed a
/// surface, composites it into `color`/`alpha`, and returns the light attenuation per channel
/// (1 where there is no mesh).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn shade_pixel(
    ctx: &SlabContext<'_>,
    x: usize,
    jitter_row: u32,
    y: usize,
    crossed: u32,
    inside: u32,
    iin: &[f32],
    color: &mut [f32; 3],
    alpha: &mut f32,
) -> [f32; 3] {
    let plan = ctx.plan;
    let ldi = ctx.ldi;
    let mesh = if crossed != NO_CROSSING {
        Some(u32::from(ldi.mesh[crossed as usize]))
    } else {
        first_mesh(inside)
    };
    let Some(mesh) = mesh else {
        return [1.0; 3];
    };
    let z = shading_depth(plan, ldi, crossed, ctx.front, jitter_row, x);
    let tf = material_at(plan, mesh, x, y, z);
    let material = &plan.materials[plan.mesh_material[mesh as usize] as usize];
    let spec = match material.specular {
        Some((strength, exponent)) if crossed != NO_CROSSING => {
            let n = ctx.raster.triangles[ldi.triangle[crossed as usize] as usize].normal;
            Some((strength, exponent, n))
        }
        _ => None,
    };
    let shaded = shade(plan, tf.color, iin, spec);
    composite(color, alpha, shaded, tf.alpha);
    tf.attenuation
}
