//! The memory budget (`RenderRequest::memory_budget`; the CLI's `--max-memory`, by default half
//! the machine's memory): a render that needs more is refused, with the numbers, before it
//! allocates what the budget cannot hold, never aborted by the allocator. The pipeline checks
//! four times, each time as soon as the size is known:
//!
//! 1. before the backend opens, the scene's per-pixel need ([`MemoryNeed`]: LDI arrays, light
//!    buffers, sweep state, output, input files, and on the GPU its device buffers), counted
//!    with the narrowest guard band the scene can resolve to ([`open_within_budget`]: a named
//!    backend is checked before it opens, so a refusal costs no adapter start-up; `auto` after,
//!    as what it opened);
//! 2. once the geometry has resolved the band, the same need again ([`MemoryNeed::check`]);
//!    what it leaves is the LDI's fragment budget (halved on the GPU, which holds the fragments
//!    on the host and on the device);
//! 3. while the LDI is built, its fragments against that budget (`Ldi::build`, an `LdiError`);
//! 4. once the plan is built, its kernel tables against what the fragments left
//!    ([`check_tables`]; they grow with the distance penumbra's levels).
//!
//! The needs are computed from the sizes the stages allocate (an estimate for the encoded
//! output), not measured.

use convshadow_common::contract::ldi::BYTES_PER_FRAGMENT;
use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::guard::GuardBand;

use super::backend::{Backend, BackendChoice};
use super::error::RenderError;

/// Bytes per grid pixel the LDI builder needs before any fragment (counts, CSR offsets, cursors).
pub const LDI_BYTES_PER_PIXEL: u64 = 4 + 4 + 4;

/// The memory a render needs before any fragment, from the scene alone (checked before
/// anything large is allocated; the LDI then gets the rest of the budget for its fragments).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryNeed {
    /// The guard band the grid is sized for.
    pub guard: GuardBand,
    /// Grid pixels (image plus guard band on every side).
    pub grid_pixels: u64,
    /// The LDI's per-pixel arrays.
    pub ldi_pixels: u64,
    /// The sweep's two light buffers per light and plane (ping-pong), f32: a plane per channel
    /// and, with the distance penumbra, the occluder-depth plane; then (distance penumbra) the
    /// two level planes per light, u32.
    pub light_buffers: u64,
    /// The sweep's per-pixel state: layer cursor, inside bits, colour and alpha; the light in
    /// planar order before and after the sweep; the level planes' block minima.
    pub sweep_state: u64,
    /// The output image as floats, its alpha, its 8-bit encoding and the encoded file
    /// (estimate; `--aov` layers are not counted).
    pub output: u64,
    /// Input data held while rendering, from the files' sizes: 3D textures (the file and its
    /// f32 voxels while loading; rendering only), light patterns (the decoded image and its f32
    /// texels, from the header; rendering only) and mesh files (`convshadow_io::mesh::memory_need`:
    /// OBJ counted from its lines, binary data from its size).
    pub inputs: u64,
    /// Device buffers of the GPU backend before any fragment (0 on the CPU, see
    /// [`MemoryNeed::on_gpu`]): its two light buffers per light and plane, layer cursors,
    /// per-pixel colour, LDI offsets, the image and its read-back copy, and the texture voxels.
    pub gpu_buffers: u64,
    /// Whether the LDI's fragments are also held on the device (the GPU backend): the
    /// fragment budget left by [`MemoryNeed::check`] is then split between host and device.
    pub gpu_fragments: bool,
}

/// Bytes the scene's input files need in memory (see [`MemoryNeed::inputs`]): its meshes, and
/// for a render (`sweep`) its 3D textures and light patterns; a file that cannot be inspected
/// counts 0 here and is reported when it is loaded.
fn input_bytes(scene: &Scene, sweep: bool) -> u64 {
    if sweep {
        mesh_bytes(scene)
            .saturating_add(texture_bytes(scene))
            .saturating_add(pattern_bytes(scene))
    } else {
        mesh_bytes(scene)
    }
}

/// The size of the file at `p`, 0 when it cannot be inspected.
fn file_size(p: &std::path::Path) -> u64 {
    std::fs::metadata(p).map_or(0, |m| m.len())
}

/// Mesh files: `convshadow_io::mesh::memory_need` (OBJ counted from its lines, binary data from
/// its size).
fn mesh_bytes(scene: &Scene) -> u64 {
    use convshadow_common::model::scene::ShapeSpec;
    scene
        .meshes
        .iter()
        .filter_map(|m| match &m.shape {
            ShapeSpec::Obj { path } => Some(convshadow_io::mesh::memory_need(path)),
            _ => None,
        })
        .fold(0u64, u64::saturating_add)
}

/// 3D textures: the file and its f32 voxels while loading.
fn texture_bytes(scene: &Scene) -> u64 {
    use convshadow_common::model::scene::TextureFormat;
    scene
        .materials
        .iter()
        .filter_map(|m| m.texture.as_ref())
        .map(|t| match t.format {
            TextureFormat::Raw { dims, voxel } => {
                let n = dims.iter().map(|&d| u64::from(d)).product::<u64>();
                n.saturating_mul(voxel.bytes() + 4)
            }
            // NIfTI: the first volume as stored and its f32 voxels, from the header (so a
            // gzip file or a 4D series counts what it holds); from the file's size (at most 4
            // f32 bytes per stored byte) when the header cannot be read.
            TextureFormat::Nifti { .. } => {
                convshadow_io::nifti::memory_need(&t.path).unwrap_or_else(|| 5 * file_size(&t.path))
            }
            // OpenVDB: vdb-rs's tree, the brick table and at most one brick per active voxel,
            // from the grid's metadata ([`convshadow_io::vdb::memory_need`]); 64 bytes per
            // stored byte when the metadata cannot be read (compressed data, densely filled).
            TextureFormat::Vdb { ref grid } => convshadow_io::vdb::memory_need(&t.path, grid)
                .unwrap_or_else(|| file_size(&t.path).saturating_mul(64)),
        })
        .fold(0u64, u64::saturating_add)
}

/// Light patterns: the decoded image and its f32 texels, from the header (the file's size says
/// nothing of a PNG's decoded size); from 16 f32 bytes per stored byte when unreadable.
fn pattern_bytes(scene: &Scene) -> u64 {
    scene
        .lights
        .iter()
        .filter_map(|l| l.pattern.as_ref())
        .map(|p| {
            convshadow_io::pattern::memory_need(&p.path)
                .unwrap_or_else(|| file_size(&p.path).saturating_mul(16))
        })
        .fold(0u64, u64::saturating_add)
}

/// Bytes of the spot lights' patterns as f32 RGB texels, the copy the GPU's eye pass uploads
/// (gpu/src/eye.rs); a directional light's pattern becomes its initial light buffer, already
/// counted. A file whose header cannot be read counts 0 here and is reported when it is loaded.
fn spot_pattern_bytes(scene: &Scene) -> u64 {
    scene
        .lights
        .iter()
        .filter(|l| l.point.as_ref().is_some_and(|p| p.spot.is_some()))
        .filter_map(|l| l.pattern.as_ref())
        .filter_map(|p| convshadow_io::pattern::texel_bytes(&p.path))
        .fold(0u64, u64::saturating_add)
}

impl MemoryNeed {
    /// The need of rendering `scene` on a grid of the image plus `guard` (with `sweep = false`:
    /// of building its LDI only). The automatic band is known once the geometry is built
    /// (`geometry.raster.guard`); before that, `scene.sweep.guard_band.lower_bound()` gives a
    /// need the render cannot fall below.
    pub fn of(scene: &Scene, guard: GuardBand, sweep: bool) -> MemoryNeed {
        let grid_pixels = guard.grid_pixels(scene.image.width, scene.image.height);
        let image_pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
        let channels: u64 = if scene.is_monochrome() { 1 } else { 3 };
        // The distance penumbra's depth plane per light (`RenderPlan::depth_planes`), and its
        // level plane (4 bytes a pixel too): two planes more per light.
        let depth_planes = u64::from(scene.sweep.penumbra == Penumbra::Distance);
        let lights = scene.lights.len() as u64;
        let (light_buffers, sweep_state, output) = if sweep {
            (
                2 * lights * (channels + 2 * depth_planes) * 4 * grid_pixels,
                // Cursor, inside bits, colour, alpha; with pre-integration the kept front value.
                // Then the light in planar order before and after the sweep (the initial buffer
                // it starts from and the final one it returns, beside its own pixel-interleaved
                // pair), and the level planes' 2×2 block minima.
                (4 + 4 + 12 + 4 + if scene.sweep.preintegration { 4 } else { 0 }) * grid_pixels
                    + 2 * lights * (channels + depth_planes) * 4 * grid_pixels
                    + lights * depth_planes * 4 * grid_pixels,
                // RGB and alpha floats, 8-bit RGB, the encoded file.
                (12 + 4 + 3 + 3) * image_pixels,
            )
        } else {
            (0, 0, image_pixels)
        };
        MemoryNeed {
            guard,
            grid_pixels,
            ldi_pixels: LDI_BYTES_PER_PIXEL * grid_pixels,
            light_buffers,
            sweep_state,
            output,
            inputs: input_bytes(scene, sweep),
            gpu_buffers: 0,
            gpu_fragments: false,
        }
    }

    /// The need on `backend`: [`MemoryNeed::of`], with the device buffers for `--backend gpu`
    /// ([`MemoryNeed::on_gpu`]). `auto` is counted here as the CPU, the smaller need: the
    /// pipeline checks `auto` again on the backend it opened ([`open_within_budget`]).
    pub fn for_backend(
        scene: &Scene,
        guard: GuardBand,
        sweep: bool,
        backend: Backend,
    ) -> MemoryNeed {
        let need = MemoryNeed::of(scene, guard, sweep);
        if matches!(backend, Backend::Gpu) {
            need.on_gpu(scene, sweep)
        } else {
            need
        }
    }

    /// Adds the GPU backend's device buffers, estimated from the sizes `convshadow-gpu`
    /// allocates (gpu/src/sweep.rs `upload_buffers`, gpu/src/ldi.rs): for a render, the light
    /// ping-pong pair (as on the CPU), 8-byte layer cursors, 16-byte per-pixel colour, 4-byte LDI
    /// offsets (with pre-integration 4-byte kept front values), the RGBA image (16 bytes per pixel)
    /// and its read-back copy, and the 3D textures' f32
    /// voxels, and the spot lights' patterns as f32 texels (gpu/src/eye.rs `spot_pattern`); for
    /// an LDI alone, its per-pixel counts and offsets. Fragments are then held on
    /// the host and on the device.
    pub fn on_gpu(mut self, scene: &Scene, sweep: bool) -> MemoryNeed {
        let image_pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
        self.gpu_buffers = if sweep {
            let textures = texture_bytes(scene);
            // With pre-integration, 4 more bytes per pixel: the kept front value.
            let pre = if scene.sweep.preintegration { 4 } else { 0 };
            (self.light_buffers + (8 + 16 + 4 + pre) * self.grid_pixels + 2 * 16 * image_pixels)
                .saturating_add(textures / 2)
                .saturating_add(spot_pattern_bytes(scene))
        } else {
            (4 + 4) * self.grid_pixels
        };
        self.gpu_fragments = true;
        self
    }

    /// Everything but the fragments.
    pub fn total(&self) -> u64 {
        (self.ldi_pixels + self.light_buffers + self.sweep_state + self.output)
            .saturating_add(self.inputs)
            .saturating_add(self.gpu_buffers)
    }

    /// Refuses (with the numbers) when the need exceeds `budget`; else returns what is left of
    /// the budget for the LDI's fragments.
    pub fn check(&self, scene: &Scene, budget: u64) -> Result<u64, RenderError> {
        let need = self.total();
        let mib = |b: u64| b.div_ceil(1 << 20);
        if need <= budget {
            // A budget above what the machine has must not end in an allocation abort: probe
            // the whole need once, fallibly (untouched, so it costs no memory), before any buffer.
            let mut probe: Vec<u8> = Vec::new();
            if usize::try_from(need).map_or(true, |n| probe.try_reserve_exact(n).is_err()) {
                return Err(RenderError::OutOfMemory(format!(
                    "{}: the render needs {} MiB before any fragment, within the memory budget of \
                     {} MiB, but the machine cannot allocate them; lower the image size, \
                     sweep.guard_band or the light count, or --max-memory",
                    scene.source,
                    mib(need),
                    budget >> 20
                )));
            }
            let left = budget - need;
            return Ok(if self.gpu_fragments { left / 2 } else { left });
        }
        Err(RenderError::OutOfMemory(format!(
            "{}: the render needs {} MiB before any fragment ({} grid pixels with a guard band \
                 of {}: LDI arrays {} MiB, light buffers {} MiB for {} lights, sweep state {} MiB, output {} MiB, \
                 textures and meshes {} MiB{}), more than the memory budget of {} MiB; lower \
                 image.width/image.height, sweep.guard_band, the light count or the input \
                 sizes, or raise --max-memory",
            scene.source,
            mib(need),
            self.grid_pixels,
            self.guard,
            mib(self.ldi_pixels),
            mib(self.light_buffers),
            scene.lights.len(),
            mib(self.sweep_state),
            mib(self.output),
            mib(self.inputs),
            if self.gpu_fragments {
                format!(
                    ", GPU buffers {} MiB (light buffers, layer cursors, colour, LDI offsets, \
                     image, textures) with the LDI's fragments also on the device",
                    mib(self.gpu_buffers)
                )
            } else {
                String::new()
            },
            budget >> 20
        )))
    }
}

/// Bytes of the plan's kernel tables while sweeping on `backend` (`Cpu` or `Gpu`), known only
/// once the plan is built: they grow with the distance penumbra's levels (one tap table per
/// level, about 100 at 512 slabs). On the host the taps (24 bytes each) and the level tables
/// (`level_of` and the per-level schedule, 4 bytes an entry); the CPU sweep adds its per-tap
/// columns (16 bytes of weights, a 4-byte light offset and a 4-byte level-plane offset a tap);
/// the GPU a device copy of the taps and
/// level tables (gpu/src/sweep.rs `light_tables`).
pub fn kernel_table_bytes(plan: &RenderPlan, backend: Backend) -> u64 {
    let (mut taps, mut words) = (0u64, 0u64);
    for light in &plan.lights {
        let t = &light.table;
        taps += t.taps.len() as u64;
        words += (t.level_of.len() + t.slab_phase.len()) as u64;
    }
    let (per_tap, per_word) = table_entry_bytes(backend);
    per_tap * taps + per_word * words
}

/// Bytes a tap and a table word take on `backend` ([`kernel_table_bytes`]): on the host 24 a tap
/// and 4 a word, the CPU sweep's tap columns 24 a tap more, the GPU a device copy of both.
pub fn table_entry_bytes(backend: Backend) -> (u64, u64) {
    match backend {
        Backend::Gpu => (2 * 24, 2 * 4),
        _ => (24 + 24, 4),
    }
}

/// What the memory budget leaves for the kernel tables after the LDI's `fragments` (`left`:
/// the fragment budget [`MemoryNeed::check`] gave).
pub(super) fn table_allowance(left: u64, fragments: u64) -> u64 {
    left.saturating_sub(fragments.saturating_mul(BYTES_PER_FRAGMENT))
}

/// Refuses, after the plan is built, kernel tables that do not fit in what the memory budget
/// leaves after the LDI's fragments (`left`: the fragment budget [`MemoryNeed::check`] gave).
/// The build itself stops once its levels pass that allowance ([`tables_over_budget`]).
pub(super) fn check_tables(
    scene: &Scene,
    plan: &RenderPlan,
    backend: Backend,
    left: u64,
    fragments: u64,
) -> Result<(), RenderError> {
    let tables = kernel_table_bytes(plan, backend);
    let free = table_allowance(left, fragments);
    if tables <= free {
        return Ok(());
    }
    let levels = plan.lights.first().map_or(1, |l| l.table.levels);
    Err(tables_over_budget(
        scene, levels, tables, "", backend, free, fragments,
    ))
}

/// The refusal of kernel tables that need `tables` bytes (`at_least`: "more than " when the
/// build stopped part way) where the budget leaves `free` after the LDI's `fragments`.
pub(super) fn tables_over_budget(
    scene: &Scene,
    levels: u32,
    tables: u64,
    at_least: &str,
    backend: Backend,
    free: u64,
    fragments: u64,
) -> RenderError {
    RenderError::OutOfMemory(format!(
        "{}: the kernel tables need {at_least}{} MiB ({} lights, {levels} kernel levels, {}), more \
         than the {} MiB the memory budget leaves after the LDI's {fragments} fragments; lower \
         sweep.slabs or use a smaller kernel (sweep.kernel), or raise --max-memory",
        scene.source,
        tables.div_ceil(1 << 20),
        scene.lights.len(),
        if backend == Backend::Gpu {
            "on the host and the device"
        } else {
            "with the sweep's tap columns"
        },
        free >> 20,
    ))
}

/// Opens `backend` and checks the memory need (with `sweep = false`: of the LDI alone) on the
/// backend that will run, returning the choice and what the budget leaves for fragments. A
/// named backend is checked before it is opened, so a refusal costs no adapter start-up; `auto`
/// is opened first and then counted as what it picked: the GPU's device buffers when it found an
/// adapter, the CPU's need when it fell back. `guard` is the band counted (before the geometry,
/// its lower bound; callers check again once the band is resolved).
pub fn open_within_budget(
    scene: &Scene,
    guard: GuardBand,
    sweep: bool,
    backend: Backend,
    budget: u64,
) -> Result<(BackendChoice, u64), RenderError> {
    if backend != Backend::Auto {
        let left = MemoryNeed::for_backend(scene, guard, sweep, backend).check(scene, budget)?;
        return Ok((BackendChoice::open(backend)?, left));
    }
    let choice = BackendChoice::open(backend)?;
    if choice.gpu.is_none() {
        let left =
            MemoryNeed::for_backend(scene, guard, sweep, Backend::Cpu).check(scene, budget)?;
        return Ok((choice, left));
    }
    // No silent fall-back to the CPU by memory: `auto` means the GPU where there is one. The
    // refusal says what the CPU would need instead.
    let left = MemoryNeed::for_backend(scene, guard, sweep, Backend::Gpu)
        .check(scene, budget)
        .map_err(|e| match e {
            RenderError::OutOfMemory(m) => RenderError::OutOfMemory(format!(
                "{m} (--backend auto opened the GPU, so its buffers count; --backend cpu needs \
                 {} MiB before any fragment)",
                MemoryNeed::for_backend(scene, guard, sweep, Backend::Cpu)
                    .total()
                    .div_ceil(1 << 20)
            )),
            other => other,
        })?;
    Ok((choice, left))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn the_distance_penumbra_counts_a_depth_and_a_level_plane_per_light() {
        // The default scene: two coloured lights, three channels each; the distance penumbra
        // adds a depth plane and a level plane (4 bytes a pixel each) per light, so its light
        // buffers are 5/3 of the iterated ones.
        let mut scene = Scene::default_scene();
        scene.sweep.penumbra = Penumbra::Iterated;
        let g = GuardBand::default();
        let iterated = MemoryNeed::for_backend(&scene, g, true, Backend::Gpu);
        scene.sweep.penumbra = Penumbra::Distance;
        let distance = MemoryNeed::for_backend(&scene, g, true, Backend::Gpu);
        assert_eq!(3 * distance.light_buffers, 5 * iterated.light_buffers);
        assert_eq!(
            distance.light_buffers,
            2 * 2 * (3 + 1 + 1) * 4 * iterated.grid_pixels
        );
        // Both copies count on the GPU: the host's and the device's.
        assert_eq!(
            distance.gpu_buffers - iterated.gpu_buffers,
            distance.light_buffers - iterated.light_buffers
        );
    }

    #[test]
    fn a_spots_pattern_counts_on_the_gpu_as_f32_texels() {
        // The gallery's spot light projects scenes/gobo.png (48 × 48): the eye pass uploads its
        // linear RGB texels as f32, 12 bytes each, beside the host's copy (an input).
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/perspective/spotlight.toml");
        let scene = convshadow_io::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let (w, h) =
            image::image_dimensions(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gobo.png"))
                .unwrap();
        let g = GuardBand::default();
        assert_eq!(spot_pattern_bytes(&scene), u64::from(w) * u64::from(h) * 12);
        // The same light as a point light, its pattern kept (so the light buffers' channels are
        // the same): the spot's device copy is all that differs.
        let with = MemoryNeed::for_backend(&scene, g, true, Backend::Gpu);
        let mut bare = scene.clone();
        bare.lights.iter_mut().for_each(|l| {
            if let Some(p) = l.point.as_mut() {
                p.spot = None;
            }
        });
        assert_eq!(spot_pattern_bytes(&bare), 0);
        let without = MemoryNeed::for_backend(&bare, g, true, Backend::Gpu);
        assert_eq!(
            with.gpu_buffers - without.gpu_buffers,
            u64::from(w) * u64::from(h) * 12
        );
        // On the CPU the pattern is an input only.
        let cpu = MemoryNeed::for_backend(&scene, g, true, Backend::Cpu);
        assert_eq!(cpu.gpu_buffers, 0);
    }

    #[test]
    fn gpu_buffers_count_in_the_memory_need_and_are_named() {
        let scene = Scene::default_scene();
        let g = GuardBand::default();
        let cpu = MemoryNeed::for_backend(&scene, g, true, Backend::Cpu);
        let gpu = MemoryNeed::for_backend(&scene, g, true, Backend::Gpu);
        assert_eq!(cpu.gpu_buffers, 0);
        // At least the light pair, cursors, colour and offsets, and the image twice.
        let image = u64::from(scene.image.width) * u64::from(scene.image.height);
        assert!(gpu.gpu_buffers >= cpu.light_buffers + 28 * cpu.grid_pixels + 32 * image);
        assert_eq!(gpu.total(), cpu.total() + gpu.gpu_buffers);
        // The LDI alone on the GPU holds its per-pixel arrays on the device too.
        assert!(MemoryNeed::for_backend(&scene, g, false, Backend::Gpu).gpu_buffers > 0);
        // A budget between the two needs: the CPU fits, the GPU is refused naming its buffers,
        // and what is left for fragments on the GPU is split between host and device.
        let budget = cpu.total() + gpu.gpu_buffers / 2;
        assert!(cpu.check(&scene, budget).is_ok());
        let err = gpu.check(&scene, budget).unwrap_err().to_string();
        assert!(err.contains("GPU buffers"), "{err}");
        let roomy = 4 * gpu.total();
        assert_eq!(gpu.check(&scene, roomy).unwrap(), (roomy - gpu.total()) / 2);
    }
}
