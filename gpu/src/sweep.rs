//! The slab sweep on the GPU (`shaders/sweep.wgsl` and the stage files it is concatenated with),
//! mirroring `convshadow_cpu::sweep`.
//!
//! Every table the sweep reads comes from the [`RenderPlan`] built on the host (kernel taps,
//! per-slab hashes, phases and shifts, transfer functions, octave tables, detail transforms,
//! slab faces) and is uploaded as it is into one `tables` storage buffer of 32-bit words (floats
//! as their bits): nothing is recomputed on the device. One dispatch per slab, one invocation per
//! grid pixel; the two light buffers ping-pong; the slab index reaches the shader through a small
//! uniform filled by a buffer copy before each dispatch, so many slabs go in one submission.

use convshadow_common::kernel::PhaseMode;
use convshadow_common::ldi::Ldi;
use convshadow_common::noise::{DetailKind, PERLIN4_SCALE};
use convshadow_common::plan::{FLUSH_BELOW, RenderPlan, TF_SIZE};
use convshadow_common::raster::RasterSetup;
use convshadow_common::scene::MAX_MESHES;
use convshadow_common::sweep_io::{MAX_LIGHT_CHANNELS, SweepOptions, SweepOutput};

use crate::buffers::{bind, check_size, pipeline, read_back, uniform, upload, wait, zeroed};
use crate::device::{GpuContext, GpuError};

/// The WGSL source of the sweep: the stage files concatenated (hash, noise, texture3d, kernels,
/// parity, shading, composite, sweep).
pub const SWEEP_WGSL: &str = concat!(
    include_str!("shaders/hash.wgsl"),
    include_str!("shaders/noise.wgsl"),
    include_str!("shaders/texture3d.wgsl"),
    include_str!("shaders/kernels.wgsl"),
    include_str!("shaders/parity.wgsl"),
    include_str!("shaders/shading.wgsl"),
    include_str!("shaders/composite.wgsl"),
    include_str!("shaders/sweep.wgsl"),
);

/// Largest triangle index + 1 (the other 27 bits of the meta word).
pub const MAX_TRIANGLES: usize = 1 << 27;
/// Words per light header and per material header.
const HEADER_WORDS: usize = 16;
/// Slabs encoded per submission (progress and cancel are checked between submissions).
const SLABS_PER_SUBMIT: u32 = 32;
/// The sweep's workgroup edge (`@workgroup_size(8, 8)`).
const TILE: u32 = 8;

/// A word buffer with float pushes.
#[derive(Default)]
struct Words(Vec<u32>);

impl Words {
    fn at(&self) -> u32 {
        self.0.len() as u32
    }
    fn u(&mut self, v: u32) {
        self.0.push(v);
    }
    fn f(&mut self, v: f32) {
        self.0.push(v.to_bits());
    }
    fn fs(&mut self, v: &[f32]) {
        self.0.extend(v.iter().map(|x| x.to_bits()));
    }
}

/// The tables buffer and the `Globals` uniform words (layout: `struct Globals` in sweep.wgsl).
fn build_tables(plan: &RenderPlan, raster: &RasterSetup) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
    let lights = plan.lights.len();
    let ch = plan.channels as usize;
    if lights * ch > MAX_LIGHT_CHANNELS {
        return Err(GpuError::Unsupported(format!(
            "{lights} lights × {ch} channels exceed {MAX_LIGHT_CHANNELS}"
        )));
    }
    if plan.mesh_material.len() > MAX_MESHES {
        return Err(GpuError::Unsupported(format!(
            "{} meshes exceed {MAX_MESHES}",
            plan.mesh_material.len()
        )));
    }
    if raster.triangles.len() > MAX_TRIANGLES {
        return Err(GpuError::Unsupported(format!(
            "{} rasterized triangles exceed {MAX_TRIANGLES}",
            raster.triangles.len()
        )));
    }
    let slabs = plan.slabs as usize;
    let mut t = Words::default();
    let off_slab_front = t.at();
    t.fs(&plan.slab_front);
    let off_slab_back = t.at();
    t.fs(&plan.slab_back);
    let off_jitter_hash = t.at();
    t.0.extend(&plan.jitter_slab_hash);

    // Per light: taps (dx, dy, w0..w3), slab hashes, slab phases, slab shifts.
    let mut light_offsets = Vec::with_capacity(lights);
    for light in &plan.lights {
        let table = &light.table;
        let taps = t.at();
        for tap in &table.taps {
            t.u(tap.dx as u32);
            t.u(tap.dy as u32);
            t.fs(&tap.w);
        }
        let hashes = t.at();
        t.0.extend(&light.slab_hash);
        let phases = t.at();
        for k in 0..slabs {
            t.u(table.slab_phase.get(k).copied().unwrap_or(0));
        }
        let shifts = t.at();
        for k in 0..slabs {
            let s = table.slab_shift.get(k).copied().unwrap_or([0, 0]);
            t.u(s[0] as u32);
            t.u(s[1] as u32);
        }
        light_offsets.push((taps, hashes, phases, shifts));
    }

    // Per material: transfer function (7 words an entry), octave table (frequency, amplitude),
    // texture voxels.
    let mut material_offsets = Vec::with_capacity(plan.materials.len());
    for m in &plan.materials {
        let tf = t.at();
        for e in &m.tf {
            t.fs(&e.color);
            t.f(e.alpha);
            t.fs(&e.attenuation);
        }
        let octaves = t.at();
        if let Some(d) = &m.detail {
            let n = d.octave_frequency.len().min(d.octave_amplitude.len());
            for i in 0..n {
                t.f(d.octave_frequency[i]);
                t.f(d.octave_amplitude[i]);
            }
        }
        let texture = t.at();
        if let Some(tex) = &m.texture {
            t.fs(&tex.voxels);
        }
        material_offsets.push((tf, octaves, texture));
    }

    let off_lights = t.at();
    for (light, &(taps, hashes, phases, shifts)) in plan.lights.iter().zip(&light_offsets) {
        let table = &light.table;
        let start = t.at();
        t.u(taps);
        t.u(table.taps_per_phase);
        t.u(table.phase_bits());
        t.u(match table.phase_mode {
            PhaseMode::PerPixel => 0,
            PhaseMode::PerSlab => 1,
            PhaseMode::Schedule => 2,
        });
        t.u(hashes);
        t.u(phases);
        t.u(shifts);
        t.fs(&light.color);
        t.fs(&light.half_vector);
        while t.at() < start + HEADER_WORDS as u32 {
            t.u(0);
        }
    }
    let off_materials = t.at();
    for (m, &(tf, octaves, texture)) in plan.materials.iter().zip(&material_offsets) {
        let start = t.at();
        t.u(tf);
        t.u(m.tf.len() as u32);
        match &m.detail {
            Some(d) => {
                t.u(match d.kind {
                    DetailKind::Perlin => 1,
                    DetailKind::Fbm => 2,
                    DetailKind::Ridged => 3,
                    DetailKind::Turbulence => 4,
                });
                t.u(d.octave_frequency.len().min(d.octave_amplitude.len()) as u32);
                t.u(octaves);
                t.f(d.inv_amplitude_sum);
                t.u(u32::from(d.time.is_some()));
                t.f(d.time.unwrap_or(0.0));
            }
            None => {
                t.0.extend([0, 0, octaves, 0, 0, 0]);
            }
        }
        match &m.texture {
            Some(tex) => {
                t.u(texture);
                t.0.extend(tex.dims);
                t.u(1);
            }
            None => t.0.extend([texture, 1, 1, 1, 0]),
        }
        match m.specular {
            Some((strength, exponent)) => {
                t.u(1);
                t.f(strength);
                t.u(exponent);
            }
            None => t.0.extend([0, 0, 0]),
        }
        debug_assert_eq!(t.at(), start + HEADER_WORDS as u32);
        // Transfer functions are either constant or TF_SIZE entries (the shader assumes so).
        debug_assert!(m.tf.len() == 1 || m.tf.len() == TF_SIZE);
    }
    let off_mesh_material = t.at();
    t.0.extend(&plan.mesh_material);
    let off_mesh_to_detail = t.at();
    for m in &plan.mesh_to_detail {
        t.fs(m);
    }
    let off_normals = t.at();
    for tri in &raster.triangles {
        t.fs(&tri.normal);
    }

    let globals = vec![
        plan.grid_width,
        plan.grid_height,
        plan.guard,
        plan.width,
        plan.height,
        plan.slabs,
        lights as u32,
        plan.channels,
        u32::from(plan.jitter),
        plan.slab_distance.to_bits(),
        FLUSH_BELOW.to_bits(),
        PERLIN4_SCALE.to_bits(),
        plan.background[0].to_bits(),
        plan.background[1].to_bits(),
        plan.background[2].to_bits(),
        plan.light_row_len() as u32,
        off_slab_front,
        off_slab_back,
        off_jitter_hash,
        off_lights,
        off_materials,
        off_mesh_material,
        off_mesh_to_detail,
        off_normals,
    ];
    Ok((t.0, globals))
}

/// Runs the sweep on the GPU: the same image and final light buffers as
/// `convshadow_cpu::sweep::sweep` (bit for bit on lavapipe; docs/gpu.md lists every source of
/// difference on other adapters).
pub fn sweep(
    ctx: &GpuContext,
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, GpuError> {
    let (w, h) = (plan.grid_width, plan.grid_height);
    let pixels = u64::from(w) * u64::from(h);
    let light_words = plan.light_row_len() as u64 * u64::from(h);
    if light_words >= u64::from(u32::MAX) || pixels * 4 >= u64::from(u32::MAX) {
        return Err(GpuError::Unsupported(format!(
            "a {w}x{h} grid with {} light channels exceeds 32-bit indices",
            plan.light_row_len() / w.max(1) as usize
        )));
    }
    let (tables, globals) = build_tables(plan, raster)?;
    check_size(ctx, "light", light_words * 4)?;
    check_size(ctx, "per-pixel colour", pixels * 16)?;

    let initial: Vec<u32> = match options.initial_light {
        Some(v) => v.iter().map(|x| x.to_bits()).collect(),
        None => vec![1.0f32.to_bits(); light_words as usize],
    };
    let light_a = upload(ctx, "light", &initial, true)?;
    drop(initial);
    let light_b = zeroed(ctx, "light", light_words)?;
    let cursors: Vec<u32> = ldi.offsets[..pixels as usize]
        .iter()
        .flat_map(|&o| [o, 0])
        .collect();
    let cursors = upload(ctx, "layer cursor", &cursors, false)?;
    let accum = zeroed(ctx, "per-pixel colour", pixels * 4)?;
    let offsets = upload(ctx, "LDI offset", &ldi.offsets, false)?;
    let depth: Vec<u32> = ldi.depth.iter().map(|d| d.to_bits()).collect();
    let frag_depth = upload(ctx, "fragment depth", &depth, false)?;
    drop(depth);
    let meta: Vec<u32> = ldi
        .mesh
        .iter()
        .zip(&ldi.triangle)
        .map(|(&m, &t)| u32::from(m) | (t << 5))
        .collect();
    let frag_meta = upload(ctx, "fragment meta", &meta, false)?;
    drop(meta);
    let tables = upload(ctx, "table", &tables, false)?;
    let image_words = u64::from(plan.width) * u64::from(plan.height) * 3;
    let image = zeroed(ctx, "image", image_words)?;
    let globals = uniform(ctx, "globals", &globals);
    let slab_param = uniform(ctx, "slab", &[0, 0, 0, 0]);
    let all_params: Vec<u32> = (0..plan.slabs).flat_map(|k| [k, 0, 0, 0]).collect();
    let all_params = {
        use wgpu::util::DeviceExt;
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("slab params"),
                contents: bytemuck::cast_slice(&all_params),
                usage: wgpu::BufferUsages::COPY_SRC,
            })
    };

    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sweep.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SWEEP_WGSL.into()),
        });
    let slab_pipe = pipeline(ctx, &module, "sweep_slab");
    let finish_pipe = pipeline(ctx, &module, "finish_image");
    let common: [(u32, &wgpu::Buffer); 7] = [
        (0, &slab_param),
        (1, &globals),
        (4, &cursors),
        (5, &accum),
        (6, &offsets),
        (7, &frag_depth),
        (8, &frag_meta),
    ];
    let group_for = |prev: &wgpu::Buffer, cur: &wgpu::Buffer| {
        let mut e: Vec<(u32, &wgpu::Buffer)> = common.to_vec();
        e.push((2, prev));
        e.push((3, cur));
        e.push((9, &tables));
        bind(ctx, &slab_pipe, &e)
    };
    let even = group_for(&light_a, &light_b);
    let odd = group_for(&light_b, &light_a);
    let groups = (w.div_ceil(TILE), h.div_ceil(TILE));

    let mut slab = 0;
    while slab < plan.slabs {
        if options
            .cancel
            .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
        {
            return Err(GpuError::Interrupted);
        }
        let end = (slab + SLABS_PER_SUBMIT).min(plan.slabs);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        for k in slab..end {
            encoder.copy_buffer_to_buffer(&all_params, u64::from(k) * 16, &slab_param, 0, 16);
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("slab"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&slab_pipe);
            pass.set_bind_group(0, if k % 2 == 0 { &even } else { &odd }, &[]);
            pass.dispatch_workgroups(groups.0, groups.1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        wait(ctx)?;
        for k in slab..end {
            (options.progress)(k);
        }
        slab = end;
    }

    let finish_group = bind(
        ctx,
        &finish_pipe,
        &[(1, &globals), (5, &accum), (10, &image)],
    );
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("finish"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&finish_pipe);
        pass.set_bind_group(0, &finish_group, &[]);
        pass.dispatch_workgroups(plan.width.div_ceil(TILE), plan.height.div_ceil(TILE), 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let image = read_back(ctx, &image, image_words)?;
    let last = if plan.slabs % 2 == 1 {
        &light_b
    } else {
        &light_a
    };
    let light = read_back(ctx, last, light_words)?;
    Ok(SweepOutput {
        image: image.into_iter().map(f32::from_bits).collect(),
        light: light.into_iter().map(f32::from_bits).collect(),
    })
}
