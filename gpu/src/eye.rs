//! The perspective camera's eye pass on the GPU (`shaders/eye.wgsl`), mirroring
//! `convshadow_cpu::sweep::sweep_perspective`: the grid's sweep ([`crate::sweep`]) runs as for an
//! orthographic camera, and before each slab's dispatch one more dispatch takes every image
//! pixel's ray through that slab, reading the light buffer the slab reads.
//!
//! The eye's LDI, layer cursors, colours and triangle normals are bound at the sweep's slots, so
//! the stage files (`parity.wgsl`, `shading.wgsl`, `composite.wgsl`) read them unchanged.

use bytemuck::Zeroable;
use convshadow_common::contract::sweep_io::{EyePoint, EyeView, SweepOptions, SweepOutput};
use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::raster::RasterSetup;

use crate::buffers::{bind, dispatch_once, uniform, upload, zeroed};
use crate::device::{GpuContext, GpuError};
use crate::layout::{EyeParams, PointParams, slot};
use crate::shader::Program;
use crate::sweep::{
    BeforeSlab, GridSweep, TILE, first_cursors, fragment_meta, last_light, read_rgba,
};
use convshadow_common::contract::ldi::Ldi;

/// The eye's device buffers.
struct EyeBuffers {
    params: wgpu::Buffer,
    cursors: wgpu::Buffer,
    accum: wgpu::Buffer,
    offsets: wgpu::Buffer,
    frag_depth: wgpu::Buffer,
    frag_meta: wgpu::Buffer,
    normals: wgpu::Buffer,
    image: wgpu::Buffer,
    image_words: u64,
    point_params: wgpu::Buffer,
    spot_pattern: wgpu::Buffer,
}

/// Uploads the eye's LDI (cursors at each pixel's first fragment, nothing composited) and
/// parameters.
fn eye_buffers(
    ctx: &GpuContext,
    plan: &RenderPlan,
    eye: &EyeView<'_>,
) -> Result<EyeBuffers, GpuError> {
    let pixels = u64::from(eye.width) * u64::from(eye.height);
    if pixels * 4 >= u64::from(u32::MAX) {
        return Err(GpuError::Unsupported(format!(
            "a {}x{} image exceeds 32-bit indices",
            eye.width, eye.height
        )));
    }
    let ldi = eye.ldi;
    let normals: Vec<[f32; 3]> = eye.raster.triangles.iter().map(|t| t.normal).collect();
    let params = EyeParams {
        width: eye.width,
        height: eye.height,
        zoom: eye.zoom,
        scale: eye.scale,
        z_origin: eye.z_origin,
        axis: eye.axis,
        centre: [eye.width as f32 * 0.5, eye.height as f32 * 0.5],
        turned_round: u32::from(eye.turned_round),
        pixel_size: plan.pixel_size as f32,
        ..EyeParams::default()
    };
    let point = eye.point.as_ref().map(point_params);
    let texels = (eye.point.as_ref())
        .and_then(|p| p.shading.pattern.as_ref())
        .map_or(&[0.0f32][..], |p| &p.image.texels[..]);
    Ok(EyeBuffers {
        params: uniform(ctx, "eye params", &params),
        cursors: upload(ctx, "eye layer cursor", &first_cursors(ldi, pixels), false)?,
        accum: zeroed(ctx, "eye per-pixel colour", pixels * 4)?,
        offsets: upload(ctx, "eye LDI offset", &ldi.offsets, false)?,
        frag_depth: upload(ctx, "eye fragment depth", &ldi.depth, false)?,
        frag_meta: upload(ctx, "eye fragment meta", &fragment_meta(ldi), false)?,
        normals: upload(ctx, "eye triangle normal", &normals, false)?,
        image: zeroed(ctx, "image", pixels * 4)?,
        image_words: pixels * 4,
        point_params: uniform(ctx, "point light", &point.unwrap_or_else(Zeroable::zeroed)),
        spot_pattern: upload(ctx, "spot pattern", texels, false)?,
    })
}

/// The eye pass's point-light constants of `p` (`eye.wgsl` `point_terms`).
fn point_params(p: &EyePoint<'_>) -> PointParams {
    let s = p.shading;
    let four = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
    let mut params = PointParams {
        on: 1,
        pixel_size: s.pixel_size,
        center: [s.center[0], s.center[1], s.center[2], s.radius2],
        color: four(s.color),
        offset: p.offset,
        depth: p.depth,
        focal: p.focal,
        frame_axis: p.frame_axis,
        turned: u32::from(s.turned),
        ..Zeroable::zeroed()
    };
    if let Some(c) = &s.cone {
        (params.spot, params.axis) = (1, four(c.axis));
        (params.inner, params.outer) = (c.inner, c.outer);
    }
    if let Some(pt) = &s.pattern {
        params.pattern = 1;
        (params.right, params.down) = (four(pt.right), four(pt.down));
        (params.pattern_size, params.pattern_centre) = (pt.size, pt.center);
        (params.pattern_width, params.pattern_height) = (pt.image.width, pt.image.height);
    }
    for (out, phase) in params.phase.iter_mut().zip(p.phase) {
        *out = [phase[0], phase[1], phase[2], 0.0];
    }
    params
}

/// The eye pass's per-slab dispatch: bind groups `[even, odd]` reading the grid's light buffer
/// of that parity and its cursors.
fn eye_slab_dispatch(
    ctx: &GpuContext,
    run: &GridSweep,
    e: &EyeBuffers,
    eye: &EyeView<'_>,
) -> BeforeSlab {
    let pipe = ctx.pipeline(Program::Eye, "eye_slab");
    let g = &run.buffers;
    let group = |light_prev: &wgpu::Buffer| {
        bind(
            ctx,
            &pipe,
            &[
                (slot::SLAB_PARAMS, &g.slab_param),
                (slot::GLOBALS, &g.globals),
                (slot::EYE_PARAMS, &e.params),
                (slot::CURSORS, &e.cursors),
                (slot::ACCUM, &e.accum),
                (slot::OFFSETS, &e.offsets),
                (slot::FRAG_DEPTH, &e.frag_depth),
                (slot::FRAG_META, &e.frag_meta),
                (slot::NORMALS, &e.normals),
                (slot::SLABS, &g.slabs),
                (slot::LIGHTS, &g.lights),
                (slot::MATERIALS, &g.materials),
                (slot::TF_ENTRIES, &g.tf_entries),
                (slot::OCTAVES, &g.octaves),
                (slot::VOXELS, &g.voxels),
                (slot::MESHES, &g.meshes),
                (slot::LIGHT_COLORS, &g.light_colors),
                // The horizon's Φ table (`Globals::horizon_at`).
                (slot::LEVEL_TABLE, &g.level_table),
                (slot::GRID_CURSORS, &g.cursors),
                (slot::GRID_OFFSETS, &g.offsets),
                (slot::GRID_FRAG_META, &g.frag_meta),
                (slot::LIGHT_PREV, light_prev),
                (slot::POINT_PARAMS, &e.point_params),
                (slot::SPOT_PATTERN, &e.spot_pattern),
            ],
        )
    };
    // Slab k reads light_a when k is even (the sweep's ping-pong).
    let groups = [group(&g.light_a), group(&g.light_b)];
    BeforeSlab {
        pipeline: pipe,
        groups,
        workgroups: (eye.width.div_ceil(TILE), eye.height.div_ceil(TILE)),
    }
}

/// Adds the background to the eye's colours into its RGBA image.
fn dispatch_eye_finish(ctx: &GpuContext, run: &GridSweep, e: &EyeBuffers, eye: &EyeView<'_>) {
    let pipe = ctx.pipeline(Program::Eye, "eye_finish");
    let group = bind(
        ctx,
        &pipe,
        &[
            (slot::GLOBALS, &run.buffers.globals),
            (slot::EYE_PARAMS, &e.params),
            (slot::ACCUM, &e.accum),
            (slot::IMAGE, &e.image),
        ],
    );
    let workgroups = (eye.width.div_ceil(TILE), eye.height.div_ceil(TILE));
    dispatch_once(ctx, "eye finish", &pipe, &group, workgroups);
}

/// Runs the sweep on the grid of `plan` with the eye pass of `eye` before every slab: the same
/// image (the eye's, `eye.width × eye.height`), alpha and final grid light as
/// `convshadow_cpu::sweep::sweep_perspective` (bit for bit on lavapipe).
pub fn sweep_perspective(
    ctx: &GpuContext,
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    eye: &EyeView<'_>,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, GpuError> {
    let run = GridSweep::prepare(ctx, plan, raster, ldi, options)?;
    let buffers = eye_buffers(ctx, plan, eye)?;
    let before = eye_slab_dispatch(ctx, &run, &buffers, eye);
    run.dispatch(ctx, plan, options, Some(&before))?;
    dispatch_eye_finish(ctx, &run, &buffers, eye);
    let (image, alpha) = read_rgba(ctx, &buffers.image, buffers.image_words)?;
    Ok(SweepOutput {
        image,
        alpha,
        light: last_light(ctx, plan, &run.buffers, run.grid.light_words)?,
        slabs_swept: plan.slabs,
    })
}
