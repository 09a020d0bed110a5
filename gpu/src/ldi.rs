//! The layered depth image on the GPU (`shaders/ldi.wgsl`), mirroring the CPU builder
//! (`convshadow_cpu::ldi`).
//!
//! The triangles are the same [`RasterSetup`] the CPU rasterizes (fixed-point vertices, boxes and
//! depth planes computed once on the host) and are uploaded as they are. Passes:
//! 1. `count`: one invocation per (triangle, row) work item; covered pixels are counted with
//!    atomics (integer coverage, exact 64-bit edge functions emulated with 32-bit pairs).
//! 2. prefix sum **on the host** (the counts are read back, summed in u64 and checked against the
//!    memory budget and the adapter's limits before any fragment buffer is allocated).
//! 3. `fill`: the same coverage; each fragment claims a slot with an atomic cursor and stores its
//!    sort key (depth as sortable u32, triangle index).
//! 4. `sort`: per-pixel sort by (depth key, triangle index): one invocation per fragment finds
//!    its pixel (binary search of the offsets) and its rank among the pixel's fragments.
//!
//! The result is read back into the shared [`Ldi`] type, so `ldi_hash`, statistics and the sweep
//! input are the same code on both backends.

use convshadow_common::contract::ldi::{Ldi, check_fragment_storage, from_sortable_bits};
use convshadow_common::prepare::raster::RasterSetup;

use crate::buffers::{bind, check_size, groups_1d, read_back, uniform, upload, zeroed};
use crate::device::{GpuContext, GpuError};
use crate::layout::{LdiParams, Triangle, WorkItem, slot};
use crate::shader::Program;

/// Invocations per workgroup (`@workgroup_size(64)` in the shader).
const WORKGROUP: u32 = 64;

/// The triangles as the shader reads them.
fn triangles(setup: &RasterSetup) -> Vec<Triangle> {
    setup
        .triangles
        .iter()
        .map(|t| Triangle {
            v: t.v,
            bbox: t.bbox,
            depth_ref: t.depth_ref,
            depth_dx: t.depth_dx,
            depth_dy: t.depth_dy,
            mesh: t.mesh,
        })
        .collect()
}

/// One (triangle, row) work item per covered row of each triangle's box.
fn work_items(setup: &RasterSetup) -> Vec<WorkItem> {
    let mut items = Vec::new();
    for (t, tri) in setup.triangles.iter().enumerate() {
        for y in tri.bbox[1]..=tri.bbox[3] {
            items.push(WorkItem {
                triangle: t as u32,
                row: y as u32,
            });
        }
    }
    items
}

/// Runs a 1D pass of `pipeline` over `n` invocations.
fn dispatch(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    n: u32,
) {
    let (x, y) = groups_1d(n.div_ceil(WORKGROUP));
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some("ldi pass"),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.dispatch_workgroups(x, y, 1);
}

/// The uniform parameters of one pass.
fn params(ctx: &GpuContext, items: u32, setup: &RasterSetup) -> wgpu::Buffer {
    let n = items.div_ceil(WORKGROUP);
    let (x, _) = groups_1d(n);
    uniform(
        ctx,
        "ldi params",
        &LdiParams {
            items,
            width: setup.width,
            height: setup.height,
            pixels: setup.width * setup.height,
            stride: x * WORKGROUP,
            perspective: u32::from(setup.perspective_origin.is_some()),
            depth_origin: setup.perspective_origin.unwrap_or(0.0),
            ..LdiParams::default()
        },
    )
}

/// Builds the LDI on the GPU; refuses before allocating fragments if they exceed `budget_bytes`
/// (the CPU builder's rule) or a buffer would exceed the adapter's per-binding limit.
pub fn build_ldi(
    ctx: &GpuContext,
    setup: &RasterSetup,
    budget_bytes: u64,
) -> Result<Ldi, GpuError> {
    let pixels = u64::from(setup.width) * u64::from(setup.height);
    if pixels >= u64::from(u32::MAX) {
        return Err(GpuError::Unsupported(format!(
            "a {}x{} grid has more pixels than 32-bit indices address",
            setup.width, setup.height
        )));
    }
    let tris = upload(ctx, "LDI triangle", &triangles(setup), false)?;
    let item_list = work_items(setup);
    let n_items = item_list.len() as u32;
    let items = upload(ctx, "LDI work item", &item_list, false)?;
    drop(item_list);
    let counts = zeroed(ctx, "LDI count", pixels)?;

    // 1. Counts.
    let count = ctx.pipeline(Program::Ldi, "count");
    let item_params = params(ctx, n_items, setup);
    let group = bind(
        ctx,
        &count,
        &[
            (slot::LDI_PARAMS, &item_params),
            (slot::TRIS, &tris),
            (slot::ITEMS, &items),
            (slot::COUNTS, &counts),
        ],
    );
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    dispatch(&mut encoder, &count, &group, n_items);
    ctx.queue.submit([encoder.finish()]);
    let counts_host = read_back(ctx, &counts, pixels)?;
    drop(counts);

    // 2. Prefix sum on the host, with the CPU builder's budget check.
    let mut offsets = Vec::with_capacity(pixels as usize + 1);
    let mut total: u64 = 0;
    offsets.push(0u32);
    for &c in &counts_host {
        total += u64::from(c);
        offsets.push(total.min(u64::from(u32::MAX)) as u32);
    }
    // The CPU builder's rule: within the budget, and allocatable on the host for the read-back.
    check_fragment_storage(total, budget_bytes).map_err(GpuError::Ldi)?;
    check_size(ctx, "LDI fragment key", total * 4)?;

    // 3. Fill and 4. sort.
    let offsets_buf = upload(ctx, "LDI offset", &offsets, false)?;
    let cursor = upload(ctx, "LDI cursor", &offsets[..pixels as usize], false)?;
    let key_depth = zeroed(ctx, "LDI fragment key", total)?;
    let key_tri = zeroed(ctx, "LDI fragment key", total)?;
    let fill = ctx.pipeline(Program::Ldi, "fill");
    let sort = ctx.pipeline(Program::Ldi, "sort");
    let fill_group = bind(
        ctx,
        &fill,
        &[
            (slot::LDI_PARAMS, &item_params),
            (slot::TRIS, &tris),
            (slot::ITEMS, &items),
            (slot::CURSOR, &cursor),
            (slot::KEY_DEPTH, &key_depth),
            (slot::KEY_TRI, &key_tri),
        ],
    );
    let sorted_depth = zeroed(ctx, "LDI fragment key", total)?;
    let sorted_tri = zeroed(ctx, "LDI fragment key", total)?;
    let fragment_params = params(ctx, total as u32, setup);
    let sort_group = bind(
        ctx,
        &sort,
        &[
            (slot::LDI_PARAMS, &fragment_params),
            (slot::KEY_DEPTH, &key_depth),
            (slot::KEY_TRI, &key_tri),
            (slot::OFFSETS, &offsets_buf),
            (slot::SORTED_DEPTH, &sorted_depth),
            (slot::SORTED_TRI, &sorted_tri),
        ],
    );
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    dispatch(&mut encoder, &fill, &fill_group, n_items);
    dispatch(&mut encoder, &sort, &sort_group, total as u32);
    ctx.queue.submit([encoder.finish()]);
    let depth_keys = read_back(ctx, &sorted_depth, total)?;
    let triangle = read_back(ctx, &sorted_tri, total)?;

    let depth = depth_keys.iter().map(|&k| from_sortable_bits(k)).collect();
    Ok(Ldi::from_sorted(setup, offsets, depth, triangle))
}
