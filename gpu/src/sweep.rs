//! The slab sweep on the GPU (`shaders/sweep.wgsl` and the stage files it imports), mirroring
//! `convshadow_cpu::sweep`.
//!
//! Every table the sweep reads comes from the [`RenderPlan`] built on the host (kernel taps,
//! per-slab hashes, phases and shifts, transfer functions, octave tables, detail transforms,
//! slab faces, and for the distance penumbra every level's taps, `level_of` and the per-level
//! slab schedule) and is uploaded as it is, one storage buffer per table, each an array of one of
//! the `layout` structs: nothing is recomputed on the device. One dispatch per slab, one invocation per
//! grid pixel; the two light buffers ping-pong; the slab index reaches the shader through a small
//! uniform filled by a buffer copy before each dispatch, so many slabs go in one submission.

use convshadow_common::contract::ldi::Ldi;
use convshadow_common::contract::sweep_io::{MAX_LIGHT_CHANNELS, SweepOptions, SweepOutput};
use convshadow_common::model::scene::MAX_MESHES;
use convshadow_common::model::scene::{DetailKind, SpecularModel};
use convshadow_common::pixel::noise::PERLIN4_SCALE;
use convshadow_common::pixel::volume::Volume;
use convshadow_common::plan::kernel::PhaseMode;
use convshadow_common::plan::levels::initial_levels;
use convshadow_common::plan::surface_hold::{HELD_WORDS, NO_HELD_SLAB, SERVED_HEAD_WORDS};
use convshadow_common::plan::{
    FLUSH_BELOW, LightPlan, MaterialPlan, OCCLUSION_EPS, RenderPlan, TF_SIZE, TfEntry,
};
use convshadow_common::prepare::raster::RasterSetup;

use crate::buffers::{bind, check_size, dispatch_once, read_back, uniform, upload, wait, zeroed};
use crate::device::{GpuContext, GpuError};
use crate::layout::{
    Cursor, DETAIL_FBM, DETAIL_NONE, DETAIL_PERLIN, DETAIL_RIDGED, DETAIL_TURBULENCE, Globals,
    HORIZON_NONE, LightHeader, LightSlab, MESH_BITS, MaterialHeader, MeshHeader, NO_PRE, Octave,
    PHASE_PER_PIXEL, PHASE_PER_SLAB, PHASE_SCHEDULE, PRE_NONE, SPEC_ASHIKMIN_SHIRLEY,
    SPEC_BLINN_PHONG, Slab, SlabParams, TEXTURE_BRICKED, TEXTURE_DENSE, Tap, TransferEntry, slot,
};
use crate::shader::Program;

/// Largest triangle index + 1 (the bits of a fragment's meta word above the mesh id).
pub const MAX_TRIANGLES: usize = 1 << (32 - MESH_BITS);
/// Slabs encoded per submission (progress and cancel are checked between submissions).
const SLABS_PER_SUBMIT: u32 = 32;
/// The sweep's workgroup edge (`@workgroup_size(8, 8)`).
pub(crate) const TILE: u32 = 8;
/// Storage buffers the `sweep_slab` entry point binds (the two light buffers and every table of
/// [`slab_groups`], and the two level planes); checked against the adapter's per-stage limit before the pipeline is made
/// (lavapipe allows 32), and against the WGSL by a test.
const SWEEP_STORAGE_BUFFERS: u32 = 24;

/// Everything the sweep reads besides the LDI and the light buffers, as the shader's structs.
struct Tables {
    globals: Globals,
    slabs: Vec<Slab>,
    lights: Vec<LightHeader>,
    light_slabs: Vec<LightSlab>,
    taps: Vec<Tap>,
    /// Distance penumbra, per light: `level_of`, then the per-level slab phases.
    level_table: Vec<u32>,
    materials: Vec<MaterialHeader>,
    tf_entries: Vec<TransferEntry>,
    octaves: Vec<Octave>,
    voxels: Vec<f32>,
    meshes: Vec<MeshHeader>,
    normals: Vec<[f32; 3]>,
    /// Per (material, light): the phase-weighted light colour.
    light_colors: Vec<[f32; 3]>,
}

/// Checks the scene against the shader's limits.
fn check_limits(plan: &RenderPlan, raster: &RasterSetup) -> Result<(), GpuError> {
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
    Ok(())
}

/// Checks a light's level tables (distance penumbra) against what the shader indexes: `level_of`
/// covers every distance 1..=slabs with a level below `levels`, and a schedule has a phase
/// below `phase_count` per level and slab. A malformed plan is refused, not read out of bounds.
fn check_levels(l: usize, light: &LightPlan, slabs: usize) -> Result<(), GpuError> {
    let t = &light.table;
    let bad = |what: String| {
        Err(GpuError::Unsupported(format!(
            "light {l}: the distance penumbra's kernel table {what}"
        )))
    };
    if t.level_of.len() < 2 || t.level_of.len() > slabs + 1 {
        return bad(format!(
            "has {} level_of entries, expected 2..={}",
            t.level_of.len(),
            slabs + 1
        ));
    }
    if let Some(v) = t.level_of.iter().find(|&&v| v >= t.levels) {
        return bad(format!("maps a distance to level {v} of {}", t.levels));
    }
    if t.taps.len() != (t.rows() * t.taps_per_phase) as usize {
        return bad(format!(
            "has {} taps, expected {} rows × {}",
            t.taps.len(),
            t.rows(),
            t.taps_per_phase
        ));
    }
    if t.phase_mode == PhaseMode::Schedule
        && (t.slab_phase.len() != t.levels as usize * slabs
            || t.slab_phase.iter().any(|&p| p >= t.phase_count))
    {
        return bad(format!(
            "has a schedule of {} phases, expected {} levels × {slabs} slabs below {}",
            t.slab_phase.len(),
            t.levels,
            t.phase_count
        ));
    }
    Ok(())
}

/// One light's header, appending its taps (every level's rows), per-slab values and, for the
/// distance penumbra, its level tables.
fn light_tables(light: &LightPlan, slabs: usize, distance: bool, t: &mut Tables) -> LightHeader {
    let table = &light.table;
    let level_of = t.level_table.len() as u32;
    if distance {
        t.level_table.extend_from_slice(&table.level_of);
    }
    let level_phases = t.level_table.len() as u32;
    if distance && table.phase_mode == PhaseMode::Schedule {
        t.level_table.extend_from_slice(&table.slab_phase);
    }
    let header = LightHeader {
        taps: t.taps.len() as u32,
        taps_per_phase: table.taps_per_phase,
        phase_count: table.phase_count,
        level_of,
        level_top: table.level_of.len().saturating_sub(1) as u32,
        level_phases,
        phase_bits: table.phase_bits(),
        phase_mode: match table.phase_mode {
            PhaseMode::PerPixel => PHASE_PER_PIXEL,
            PhaseMode::PerSlab => PHASE_PER_SLAB,
            PhaseMode::Schedule => PHASE_SCHEDULE,
        },
        color: light.color,
        half_vector: light.half_vector,
        to_light: light.to_light,
        fresnel: light.fresnel,
        drift: light.drift,
        spread: light.spread,
        plain: u32::from(light.plain),
    };
    t.taps.extend(table.taps.iter().map(|tap| Tap {
        dx: tap.dx,
        dy: tap.dy,
        w: tap.w,
    }));
    t.light_slabs.extend((0..slabs).map(|k| LightSlab {
        hash: light.slab_hash.get(k).copied().unwrap_or(0),
        phase: table.slab_phase.get(k).copied().unwrap_or(0),
        shift: table.slab_shift.get(k).copied().unwrap_or([0, 0]),
        residual: light.carry_residual.get(k).copied().unwrap_or([0.0; 2]),
    }));
    header
}

/// One material's header, appending its transfer function, octaves and texture voxels (unless
/// `shared`, an earlier material's header with the same texture, has them).
fn material_tables(
    m: &MaterialPlan,
    shared: Option<MaterialHeader>,
    t: &mut Tables,
) -> MaterialHeader {
    // Transfer functions are either constant or TF_SIZE entries (the shader assumes so).
    debug_assert!(m.tf.len() == 1 || m.tf.len() == TF_SIZE);
    let mut header = MaterialHeader {
        tf: t.tf_entries.len() as u32,
        tf_len: m.tf.len() as u32,
        detail_kind: DETAIL_NONE,
        octaves: t.octaves.len() as u32,
        texture: t.voxels.len() as u32,
        dims: [1, 1, 1],
        pre: NO_PRE,
        ..MaterialHeader::default()
    };
    let entry = |e: &TfEntry| TransferEntry {
        color: e.color,
        alpha: e.alpha,
        attenuation: e.attenuation,
    };
    t.tf_entries.extend(m.tf.iter().map(entry));
    if let Some(pre) = &m.pre {
        // The pre-integration table follows the transfer function in the same buffer.
        header.pre = t.tf_entries.len() as u32;
        t.tf_entries.extend(pre.iter().map(entry));
    }
    if let Some(d) = &m.detail {
        let n = d.octave_frequency.len().min(d.octave_amplitude.len());
        t.octaves.extend((0..n).map(|i| Octave {
            frequency: d.octave_frequency[i],
            amplitude: d.octave_amplitude[i],
        }));
        header.detail_kind = match d.kind {
            DetailKind::Perlin => DETAIL_PERLIN,
            DetailKind::Fbm => DETAIL_FBM,
            DetailKind::Ridged => DETAIL_RIDGED,
            DetailKind::Turbulence => DETAIL_TURBULENCE,
        };
        header.octave_count = n as u32;
        header.inv_amplitude_sum = d.inv_amplitude_sum;
        header.animated = u32::from(d.time.is_some());
        header.time = d.time.unwrap_or(0.0);
    }
    match m.texture.as_deref() {
        Some(_) if shared.is_some() => {
            let s = shared.unwrap_or_default();
            (header.texture, header.pool, header.dims) = (s.texture, s.pool, s.dims);
            (header.bricks, header.has_texture) = (s.bricks, s.has_texture);
        }
        Some(Volume::Dense(tex)) => {
            t.voxels.extend_from_slice(&tex.voxels);
            header.dims = tex.dims;
            header.has_texture = TEXTURE_DENSE;
        }
        Some(Volume::Bricked(b)) => {
            // The index table as exact f32 integers (slots < 2^23), then the pool.
            t.voxels.extend(b.table.iter().map(|&s| s as f32));
            header.pool = t.voxels.len() as u32;
            t.voxels.extend_from_slice(&b.pool);
            header.dims = b.dims;
            header.bricks = b.bricks;
            header.has_texture = TEXTURE_BRICKED;
        }
        None => {}
    }
    if let Some(sp) = m.specular {
        header.has_specular = match sp.model {
            SpecularModel::BlinnPhong => SPEC_BLINN_PHONG,
            SpecularModel::AshikminShirley { .. } => SPEC_ASHIKMIN_SHIRLEY,
        };
        header.spec_strength = sp.scale;
        header.spec_exponent = sp.exponent;
        header.spec_f0 = sp.f0;
    }
    header.lambert = u32::from(m.lambert);
    header
}

/// All the sweep's tables from the plan (nothing is recomputed on the device).
fn build_tables(plan: &RenderPlan, raster: &RasterSetup) -> Result<Tables, GpuError> {
    check_limits(plan, raster)?;
    let slabs = plan.slabs as usize;
    let mut t = Tables {
        globals: Globals {
            grid_w: plan.grid_width,
            grid_h: plan.grid_height,
            guard_left: plan.guard.left,
            width: plan.width,
            height: plan.height,
            slabs: plan.slabs,
            lights: plan.lights.len() as u32,
            channels: plan.channels,
            jitter: u32::from(plan.jitter),
            slab_distance: plan.slab_distance,
            flush_below: FLUSH_BELOW,
            perlin4_scale: PERLIN4_SCALE,
            bg_r: plan.background[0],
            bg_g: plan.background[1],
            bg_b: plan.background[2],
            row_len: plan.light_row_len() as u32,
            guard_top: plan.guard.top,
            planes: plan.planes_per_light() as u32,
            depth_planes: plan.depth_planes() as u32,
            occlusion_eps: OCCLUSION_EPS,
            preintegration: u32::from(plan.preintegration),
            surface_holds: u32::from(plan.has_surface_hold()),
            held_lit_side: u32::from(plan.has_surface_hold() && plan.held_lit_side),
            parity_meshes: raster.parity_meshes,
            inv_slab_distance: plan.inv_slab_distance,
            second_order_media: u32::from(plan.second_order_media),
            subpixel_shadows: u32::from(!plan.subpixel_meshes.is_empty()),
            back_to_front: u32::from(plan.turned_round),
            horizon_at: HORIZON_NONE,
            hold_stride: hold_stride(plan) as u32,
            ..Globals::default()
        },
        slabs: (0..slabs)
            .map(|k| Slab {
                front: plan.slab_front[k],
                back: plan.slab_back[k],
                jitter_hash: plan.jitter_slab_hash.get(k).copied().unwrap_or(0),
            })
            .collect(),
        lights: Vec::with_capacity(plan.lights.len()),
        light_slabs: Vec::new(),
        taps: Vec::new(),
        level_table: Vec::new(),
        materials: Vec::with_capacity(plan.materials.len()),
        tf_entries: Vec::new(),
        octaves: Vec::new(),
        voxels: Vec::new(),
        meshes: plan
            .mesh_to_detail
            .iter()
            .zip(&plan.mesh_material)
            .enumerate()
            .map(|(m, (&to_detail, &material))| MeshHeader {
                to_detail,
                material,
                subpixel: u32::from(plan.subpixel_meshes.get(m).copied().unwrap_or(false)),
            })
            .collect(),
        normals: raster.triangles.iter().map(|tri| tri.normal).collect(),
        light_colors: plan
            .materials
            .iter()
            .flat_map(|m| m.light_color.iter().copied())
            .collect(),
    };
    let distance = plan.depth_planes() > 0;
    for (l, light) in plan.lights.iter().enumerate() {
        if distance {
            check_levels(l, light, slabs)?;
        }
        let header = light_tables(light, slabs, distance, &mut t);
        t.lights.push(header);
    }
    point_grid_tables(plan, &mut t);
    horizon_tables(plan, &mut t);
    for (i, m) in plan.materials.iter().enumerate() {
        // A material sharing an earlier one's texture (an open mesh's shell variant) reads the
        // voxels already uploaded.
        let shared = m.texture.as_ref().and_then(|tex| {
            plan.materials[..i].iter().position(|o| {
                o.texture
                    .as_ref()
                    .is_some_and(|ot| std::sync::Arc::ptr_eq(ot, tex))
            })
        });
        let header = material_tables(m, shared.map(|j| t.materials[j]), &mut t);
        t.materials.push(header);
    }
    Ok(t)
}

/// A point light's grid (`src/pipeline/point.rs` `on_point_grid`): its projective material
/// map into the globals and a soft light's ψ per slab coordinate after the level tables.
/// The horizon's Φ table in `level_table` (f32 bits), where the plan has one.
fn horizon_tables(plan: &RenderPlan, t: &mut Tables) {
    if !plan.horizon.is_empty() {
        t.globals.horizon_at = t.level_table.len() as u32;
        t.level_table
            .extend(plan.horizon.iter().map(|v| v.to_bits()));
    }
}

fn point_grid_tables(plan: &RenderPlan, t: &mut Tables) {
    if let Some(p) = &plan.projective {
        let g = &mut t.globals;
        g.projective = 1;
        g.projective_centre = p.centre;
        g.projective_depth_origin = p.depth_origin;
        g.projective_per_depth = p.per_depth;
    }
    if let Some(scale) = &plan.depth_scale {
        t.globals.depth_scaled = 1;
        t.globals.psi_at = t.level_table.len() as u32;
        t.globals.psi_last = (scale.psi.len() - 2) as u32;
        t.level_table.extend(scale.psi.iter().map(|v| v.to_bits()));
    }
}

/// The grid's pixel and light-word counts, refused where they exceed 32-bit indices.
pub(crate) struct GridSize {
    w: u32,
    h: u32,
    pixels: u64,
    pub(crate) light_words: u64,
}

/// Sizes the grid of `plan`, refusing one whose indices do not fit in 32 bits.
fn grid_size(plan: &RenderPlan) -> Result<GridSize, GpuError> {
    let (w, h) = (plan.grid_width, plan.grid_height);
    let pixels = u64::from(w) * u64::from(h);
    let light_words = plan.light_row_len() as u64 * u64::from(h);
    if light_words >= u64::from(u32::MAX) || pixels * 4 >= u64::from(u32::MAX) {
        return Err(GpuError::Unsupported(format!(
            "a {w}x{h} grid with {} light channels exceeds 32-bit indices",
            plan.light_row_len() / w.max(1) as usize
        )));
    }
    Ok(GridSize {
        w,
        h,
        pixels,
        light_words,
    })
}

/// Every device buffer the sweep binds or copies from.
pub(crate) struct SweepBuffers {
    pub(crate) light_a: wgpu::Buffer,
    pub(crate) light_b: wgpu::Buffer,
    level_a: wgpu::Buffer,
    level_b: wgpu::Buffer,
    pub(crate) cursors: wgpu::Buffer,
    accum: wgpu::Buffer,
    pub(crate) offsets: wgpu::Buffer,
    frag_depth: wgpu::Buffer,
    pub(crate) frag_meta: wgpu::Buffer,
    pub(crate) slabs: wgpu::Buffer,
    pub(crate) lights: wgpu::Buffer,
    light_slabs: wgpu::Buffer,
    taps: wgpu::Buffer,
    pub(crate) level_table: wgpu::Buffer,
    pub(crate) materials: wgpu::Buffer,
    pub(crate) tf_entries: wgpu::Buffer,
    pub(crate) octaves: wgpu::Buffer,
    pub(crate) voxels: wgpu::Buffer,
    pub(crate) meshes: wgpu::Buffer,
    normals: wgpu::Buffer,
    pub(crate) light_colors: wgpu::Buffer,
    pre_front: wgpu::Buffer,
    hold: wgpu::Buffer,
    surface_hold: wgpu::Buffer,
    image: wgpu::Buffer,
    image_words: u64,
    pub(crate) globals: wgpu::Buffer,
    pub(crate) slab_param: wgpu::Buffer,
    all_params: wgpu::Buffer,
}

/// Each of the first `pixels` pixels' layer cursor before the first slab: at its first fragment,
/// inside nothing.
pub(crate) fn first_cursors(ldi: &Ldi, pixels: u64) -> Vec<Cursor> {
    ldi.offsets[..pixels as usize]
        .iter()
        .map(|&o| Cursor { next: o, inside: 0 })
        .collect()
}

/// Every fragment's meta word, `mesh | triangle << MESH_BITS`.
pub(crate) fn fragment_meta(ldi: &Ldi) -> Vec<u32> {
    ldi.mesh
        .iter()
        .zip(&ldi.triangle)
        .map(|(&m, &t)| u32::from(m) | (t << MESH_BITS))
        .collect()
}

/// Uploads the light, LDI and plan tables and creates the image and uniform buffers.
fn upload_buffers(
    ctx: &GpuContext,
    plan: &RenderPlan,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
    tables: &Tables,
    grid: &GridSize,
) -> Result<SweepBuffers, GpuError> {
    let (pixels, light_words) = (grid.pixels, grid.light_words);
    // Light 1 and, with the distance penumbra, occluder depth 0 (as the CPU starts).
    let unlit;
    let initial_light = match options.initial_light {
        Some(v) => v,
        None => {
            unlit = plan.unlit_light_buffer();
            &unlit[..]
        }
    };
    let levels = initial_levels(plan, initial_light);
    let initial: Vec<u32> = initial_light.iter().map(|x| x.to_bits()).collect();
    let light_a = upload(ctx, "light", &initial, true)?;
    drop(initial);
    let light_b = zeroed(ctx, "light", light_words)?;
    let level_a = upload(ctx, "level plane", &levels, false)?;
    let level_b = zeroed(ctx, "level plane", levels.len() as u64)?;
    drop(levels);
    let cursors = upload(ctx, "layer cursor", &first_cursors(ldi, pixels), false)?;
    let accum = zeroed(ctx, "per-pixel colour", pixels * 4)?;
    let offsets = upload(ctx, "LDI offset", &ldi.offsets, false)?;
    let frag_depth = upload(ctx, "fragment depth", &ldi.depth, false)?;
    let frag_meta = upload(ctx, "fragment meta", &fragment_meta(ldi), false)?;
    let slabs = upload(ctx, "slab", &tables.slabs, false)?;
    let lights = upload(ctx, "light header", &tables.lights, false)?;
    let light_slabs = upload(ctx, "light slab", &tables.light_slabs, false)?;
    let taps = upload(ctx, "kernel tap", &tables.taps, false)?;
    let level_table = upload(ctx, "kernel level table", &tables.level_table, false)?;
    let materials = upload(ctx, "material header", &tables.materials, false)?;
    let tf_entries = upload(ctx, "transfer function", &tables.tf_entries, false)?;
    let octaves = upload(ctx, "octave", &tables.octaves, false)?;
    let voxels = upload(ctx, "texture voxel", &tables.voxels, false)?;
    let meshes = upload(ctx, "mesh header", &tables.meshes, false)?;
    let normals = upload(ctx, "triangle normal", &tables.normals, false)?;
    let light_colors = upload(ctx, "phase light colour", &tables.light_colors, false)?;
    // One word per grid pixel with pre-integration (none kept yet), else one unused word.
    let pre_words = if plan.preintegration { pixels } else { 1 };
    let pre_front = upload(
        ctx,
        "pre-integration front value",
        &vec![PRE_NONE; pre_words as usize],
        false,
    )?;
    // Surface holds: per grid pixel its hold state (none held yet), its held-plane record (every
    // slot empty) and its two served releases (none yet: `NO_HELD_SLAB` heads), and per triangle
    // its word and depth slopes; else one word each.
    let hold_words: Vec<u32> = if plan.has_surface_hold() {
        let served = hold_stride(plan) - 1 - HELD_WORDS;
        let slot = (served / 2).max(1);
        (0..pixels as usize)
            .flat_map(|_| {
                let words = std::iter::once(0).chain([NO_HELD_SLAB; HELD_WORDS]);
                words.chain((0..served).map(move |i| if i % slot == 0 { NO_HELD_SLAB } else { 0 }))
            })
            .collect()
    } else {
        vec![0]
    };
    let hold = upload(ctx, "surface hold", &hold_words, false)?;
    let per_triangle: Vec<u32> = if plan.has_surface_hold() {
        (plan.surface_hold.iter().zip(&plan.hold_slopes))
            .flat_map(|(&word, g)| [word, g[0].to_bits(), g[1].to_bits()])
            .collect()
    } else {
        vec![0]
    };
    let surface_hold = upload(ctx, "triangle surface hold", &per_triangle, false)?;
    // RGBA per image pixel: the RGB image and the composited alpha (`SweepOutput::alpha`).
    let image_words = u64::from(plan.width) * u64::from(plan.height) * 4;
    let image = zeroed(ctx, "image", image_words)?;
    let globals = uniform(ctx, "globals", &tables.globals);
    let slab_param = uniform(ctx, "slab", &SlabParams::default());
    let all_params = slab_params_buffer(ctx, plan.slabs);
    Ok(SweepBuffers {
        light_a,
        light_b,
        level_a,
        level_b,
        cursors,
        accum,
        offsets,
        frag_depth,
        frag_meta,
        slabs,
        lights,
        light_slabs,
        taps,
        level_table,
        materials,
        tf_entries,
        octaves,
        voxels,
        meshes,
        normals,
        light_colors,
        pre_front,
        hold,
        surface_hold,
        image,
        image_words,
        globals,
        slab_param,
        all_params,
    })
}

/// Every slab's [`SlabParams`] in one copy-source buffer, copied into the uniform per dispatch.
fn slab_params_buffer(ctx: &GpuContext, slabs: u32) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    let all_params: Vec<SlabParams> = (0..slabs)
        .map(|slab| SlabParams {
            slab,
            ..SlabParams::default()
        })
        .collect();
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("slab params"),
            contents: bytemuck::cast_slice(&all_params),
            usage: wgpu::BufferUsages::COPY_SRC,
        })
}

/// The per-slab bind groups, `[even, odd]`: each reads one light buffer and level plane and
/// writes the other.
fn slab_groups(
    ctx: &GpuContext,
    slab_pipe: &wgpu::ComputePipeline,
    b: &SweepBuffers,
) -> [wgpu::BindGroup; 2] {
    let common: [(u32, &wgpu::Buffer); 22] = [
        (slot::SLAB_PARAMS, &b.slab_param),
        (slot::GLOBALS, &b.globals),
        (slot::CURSORS, &b.cursors),
        (slot::ACCUM, &b.accum),
        (slot::OFFSETS, &b.offsets),
        (slot::FRAG_DEPTH, &b.frag_depth),
        (slot::FRAG_META, &b.frag_meta),
        (slot::SLABS, &b.slabs),
        (slot::LIGHTS, &b.lights),
        (slot::LIGHT_SLABS, &b.light_slabs),
        (slot::TAPS, &b.taps),
        (slot::LEVEL_TABLE, &b.level_table),
        (slot::MATERIALS, &b.materials),
        (slot::TF_ENTRIES, &b.tf_entries),
        (slot::OCTAVES, &b.octaves),
        (slot::VOXELS, &b.voxels),
        (slot::MESHES, &b.meshes),
        (slot::NORMALS, &b.normals),
        (slot::LIGHT_COLORS, &b.light_colors),
        (slot::PRE_FRONT, &b.pre_front),
        (slot::HOLD, &b.hold),
        (slot::SURFACE_HOLD, &b.surface_hold),
    ];
    let group_for = |prev: [&wgpu::Buffer; 2], cur: [&wgpu::Buffer; 2]| {
        let mut e: Vec<(u32, &wgpu::Buffer)> = common.to_vec();
        e.push((slot::LIGHT_PREV, prev[0]));
        e.push((slot::LIGHT_CUR, cur[0]));
        e.push((slot::LEVEL_PREV, prev[1]));
        e.push((slot::LEVEL_CUR, cur[1]));
        bind(ctx, slab_pipe, &e)
    };
    let even = group_for([&b.light_a, &b.level_a], [&b.light_b, &b.level_b]);
    let odd = group_for([&b.light_b, &b.level_b], [&b.light_a, &b.level_a]);
    [even, odd]
}

/// A dispatch run before each slab's (the perspective camera's eye pass), in the same order as
/// the CPU's `before_slab`: its bind groups `[even, odd]` read the light buffer that slab reads.
pub(crate) struct BeforeSlab {
    pub(crate) pipeline: wgpu::ComputePipeline,
    pub(crate) groups: [wgpu::BindGroup; 2],
    pub(crate) workgroups: (u32, u32),
}

/// Dispatches every slab, [`SLABS_PER_SUBMIT`] per submission, checking cancel before each
/// submission and reporting progress after it.
fn dispatch_slabs(
    ctx: &GpuContext,
    plan: &RenderPlan,
    options: &SweepOptions<'_>,
    run: &GridSweep,
    before_slab: Option<&BeforeSlab>,
) -> Result<(), GpuError> {
    let (b, slab_pipe) = (&run.buffers, &run.slab_pipe);
    let [even, odd] = &run.groups;
    let workgroups = (run.grid.w.div_ceil(TILE), run.grid.h.div_ceil(TILE));
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
            let size = std::mem::size_of::<SlabParams>() as u64;
            encoder.copy_buffer_to_buffer(
                &b.all_params,
                u64::from(k) * size,
                &b.slab_param,
                0,
                size,
            );
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("slab"),
                timestamp_writes: None,
            });
            if let Some(before) = before_slab {
                pass.set_pipeline(&before.pipeline);
                pass.set_bind_group(0, &before.groups[k as usize % 2], &[]);
                pass.dispatch_workgroups(before.workgroups.0, before.workgroups.1, 1);
            }
            pass.set_pipeline(slab_pipe);
            pass.set_bind_group(0, if k % 2 == 0 { even } else { odd }, &[]);
            pass.dispatch_workgroups(workgroups.0, workgroups.1, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        wait(ctx)?;
        for k in slab..end {
            (options.progress)(k);
        }
        slab = end;
    }
    Ok(())
}

/// Submits the pass that turns the accumulated per-pixel colour into the image.
fn dispatch_finish(
    ctx: &GpuContext,
    plan: &RenderPlan,
    b: &SweepBuffers,
    finish_pipe: &wgpu::ComputePipeline,
) {
    let finish_group = bind(
        ctx,
        finish_pipe,
        &[
            (slot::GLOBALS, &b.globals),
            (slot::ACCUM, &b.accum),
            (slot::IMAGE, &b.image),
        ],
    );
    let workgroups = (plan.width.div_ceil(TILE), plan.height.div_ceil(TILE));
    dispatch_once(ctx, "finish", finish_pipe, &finish_group, workgroups);
}

/// Reads back an RGBA f32 image as its RGB image and its alpha.
pub(crate) fn read_rgba(
    ctx: &GpuContext,
    rgba: &wgpu::Buffer,
    words: u64,
) -> Result<(Vec<f32>, Vec<f32>), GpuError> {
    let rgba = read_back(ctx, rgba, words)?;
    let image = rgba
        .chunks_exact(4)
        .flat_map(|p| p[..3].iter().map(|&v| f32::from_bits(v)))
        .collect();
    let alpha = rgba.chunks_exact(4).map(|p| f32::from_bits(p[3])).collect();
    Ok((image, alpha))
}

/// Reads back the light buffer the last slab wrote, as floats.
pub(crate) fn last_light(
    ctx: &GpuContext,
    plan: &RenderPlan,
    b: &SweepBuffers,
    light_words: u64,
) -> Result<Vec<f32>, GpuError> {
    let last = if plan.slabs % 2 == 1 {
        &b.light_b
    } else {
        &b.light_a
    };
    Ok(read_back(ctx, last, light_words)?
        .into_iter()
        .map(f32::from_bits)
        .collect())
}

/// Reads back the image, its alpha and the last slab's light buffer as floats.
fn read_output(
    ctx: &GpuContext,
    plan: &RenderPlan,
    b: &SweepBuffers,
    light_words: u64,
) -> Result<SweepOutput, GpuError> {
    let (image, alpha) = read_rgba(ctx, &b.image, b.image_words)?;
    Ok(SweepOutput {
        image,
        alpha,
        light: last_light(ctx, plan, b, light_words)?,
        // The GPU sweeps every slab (`SweepOptions::every_slab` permits, never asks, an early
        // finish): its image is the CPU's either way.
        slabs_swept: plan.slabs,
    })
}

/// Runs the sweep on the GPU, every slab: the same image as `convshadow_cpu::sweep::sweep`, and
/// the same final light buffers as the CPU sweep run with `SweepOptions::every_slab` (bit for
/// bit on lavapipe; docs/gpu.md lists every source of difference on other adapters).
pub fn sweep(
    ctx: &GpuContext,
    plan: &RenderPlan,
    raster: &RasterSetup,
    ldi: &Ldi,
    options: &SweepOptions<'_>,
) -> Result<SweepOutput, GpuError> {
    let run = GridSweep::prepare(ctx, plan, raster, ldi, options)?;
    run.dispatch(ctx, plan, options, None)?;
    dispatch_finish(ctx, plan, &run.buffers, &run.finish_pipe);
    read_output(ctx, plan, &run.buffers, run.grid.light_words)
}

/// The grid's sweep made ready on the device: its buffers (tables uploaded), pipelines and
/// per-slab bind groups.
pub(crate) struct GridSweep {
    pub(crate) grid: GridSize,
    pub(crate) buffers: SweepBuffers,
    slab_pipe: wgpu::ComputePipeline,
    finish_pipe: wgpu::ComputePipeline,
    groups: [wgpu::BindGroup; 2],
}

impl GridSweep {
    /// Checks the plan against the adapter, uploads everything and makes the pipelines.
    pub(crate) fn prepare(
        ctx: &GpuContext,
        plan: &RenderPlan,
        raster: &RasterSetup,
        ldi: &Ldi,
        options: &SweepOptions<'_>,
    ) -> Result<GridSweep, GpuError> {
        let grid = grid_size(plan)?;
        let tables = build_tables(plan, raster)?;
        let per_stage = ctx.limits.max_storage_buffers_per_shader_stage;
        if per_stage < SWEEP_STORAGE_BUFFERS {
            return Err(GpuError::Unsupported(format!(
                "the sweep binds {SWEEP_STORAGE_BUFFERS} storage buffers, the adapter allows \
                 {per_stage} per shader stage"
            )));
        }
        check_size(ctx, "light", grid.light_words * 4)?;
        check_size(ctx, "per-pixel colour", grid.pixels * 16)?;
        let buffers = upload_buffers(ctx, plan, ldi, options, &tables, &grid)?;
        let slab_pipe = ctx.pipeline(Program::Sweep, "sweep_slab");
        let finish_pipe = ctx.pipeline(Program::Sweep, "finish_image");
        let groups = slab_groups(ctx, &slab_pipe, &buffers);
        Ok(GridSweep {
            grid,
            buffers,
            slab_pipe,
            finish_pipe,
            groups,
        })
    }

    /// Sweeps every slab, `before_slab` dispatched before each.
    pub(crate) fn dispatch(
        &self,
        ctx: &GpuContext,
        plan: &RenderPlan,
        options: &SweepOptions<'_>,
        before_slab: Option<&BeforeSlab>,
    ) -> Result<(), GpuError> {
        dispatch_slabs(ctx, plan, options, self, before_slab)
    }
}

/// Words per grid pixel of the `hold` buffer where some surface is held (`Globals::hold_stride`):
/// the hold state, the held-plane record and two served releases.
fn hold_stride(plan: &RenderPlan) -> usize {
    let served = if plan.served_releases {
        2 * (SERVED_HEAD_WORDS + 4 * plan.lights.len())
    } else {
        0
    };
    1 + HELD_WORDS + served
}

#[cfg(test)]
mod tests;
