//! The per-pixel kit every lane path of the sweep uses: what a slab shares ([`SlabContext`]),
//! what a row's pixels read ([`RowContext`]: the previous slab's buffers, the row hashes), one
//! row's mutable state ([`RowState`]), the light buffer's layout and the gather's reach.

use convshadow_common::pixel::hash::row_hash;
use convshadow_common::pixel::levels::LevelAt;
use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::raster::RasterSetup;

use crate::composite::HeldPlanes;
use crate::kernels::{LevelPlane, LightPlanes, LightTaps, light_row_hash};
use crate::ldi::Ldi;

pub use convshadow_common::contract::sweep_io::MAX_LIGHT_CHANNELS;
pub use convshadow_common::model::scene::MAX_LIGHTS;

/// What every pixel of one slab shares.
pub(crate) struct SlabContext<'a> {
    pub plan: &'a RenderPlan,
    pub raster: &'a RasterSetup,
    pub ldi: &'a Ldi,
    /// Every light's tap rows, as the gather and the level search read them.
    pub taps: &'a [LightTaps],
    /// How far any gather reads from the pixel it writes.
    pub reach: Reach,
    pub slab: u32,
    /// Back face of the slab (the cursor advances past fragments in front of it).
    pub back: f32,
    /// Front face of the slab.
    pub front: f32,
    /// Where the distance penumbra's level search stands for the next slab (`level_at`, once
    /// per slab).
    pub next_level_at: LevelAt,
    /// Every pixel's held-plane records (empty where no surface holds).
    pub held: HeldPlanes<'a>,
}

/// What the previous slab left that a pixel's gather reads beyond its own row: the light
/// buffer and (distance penumbra) the level plane.
#[derive(Clone, Copy)]
pub(crate) struct Previous<'a> {
    pub light: &'a [f32],
    pub levels: &'a [u32],
    /// The level plane's 2×2 block minima (`level_blocks::LevelBlocks`), laid out as `levels`.
    pub level_blocks: &'a [u32],
}

/// One row's mutable per-pixel state. Colours are planar per row: `[R…][G…][B…]`.
pub(crate) struct RowState<'a> {
    pub light: &'a mut [f32],
    /// Distance penumbra: each light's level per pixel for the next slab (`[light][x]`).
    pub levels: &'a mut [u32],
    pub next: &'a mut [u32],
    pub inside: &'a mut [u32],
    pub color: &'a mut [f32],
    pub alpha: &'a mut [f32],
    /// With pre-integration: per pixel the detail value at the slab's front face kept from the
    /// previous slab (NaN: none kept). Without: one unused float.
    pub pre: &'a mut [f32],
    /// With surface holds (`RenderPlan::surface_hold`): per pixel its packed hold
    /// (`crate::composite::hold_step`). Without: one unused 0.
    pub hold: &'a mut [u32],
}

/// What every pixel of one row reads: its slab, the previous slab's buffers, the row's index and
/// its hashes.
pub(crate) struct RowContext<'a> {
    pub ctx: &'a SlabContext<'a>,
    pub prev: &'a Previous<'a>,
    pub y: usize,
    /// Every light's row hash ([`light_row_hashes`]).
    pub light_hashes: [u32; MAX_LIGHT_CHANNELS],
    /// The row's jitter hash ([`jitter_row_hash`]).
    pub jitter_hash: u32,
}

impl<'a> RowContext<'a> {
    /// Row y of the slab `ctx`, reading `prev`.
    pub(crate) fn new(ctx: &'a SlabContext<'a>, prev: &'a Previous<'a>, y: usize) -> Self {
        RowContext {
            ctx,
            prev,
            y,
            light_hashes: light_row_hashes(ctx, y),
            jitter_hash: jitter_row_hash(ctx, y),
        }
    }
}

/// Where light `l`'s pixel (0, 0) starts in a pixel-interleaved light-buffer row (see
/// [`LightPlanes`]): its planes side by side per pixel, `planes_per_light` of them.
#[inline(always)]
pub(crate) fn light_block(plan: &RenderPlan, l: usize) -> usize {
    plan.light_plane(l, 0) * plan.grid_width as usize
}

/// Every plane of light `l` (its channels, then its depth plane if any) in the pixel-interleaved
/// light buffer `light` (every row), as the gather reads them.
#[inline(always)]
pub(crate) fn light_planes<'a>(plan: &RenderPlan, light: &'a [f32], l: usize) -> LightPlanes<'a> {
    let planes = plan.planes_per_light();
    LightPlanes {
        data: light,
        base: light_block(plan, l),
        channels: planes,
        light_channels: plan.channels as usize,
        row_stride: plan.light_row_len(),
        pixel_step: planes,
        plane_step: 1,
        width: plan.grid_width as i32,
        height: plan.grid_height as i32,
    }
}

/// Distance penumbra: light `l`'s level plane of the previous slab, with its block minima.
#[inline(always)]
pub(crate) fn level_plane<'a>(plan: &RenderPlan, prev: &Previous<'a>, l: usize) -> LevelPlane<'a> {
    LevelPlane {
        data: prev.levels,
        blocks: prev.level_blocks,
        base: l * plan.grid_width as usize,
        row_stride: plan.level_row_len(),
        width: plan.grid_width as i32,
        height: plan.grid_height as i32,
    }
}

/// Every light's row hash for row `y` of the slab (the prefix of each per-pixel phase hash).
pub(crate) fn light_row_hashes(ctx: &SlabContext<'_>, y: usize) -> [u32; MAX_LIGHT_CHANNELS] {
    let mut row_hashes = [0u32; MAX_LIGHT_CHANNELS];
    for (l, light) in ctx.plan.lights.iter().enumerate() {
        row_hashes[l] = light_row_hash(
            light.slab_hash[ctx.slab as usize],
            ctx.plan.hash_y(y as u32),
        );
    }
    row_hashes
}

/// The jitter row hash of row `y` of the slab.
pub(crate) fn jitter_row_hash(ctx: &SlabContext<'_>, y: usize) -> u32 {
    row_hash(
        ctx.plan.jitter_slab_hash[ctx.slab as usize],
        ctx.plan.hash_y(y as u32),
    )
}

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

    /// Whether every read of the `lanes` pixels x0.. of row y lies inside the grid.
    #[inline(always)]
    pub(crate) fn interior(&self, x0: usize, lanes: usize, y: usize, w: usize, h: usize) -> bool {
        let (x0, y) = (x0 as i64, y as i64);
        x0 + i64::from(self.x0) >= 0
            && x0 + lanes as i64 - 1 + i64::from(self.x1) < w as i64
            && y + i64::from(self.y0) >= 0
            && y + i64::from(self.y1) < h as i64
    }
}
