//! The front-to-back slab sweep (paper §4.2; docs/ARCHITECTURE.md, stage 6). Mirrors
//! `gpu/src/shaders/sweep.wgsl`.
//!
//! Per slab, rows are processed in parallel; each pixel convolves every light buffer (reading
//! the previous slab's buffer, ping-pong), advances its layer cursor, shades one point if it is
//! inside a mesh or crossed a surface, composites front to back and attenuates its light.
//! A pixel's result depends only on the previous slab and its own state, so the image is the
//! same bits for any thread count. The sweep stops after the first slab after which every image
//! pixel is opaque (alpha exactly 1; no later slab can change an image bit) unless
//! [`SweepOptions::every_slab`] asks for every slab.
//!
//! Two code paths give the same bits: [`SweepPath::Scalar`] runs the per-pixel stage (`pixel`,
//! which reads like `sweep.wgsl`) one pixel at a time, and [`SweepPath::Simd`] eight pixels at a
//! time with `wide` (`fast`, each of whose fast paths is held to the per-pixel stage's bits by
//! its tests), skipping provably quiet pixels; a row's last `width mod 8` pixels go through the
//! per-pixel stage.
//!
//! Modules, with imports in one direction only: this driver (the per-slab loop, ping-pong
//! buffers, cancel and progress) → `fast` (the SIMD path: the 8-lane row and chunk, quiet-chunk
//! skipping, the lane gathers) → `pixel` (the per-pixel stage) → `kit` (slab and row context,
//! row state, row hashes) → the stage functions in `kernels`, `parity`, `shading` and
//! `composite`; `level_blocks` (the level plane's block minima, which both paths read) beside;
//! `eye` (a perspective camera's rays, reading the light this driver sweeps on the slab grid:
//! [`sweep_perspective`]) beside.

mod eye;
mod fast;
mod kit;
mod level_blocks;
mod pixel;

use convshadow_common::pixel::levels::level_at;
use std::sync::atomic::Ordering;

use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::raster::RasterSetup;
use rayon::prelude::*;

use crate::composite::{HeldRecords, finish};
use crate::kernels::LightTaps;
use crate::ldi::Ldi;
use convshadow_common::plan::levels::initial_levels;
use eye::{EyeState, GridLight};
use fast::{ChunkState, QuietRow, QuietSetup, RowSpans, SimdSlab, TapColumns, sweep_row_simd};
use kit::{Previous, Reach, RowContext, RowState, SlabContext};
use level_blocks::LevelBlocks;

pub use convshadow_common::contract::sweep_io::{EyePoint, EyeView};
pub use convshadow_common::contract::sweep_io::{
    MAX_LIGHT_CHANNELS, SweepError, SweepOptions, SweepOutput,
};
pub use fast::ChunkCounts;

/// Which CPU code path runs the sweep. Both give the same bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SweepPath {
    /// One pixel at a time: the readable reference.
    Scalar,
    /// Eight pixels at a time (`wide` f32x8/u32x8), with quiet-pixel skipping.
    #[default]
    Simd,
}

/// The CPU sweep's own knobs: code path, quiet-chunk skipping and chunk counts.
pub struct CpuOptions<'a> {
    /// The CPU code path.
    pub path: SweepPath,
    /// SIMD path only: skip 8-pixel chunks whose result is known exactly without computing it
    /// (unoccluded light and no mesh, or opaque pixels in the dark). On by default; off only to
    /// measure what it saves.
    pub skip_quiet: bool,
    /// SIMD path: counts of how 8-pixel chunks were processed, if wanted.
    pub chunk_counts: Option<&'a ChunkCounts>,
}

impl Default for CpuOptions<'_> {
    fn default() -> Self {
        CpuOptions {
            path: SweepPath::default(),
            skip_quiet: true,
            chunk_counts: None,
        }
    }
}

/// Runs the sweep on the current rayon pool with the default [`CpuOptions`] (SIMD path,
/// quiet chunks skipped).
pub fn sweep(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, SweepError> {
    sweep_with(plan, raster, ldi, options, &CpuOptions::default())
}

/// The sweep's per-pixel state: the two light buffers (ping-pong: `prev` is read, `cur` written;
/// pixel-interleaved, see [`to_pixel_rows`]), the layer cursors and the composited colour
/// (planar per row) and alpha.
struct PixelState {
    prev: Vec<f32>,
    cur: Vec<f32>,
    /// Distance penumbra: each light's level per pixel for the next slab (ping-pong like the
    /// light; see `kernels::distance_row`). One unused entry per row otherwise.
    levels_prev: Vec<u32>,
    levels_cur: Vec<u32>,
    /// `levels_prev`'s 2×2 block minima.
    level_blocks: LevelBlocks,
    next: Vec<u32>,
    inside: Vec<u32>,
    color: Vec<f32>,
    alpha: Vec<f32>,
    /// Pre-integration's kept front values ([`RowState::pre`]), `pre_stride` per row.
    pre: Vec<f32>,
    pre_stride: usize,
    /// Surface holds ([`RowState::hold`]), `hold_stride` per row.
    hold: Vec<u32>,
    hold_stride: usize,
}

impl PixelState {
    /// The state before the first slab: the initial light `initial` (planar, as
    /// [`SweepOptions::initial_light`]), each cursor at its pixel's first fragment, nothing
    /// composited.
    fn new(plan: &RenderPlan, ldi: &Ldi, initial: &[f32]) -> PixelState {
        let w = plan.grid_width as usize;
        let h = plan.grid_height as usize;
        // One float per pixel with pre-integration, one per row (unused) without: every row
        // needs a slice.
        let pre_stride = if plan.preintegration { w } else { 1 };
        let hold_stride = if plan.has_surface_hold() { w } else { 1 };
        let levels_prev = initial_levels(plan, initial);
        let prev = to_pixel_rows(plan, initial);
        PixelState {
            levels_cur: vec![0u32; levels_prev.len()],
            level_blocks: LevelBlocks::new(plan, &levels_prev),
            levels_prev,
            cur: vec![0.0f32; prev.len()],
            prev,
            next: ldi.offsets[..w * h].to_vec(),
            inside: vec![0u32; w * h],
            color: vec![0.0f32; w * h * 3],
            alpha: vec![0.0f32; w * h],
            pre: vec![f32::NAN; pre_stride * h],
            pre_stride,
            hold: vec![0u32; hold_stride * h],
            hold_stride,
        }
    }
}

/// Floats after the last light-buffer row: the per-lane gather reads 8 floats at a pixel pair of
/// 2 or 3 planes, up to 4 beyond the pair.
const LIGHT_SLACK: usize = 8;

/// A planar light buffer (`[row][light][plane][x]`, the sweep's input and output) as the sweep
/// keeps it, pixel-interleaved (`[row][light][x][plane]`, see `kernels::LightPlanes`), with
/// [`LIGHT_SLACK`] zeros after it.
fn to_pixel_rows(plan: &RenderPlan, planar: &[f32]) -> Vec<f32> {
    let (w, planes) = (plan.grid_width as usize, plan.planes_per_light());
    let mut out = vec![0.0f32; planar.len() + LIGHT_SLACK];
    for (block, from) in out.chunks_mut(w * planes).zip(planar.chunks(w * planes)) {
        for (x, pixel) in block.chunks_mut(planes).enumerate() {
            for (c, v) in pixel.iter_mut().enumerate() {
                *v = from[c * w + x];
            }
        }
    }
    debug_assert_eq!(planar.len() % plan.light_row_len().max(1), 0, "whole rows");
    out
}

/// The inverse of [`to_pixel_rows`]: the sweep's buffer back in planar order.
fn to_plane_rows(plan: &RenderPlan, pixels: &[f32]) -> Vec<f32> {
    let (w, planes) = (plan.grid_width as usize, plan.planes_per_light());
    let len = pixels.len() - LIGHT_SLACK;
    let mut out = vec![0.0f32; len];
    for (block, from) in out
        .chunks_mut(w * planes)
        .zip(pixels[..len].chunks(w * planes))
    {
        for (x, pixel) in from.chunks(planes).enumerate() {
            for (c, v) in pixel.iter().enumerate() {
                block[c * w + x] = *v;
            }
        }
    }
    out
}

/// SIMD path: per-row spans of the light that is not exactly 1 / not exactly 0, and per-chunk
/// cursor summaries, so quiet chunks can be recognised without touching their pixels.
struct QuietState {
    setup: QuietSetup,
    spans_prev: Vec<RowSpans>,
    spans_cur: Vec<RowSpans>,
    chunk_states: Vec<ChunkState>,
    /// Per row, the hull of `spans_prev` over the rows within the kernels' vertical reach
    /// (`fast::window_hulls`), and that function's scratch buffers.
    windows: Vec<RowSpans>,
    window_scratch: [Vec<RowSpans>; 2],
    /// Per chunk, bit b: light buffer b (slab mod 2 writes it) already holds this chunk's
    /// unoccluded fill, written two slabs ago and not since (see `QuietRow::filled`).
    filled: Vec<u8>,
    chunks_per_row: usize,
}

impl QuietState {
    /// The quiet-chunk state for the initial light `prev`, when `cpu` asks for skipping on the
    /// SIMD path.
    fn new(
        plan: &RenderPlan,
        ldi: &Ldi,
        prev: &[f32],
        reach: &Reach,
        cpu: &CpuOptions<'_>,
    ) -> Option<QuietState> {
        (cpu.path == SweepPath::Simd && cpu.skip_quiet).then(|| {
            let setup = QuietSetup::new(plan, ldi, prev);
            let mut q = QuietState {
                spans_prev: setup.initial_spans.clone(),
                spans_cur: setup.initial_spans.clone(),
                chunk_states: setup.chunks.clone(),
                windows: Vec::new(),
                window_scratch: [Vec::new(), Vec::new()],
                filled: vec![0; setup.chunks.len()],
                chunks_per_row: fast::chunks_per_row(plan.grid_width as usize),
                setup,
            };
            q.update_windows(reach);
            q
        })
    }

    /// `windows` for the current `spans_prev`.
    fn update_windows(&mut self, reach: &Reach) {
        let (spans, out) = (&self.spans_prev, &mut self.windows);
        fast::window_hulls(spans, reach.y0, reach.y1, out, &mut self.window_scratch);
    }
}

/// Sweeps one slab over every row in parallel, on the SIMD path where `simd` is given (with
/// quiet-chunk skipping where `quiet` is), else on the scalar path; then swaps the light buffers.
fn sweep_slab(
    ctx: &SlabContext<'_>,
    simd: Option<&SimdSlab<'_>>,
    counts: Option<&ChunkCounts>,
    state: &mut PixelState,
    mut quiet: Option<&mut QuietState>,
) {
    let w = ctx.plan.grid_width as usize;
    let row_len = ctx.plan.light_row_len();
    let prev_ref = &Previous {
        light: &state.prev,
        levels: &state.levels_prev,
        level_blocks: &state.level_blocks.blocks,
    };
    let rows = state.cur[..state.prev.len() - LIGHT_SLACK]
        .par_chunks_mut(row_len)
        .zip(state.levels_cur.par_chunks_mut(ctx.plan.level_row_len()))
        .zip(state.next.par_chunks_mut(w))
        .zip(state.inside.par_chunks_mut(w))
        .zip(state.color.par_chunks_mut(w * 3))
        .zip(state.alpha.par_chunks_mut(w))
        .zip(state.pre.par_chunks_mut(state.pre_stride))
        .zip(state.hold.par_chunks_mut(state.hold_stride))
        .enumerate()
        .map(
            |(y, (((((((light, levels), next), inside), color), alpha), pre), hold))| {
                (
                    y,
                    RowState {
                        light,
                        levels,
                        next,
                        inside,
                        color,
                        alpha,
                        pre,
                        hold,
                    },
                )
            },
        );
    let row_of = |y| RowContext::new(ctx, prev_ref, y);
    match (simd, quiet.as_deref_mut()) {
        (None, _) => rows.for_each(|(y, mut row)| {
            pixel::sweep_row(&row_of(y), &mut row);
        }),
        (Some(simd), None) => rows.for_each(|(y, row)| {
            sweep_row_simd(simd, &row_of(y), row, None, counts);
        }),
        (Some(simd), Some(q)) => {
            let setup = &q.setup;
            rows.zip(q.spans_cur.par_iter_mut())
                .zip(q.chunk_states.par_chunks_mut(q.chunks_per_row))
                .zip(q.filled.par_chunks_mut(q.chunks_per_row))
                .zip(q.windows.par_iter())
                .for_each(|(((((y, row), span_out), chunks), filled), window)| {
                    let quiet_row = QuietRow {
                        setup,
                        window,
                        span_out,
                        chunks,
                        filled,
                    };
                    sweep_row_simd(simd, &row_of(y), row, Some(quiet_row), counts);
                });
            std::mem::swap(&mut q.spans_prev, &mut q.spans_cur);
            q.update_windows(&ctx.reach);
        }
    }
    std::mem::swap(&mut state.prev, &mut state.cur);
    std::mem::swap(&mut state.levels_prev, &mut state.levels_cur);
    if ctx.plan.depth_planes() > 0 {
        // Where a row's outgoing light was exactly 1 in every channel, its level is `LIT_LEVEL`.
        let w = ctx.plan.grid_width as i32;
        let levels = &state.levels_prev;
        match quiet {
            Some(q) => state.level_blocks.update(levels, |y| {
                q.spans_prev
                    .get(y)
                    .map_or(RowSpans::EMPTY.not_one, |r| r.not_one)
            }),
            None => state.level_blocks.update(levels, |_| (0, w)),
        }
    }
}

/// The image: each pixel inside the guard band composited over the background by [`finish`];
/// and the image pixels' alpha (the guard band cropped away).
fn finish_image(plan: &RenderPlan, color: &[f32], alpha: &[f32]) -> (Vec<f32>, Vec<f32>) {
    let w = plan.grid_width as usize;
    let (left, top) = (plan.guard.left as usize, plan.guard.top as usize);
    let (iw, ih) = (plan.width as usize, plan.height as usize);
    let mut image = vec![0.0f32; iw * ih * 3];
    let mut image_alpha = vec![0.0f32; iw * ih];
    image
        .par_chunks_mut(iw * 3)
        .zip(image_alpha.par_chunks_mut(iw))
        .enumerate()
        .for_each(|(y, (row, row_alpha))| {
            let gy = y + top;
            let colors = &color[gy * w * 3..(gy + 1) * w * 3];
            for x in 0..iw {
                let gx = x + left;
                let mut c = [colors[gx], colors[w + gx], colors[2 * w + gx]];
                let a = alpha[gy * w + gx];
                finish(&mut c, a, plan.background);
                row[3 * x..3 * x + 3].copy_from_slice(&c);
                row_alpha[x] = a;
            }
        });
    (image, image_alpha)
}

/// Which image pixels are opaque (alpha exactly 1), tracked between slabs: once every one is,
/// the image is final. An opaque pixel stays opaque and its colour stays the same bits:
/// compositing adds `(1 − 1)·α·c = 0` (α and the shaded colour are finite: scene validation
/// bounds every colour, `MAX_COLOR`), and the image reads only image pixels' colour and alpha.
struct OpaqueImage {
    /// The grid's width: the row stride of the alpha plane.
    grid_width: usize,
    /// The image's first pixel in the grid: (guard band left, guard band top).
    origin: (usize, usize),
    /// The image's width.
    width: usize,
    /// Per image row, how many of its first pixels are known to be opaque.
    known: Vec<usize>,
}

impl OpaqueImage {
    /// Nothing known yet about the image of `plan`.
    fn new(plan: &RenderPlan) -> OpaqueImage {
        let origin = (plan.guard.left as usize, plan.guard.top as usize);
        let (grid_width, width) = (plan.grid_width as usize, plan.width as usize);
        OpaqueImage::of_image(grid_width, origin, width, plan.height as usize)
    }

    /// Nothing known yet about the `width`×`height` image at `origin` of a grid `grid_width` wide.
    fn of_image(grid_width: usize, origin: (usize, usize), width: usize, height: usize) -> Self {
        OpaqueImage {
            grid_width,
            origin,
            width,
            known: vec![0; height],
        }
    }

    /// Whether every image pixel is opaque in `alpha` (the grid's, row-major): each row is read
    /// from its first pixel not yet known to be opaque, so a render reads each pixel about once
    /// plus once per row and slab.
    fn is_final(&mut self, alpha: &[f32]) -> bool {
        let (left, top) = self.origin;
        for (y, known) in self.known.iter_mut().enumerate() {
            if *known == self.width {
                continue;
            }
            let row = &alpha[(top + y) * self.grid_width + left..][..self.width];
            *known += row[*known..].iter().take_while(|&&a| a == 1.0).count();
            if *known < self.width {
                return false;
            }
        }
        // Every row read to its end.
        true
    }
}

/// Runs the sweep on the current rayon pool with the path and knobs chosen in `cpu`.
pub fn sweep_with(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
    cpu: &CpuOptions<'_>,
) -> Result<SweepOutput, SweepError> {
    let (state, slabs_swept) = drive(plan, raster, ldi, options, cpu, |_, _| false)?;
    let (image, alpha) = finish_image(plan, &state.color, &state.alpha);
    Ok(SweepOutput {
        image,
        alpha,
        light: to_plane_rows(plan, &state.prev),
        slabs_swept,
    })
}

/// The sweep for a perspective camera (`eye`): the light swept on the slab grid of `plan`,
/// `raster` and `ldi`, and before each slab the eye's rays take their step through it
/// (`eye::eye_slab`). The image is the eye's, `eye.width × eye.height`. The early finish
/// watches the eye's pixels, not the grid's: once every one is opaque (front to back) the sweep
/// stops, unless `options.every_slab` asks for the grid's light after the last slab.
pub fn sweep_perspective(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    eye: &EyeView<'_>,
    options: &SweepOptions<'_>,
    cpu: &CpuOptions<'_>,
) -> Result<SweepOutput, SweepError> {
    let mut view = EyeState::new(eye);
    let every_slab = SweepOptions {
        every_slab: true,
        ..*options
    };
    let (w, h) = (eye.width as usize, eye.height as usize);
    let mut opaque = OpaqueImage::of_image(w, (0, 0), w, h);
    let (state, slabs_swept) = drive(plan, raster, ldi, &every_slab, cpu, |slab, state| {
        if !options.every_slab && !plan.turned_round && slab > 0 && opaque.is_final(&view.alpha) {
            // No later slab can change an eye pixel's bits (see `OpaqueImage`).
            return true;
        }
        let grid = GridLight {
            light: &state.prev,
            inside: &state.inside,
            ldi,
            next: &state.next,
        };
        eye::eye_slab(
            plan,
            eye,
            &grid,
            slab,
            cpu.path == SweepPath::Simd,
            &mut view,
        );
        false
    })?;
    let n = (eye.width * eye.height) as usize;
    let mut image = vec![0.0f32; n * 3];
    for (k, (c, &a)) in view.color.iter().zip(&view.alpha).enumerate() {
        let mut c = *c;
        finish(&mut c, a, plan.background);
        image[3 * k..3 * k + 3].copy_from_slice(&c);
    }
    Ok(SweepOutput {
        image,
        alpha: view.alpha,
        light: to_plane_rows(plan, &state.prev),
        slabs_swept,
    })
}

/// The slab loop of [`sweep_with`] and [`sweep_perspective`]: `before_slab(k, state)` runs before
/// slab k is swept, and stops the loop there if it returns true. Returns the state after the
/// last slab swept and how many were.
fn drive(
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
    cpu: &CpuOptions<'_>,
    mut before_slab: impl FnMut(u32, &PixelState) -> bool,
) -> Result<(PixelState, u32), SweepError> {
    let ch = plan.channels as usize;
    let lights = plan.lights.len();
    assert!(
        lights * ch <= MAX_LIGHT_CHANNELS,
        "scene validation caps the light count"
    );

    let unlit;
    let initial = match options.initial_light {
        Some(v) => v,
        None => {
            unlit = plan.unlit_light_buffer();
            &unlit
        }
    };
    let mut state = PixelState::new(plan, ldi, initial);
    let reach = Reach::of(plan);
    let mut quiet = QuietState::new(plan, ldi, initial, &reach, cpu);
    // The SIMD path's tap tables by column, for its per-lane gathers.
    let simd = cpu.path == SweepPath::Simd;
    let columns: Vec<TapColumns> = plan
        .lights
        .iter()
        .filter(|_| simd)
        .map(|l| {
            let (row_len, planes) = (plan.light_row_len(), plan.planes_per_light());
            TapColumns::new(&l.table, row_len, planes, plan.level_row_len())
        })
        .collect();

    let taps: Vec<LightTaps> = plan
        .lights
        .iter()
        .map(|l| LightTaps::new(&l.table))
        .collect();
    let mut opaque = OpaqueImage::new(plan);
    let mut held = HeldRecords::new(plan);
    let mut slabs_swept = plan.slabs;
    for slab in 0..plan.slabs {
        if options.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(SweepError::Interrupted);
        }
        held.prepare(slab, (reach.y0, reach.y1));
        let ctx = SlabContext {
            plan,
            raster,
            ldi,
            taps: &taps,
            reach,
            slab,
            back: plan.slab_back[slab as usize],
            front: plan.slab_front[slab as usize],
            next_level_at: level_at(plan, slab + 1),
            held: held.view(),
        };
        if before_slab(slab, &state) {
            slabs_swept = slab;
            (options.progress)(plan.slabs - 1);
            break;
        }
        let lanes = simd.then(|| SimdSlab::new(plan, &columns, slab));
        sweep_slab(
            &ctx,
            lanes.as_ref(),
            cpu.chunk_counts,
            &mut state,
            quiet.as_mut(),
        );
        (options.progress)(slab);
        if !options.every_slab
            && !plan.turned_round
            && slab + 1 < plan.slabs
            && opaque.is_final(&state.alpha)
        {
            // No later slab can change an image bit (see `OpaqueImage`).
            slabs_swept = slab + 1;
            (options.progress)(plan.slabs - 1);
            break;
        }
    }

    Ok((state, slabs_swept))
}

/// Unit tests' scenes: `text` parsed (as the file `name`) and built into what a sweep takes.
#[cfg(test)]
pub(crate) fn built_scene(
    text: &str,
    name: &str,
) -> (
    convshadow_common::model::scene::Scene,
    convshadow_common::prepare::geometry::SceneGeometry,
    Ldi,
    RenderPlan,
) {
    use crate::ldi::BuildLdi;
    let scene =
        convshadow_common::model::scene::Scene::parse(text, name, std::path::Path::new("."))
            .expect("scene");
    let g = convshadow_io::build_geometry(&scene).expect("geometry");
    let ldi = Ldi::build(&g.raster, u64::MAX).expect("ldi");
    let plan = convshadow_io::build_plan(&scene, &g).expect("plan");
    (scene, g, ldi, plan)
}

#[cfg(test)]
mod tests {
    use super::OpaqueImage;

    #[test]
    fn chunk_summaries_stay_current_through_a_sweep() {
        // The row loop checks each summary against `ChunkState::of` before it uses it (in unit
        // tests). A thick hazy box turns its chunks opaque a few slabs past its front face,
        // where no cursor moves (summaries refreshed for their alphas alone); a wall behind it
        // over the image's left half leaves chunks in the dark, the space beside them unoccluded;
        // a thin opaque plate turned 50° is held (surface holds start and release, also where
        // the light around is unoccluded).
        for penumbra in ["iterated", "distance"] {
            let text = format!(
                "[image]\nwidth = 45\nheight = 27\n[camera]\nview_width = 4.0\n[sweep]\n\
                 guard_band = 0\nslabs = 64\noptimal_distance = 0.5\npenumbra = \"{penumbra}\"\n\
                 [[light]]\ntilt_deg = [20.0, 10.0]\nvariance = [0.04, 0.02]\n\
                 [[mesh]]\nshape = \"box\"\nsize = [2.0, 2.0, 2.0]\nmaterial = \"haze\"\n\
                 [[mesh]]\nshape = \"box\"\nsize = [4.0, 6.0, 0.1]\ntranslate = [-2.0, 0.0, 1.5]\n\
                 material = \"wall\"\n[[mesh]]\nshape = \"box\"\nsize = [1.5, 1.5, 0.05]\n\
                 translate = [1.3, 0.0, -2.0]\nrotate_deg = [50.0, 0.0, 0.0]\nmaterial = \"wall\"\n\
                 [material.haze]\nopacity = 0.999\n[material.wall]\nopacity = 1.0\n"
            );
            let (_scene, g, ldi, plan) = super::built_scene(&text, "summaries");
            assert!(plan.has_surface_hold(), "the turned plate is held");
            let counts = super::ChunkCounts::default();
            let cpu = super::CpuOptions {
                chunk_counts: Some(&counts),
                ..super::CpuOptions::default()
            };
            let options = super::SweepOptions {
                every_slab: true,
                ..super::SweepOptions::default()
            };
            super::sweep_with(&plan, &g.raster, &ldi, &options, &cpu).expect("sweep");
            let [full, unoccluded, dark] = counts.snapshot();
            assert!(
                full > 0 && unoccluded > 0 && dark > 0,
                "{penumbra}: chunks {:?}",
                counts.snapshot()
            );
        }
    }

    /// A 6×4 grid with a 3×2 image at (2, 1), every pixel opaque.
    fn opaque_grid() -> (OpaqueImage, Vec<f32>) {
        (OpaqueImage::of_image(6, (2, 1), 3, 2), vec![1.0; 6 * 4])
    }

    #[test]
    fn one_image_pixel_short_of_opaque_keeps_the_image_open() {
        let (mut image, mut alpha) = opaque_grid();
        alpha[2 * 6 + 4] = 1.0 - f32::EPSILON / 2.0; // the image's last pixel: one ulp below 1
        assert!(!image.is_final(&alpha));
        alpha[2 * 6 + 4] = 1.0;
        assert!(image.is_final(&alpha));
    }

    #[test]
    fn guard_band_pixels_do_not_count() {
        let (mut image, mut alpha) = opaque_grid();
        for (i, a) in alpha.iter_mut().enumerate() {
            let (x, y) = (i % 6, i / 6);
            if !(2..5).contains(&x) || !(1..3).contains(&y) {
                *a = 0.0;
            }
        }
        assert!(image.is_final(&alpha));
    }

    #[test]
    fn rows_are_rechecked_from_their_first_open_pixel() {
        let (mut image, mut alpha) = opaque_grid();
        alpha[6 + 3] = 0.5;
        alpha[2 * 6 + 2] = 0.5;
        assert!(!image.is_final(&alpha));
        assert_eq!(image.known, [1, 0]);
        alpha[6 + 3] = 1.0;
        assert!(!image.is_final(&alpha));
        assert_eq!(image.known, [3, 0]);
        alpha[2 * 6 + 2] = 1.0;
        assert!(image.is_final(&alpha));
    }
}
