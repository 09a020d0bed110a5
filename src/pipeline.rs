//! The render pipeline as a library call: scene → geometry → LDI → plan → sweep → image.
//! The `render` command and the tests both go through [`render`]. Library code: failures are a
//! typed [`RenderError`]; the exit codes they map to live in the binary's CLI (`src/cli/exit.rs`).

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use convshadow_common::geometry::{GeometryError, SceneGeometry};
use convshadow_common::guard::GuardBand;
use convshadow_common::hash::Fingerprint;
use convshadow_common::image_io::RgbImage;
use convshadow_common::ldi::BYTES_PER_FRAGMENT;
use convshadow_common::plan::RenderPlan;
use convshadow_common::scene::{Penumbra, Scene, SceneError};
use convshadow_cpu::ldi::{BuildLdi, Ldi, LdiError, LdiStats};
use convshadow_cpu::sweep::{
    ChunkCounts, CpuOptions, SweepError, SweepOptions, SweepPath, sweep_with,
};
use convshadow_gpu::{GpuContext, GpuError};

/// Why a render (or an LDI build) failed. The CLI maps each to an exit code (docs/errors.md);
/// the message is the error's `Display`.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The geometry could not be built (a bad mesh, or too many slabs).
    #[error(transparent)]
    Geometry(#[from] GeometryError),
    /// The LDI exceeds its fragment budget.
    #[error(transparent)]
    Ldi(#[from] LdiError),
    /// The GPU backend failed: no adapter, a device error, or a limit.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The per-pixel buffers alone exceed the memory budget (the message has the numbers).
    #[error("{0}")]
    OutOfMemory(String),
    /// The meshes are open, non-manifold or inconsistently wound (the message names them).
    #[error("{0}")]
    MeshDefect(String),
    /// The scene's tables could not be planned.
    #[error("{0}")]
    BadPlan(String),
    /// The cancel flag was raised; nothing was written.
    #[error("interrupted; no output written")]
    Interrupted,
    /// The worker threads could not start.
    #[error("cannot start threads: {0}")]
    Threads(String),
}

/// Most worker threads a render may ask for: far above any core count, and low enough that
/// starting (and, on a signal, stopping) the pool stays quick.
pub const MAX_THREADS: usize = 1024;

/// A thread pool with `threads` workers (0 = rayon's default: one per core), at most
/// [`MAX_THREADS`].
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, RenderError> {
    if threads > MAX_THREADS {
        return Err(RenderError::Threads(format!(
            "expected at most {MAX_THREADS} worker threads, got {threads}"
        )));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| RenderError::Threads(e.to_string()))
}

/// Which CPU code path runs the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CpuPath {
    /// One pixel at a time: the readable reference path.
    Scalar,
    /// Eight pixels at a time with `wide`, the same bits as `scalar` (the default).
    Simd,
}

impl CpuPath {
    /// The name used in stats.
    pub fn name(self) -> &'static str {
        match self {
            CpuPath::Scalar => "scalar",
            CpuPath::Simd => "simd",
        }
    }

    /// The sweep's code path.
    pub fn sweep_path(self) -> SweepPath {
        match self {
            CpuPath::Scalar => SweepPath::Scalar,
            CpuPath::Simd => SweepPath::Simd,
        }
    }
}

/// Which device renders (`--backend`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The CPU oracle.
    #[default]
    Cpu,
    /// The wgpu port (Vulkan: a hardware adapter, else Mesa lavapipe); exit code 5 without one.
    Gpu,
    /// The GPU when an adapter exists, else the CPU (and says so).
    Auto,
}

/// The device chosen for a request.
pub struct BackendChoice {
    /// The GPU context, or `None` for the CPU.
    pub gpu: Option<GpuContext>,
    /// Why `auto` fell back to the CPU, if it did.
    pub note: Option<String>,
}

impl BackendChoice {
    /// The backend this choice runs on (never `auto`).
    pub fn opened(&self) -> Backend {
        if self.gpu.is_some() {
            Backend::Gpu
        } else {
            Backend::Cpu
        }
    }

    /// Opens the backend: `gpu` fails without an adapter, `auto` falls back to the CPU.
    pub fn open(backend: Backend) -> Result<BackendChoice, RenderError> {
        match backend {
            Backend::Cpu => Ok(BackendChoice {
                gpu: None,
                note: None,
            }),
            Backend::Gpu => Ok(BackendChoice {
                gpu: Some(GpuContext::new()?),
                note: None,
            }),
            Backend::Auto => Ok(match GpuContext::new() {
                Ok(ctx) => BackendChoice {
                    gpu: Some(ctx),
                    note: None,
                },
                Err(e) => BackendChoice {
                    gpu: None,
                    note: Some(format!("--backend auto: {e}; rendering on the CPU")),
                },
            }),
        }
    }

    /// `"gpu"` or `"cpu"`, as in stats.
    pub fn name(&self) -> &'static str {
        if self.gpu.is_some() { "gpu" } else { "cpu" }
    }

    /// The adapter's name on the GPU backend.
    pub fn adapter(&self) -> Option<String> {
        self.gpu.as_ref().map(GpuContext::adapter_name)
    }
}

/// How to render.
pub struct RenderRequest<'a> {
    /// Which device renders.
    pub backend: Backend,
    /// Worker threads (0 = one per core).
    pub threads: usize,
    /// CPU code path.
    pub path: CpuPath,
    /// SIMD path: skip chunks whose result is known exactly (see `convshadow_cpu::sweep`).
    pub skip_quiet: bool,
    /// Memory budget in bytes for the LDI and the sweep's buffers.
    pub memory_budget: u64,
    /// Render even if meshes are open (the odd pixels are reported).
    pub allow_open: bool,
    /// Called after each slab.
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Raised to stop the sweep.
    pub cancel: Option<&'a AtomicBool>,
    /// Sweep every slab even once the image is final, so that [`Rendered::light`] is the light
    /// after the plan's last slab (`SweepOptions::every_slab`). Off by default: the image is
    /// the same bits either way.
    pub every_slab: bool,
}

impl Default for RenderRequest<'_> {
    fn default() -> Self {
        RenderRequest {
            backend: Backend::Cpu,
            threads: 0,
            path: CpuPath::Simd,
            skip_quiet: true,
            memory_budget: convshadow_cpu::default_memory_budget(),
            allow_open: false,
            progress: &|_| {},
            cancel: None,
            every_slab: false,
        }
    }
}

/// A finished render and its numbers.
pub struct Rendered {
    /// The linear float image.
    pub image: RgbImage,
    /// 64-bit fingerprint of the image's float bits (`image_hash`).
    pub image_hash: u64,
    /// LDI numbers.
    pub ldi: LdiStats,
    /// LDI fingerprint.
    pub ldi_hash: u64,
    /// The plan (tables) used.
    pub plan: RenderPlan,
    /// Light buffers after the last slab swept ([`Rendered::slabs_swept`]).
    pub light: Vec<f32>,
    /// Slabs swept: the plan's count, or fewer when the image was final earlier (see
    /// [`RenderRequest::every_slab`]); 0 for the shadow-ray reference, which sweeps none.
    pub slabs_swept: u32,
    /// Threads used.
    pub threads: usize,
    /// Seconds building geometry and the LDI.
    pub seconds_ldi: f64,
    /// Seconds building the render plan: its tables and the 3D textures it loads.
    pub seconds_plan: f64,
    /// Seconds in the sweep.
    pub seconds_sweep: f64,
    /// Seconds in all.
    pub seconds_total: f64,
    /// SIMD path: 8-pixel chunks `[full, skipped unoccluded, skipped dark]` over all slabs.
    pub chunks: [u64; 3],
    /// `"cpu"` or `"gpu"`: the backend that rendered.
    pub backend: &'static str,
    /// The GPU adapter's name on the GPU backend.
    pub adapter: Option<String>,
    /// Why `--backend auto` fell back to the CPU, if it did.
    pub backend_note: Option<String>,
    /// Warnings about accepted meshes (closed non-manifold edges), one line each.
    pub mesh_warnings: Vec<String>,
}

/// Fingerprint of a float image's bits.
pub fn image_fingerprint(data: &[f32]) -> u64 {
    let mut f = Fingerprint::default();
    f.floats(data);
    f.finish()
}

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
    /// The sweep's per-pixel state: layer cursor, inside bits, colour and alpha.
    pub sweep_state: u64,
    /// The output image as floats, its 8-bit encoding and the encoded file (estimate).
    pub output: u64,
    /// Input data held while rendering, from the files' sizes: 3D textures (the file and its
    /// f32 voxels while loading; rendering only) and OBJ files (twice the text: the parsed mesh).
    pub inputs: u64,
    /// Device buffers of the GPU backend before any fragment (0 on the CPU, see
    /// [`MemoryNeed::on_gpu`]): its two light buffers per light and plane, layer cursors,
    /// per-pixel colour, LDI offsets, the image and its read-back copy, and the texture voxels.
    pub gpu_buffers: u64,
    /// Whether the LDI's fragments are also held on the device (the GPU backend): the
    /// fragment budget left by [`MemoryNeed::check`] is then split between host and device.
    pub gpu_fragments: bool,
}

/// Bytes the scene's input files need in memory (see [`MemoryNeed::inputs`]); a file that cannot
/// be inspected counts 0 here and is reported when it is loaded.
fn input_bytes(scene: &Scene, textures: bool) -> u64 {
    use convshadow_common::scene::{ShapeSpec, TextureFormat};
    let size = |p: &std::path::Path| std::fs::metadata(p).map_or(0, |m| m.len());
    let meshes: u64 = scene
        .meshes
        .iter()
        .filter_map(|m| match &m.shape {
            ShapeSpec::Obj { path } => Some(2 * size(path)),
            _ => None,
        })
        .sum();
    if !textures {
        return meshes;
    }
    let texture_bytes: u64 = scene
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
                convshadow_common::nifti::memory_need(&t.path).unwrap_or_else(|| 5 * size(&t.path))
            }
        })
        .fold(0u64, u64::saturating_add);
    meshes.saturating_add(texture_bytes)
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
                (4 + 4 + 12 + 4 + if scene.sweep.preintegration { 4 } else { 0 }) * grid_pixels,
                (12 + 3 + 3) * image_pixels,
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
    /// offsets (with pre-integration 4-byte kept front values), the image (12 bytes per pixel)
    /// and its read-back copy, and the 3D textures' f32
    /// voxels; for an LDI alone, its per-pixel counts and offsets. Fragments are then held on
    /// the host and on the device.
    pub fn on_gpu(mut self, scene: &Scene, sweep: bool) -> MemoryNeed {
        let image_pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
        self.gpu_buffers = if sweep {
            let textures = input_bytes(scene, true).saturating_sub(input_bytes(scene, false));
            // With pre-integration, 4 more bytes per pixel: the kept front value.
            let pre = if scene.sweep.preintegration { 4 } else { 0 };
            (self.light_buffers + (8 + 16 + 4 + pre) * self.grid_pixels + 2 * 12 * image_pixels)
                .saturating_add(textures / 2)
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
    let host = 24 * taps + 4 * words;
    match backend {
        Backend::Gpu => 2 * host,
        _ => host + 24 * taps,
    }
}

/// Refuses, after the plan is built, kernel tables that do not fit in what the memory budget
/// leaves after the LDI's fragments (`left`: the fragment budget [`MemoryNeed::check`] gave).
fn check_tables(
    scene: &Scene,
    plan: &RenderPlan,
    backend: Backend,
    left: u64,
    fragments: u64,
) -> Result<(), RenderError> {
    let tables = kernel_table_bytes(plan, backend);
    let free = left.saturating_sub(fragments.saturating_mul(BYTES_PER_FRAGMENT));
    if tables <= free {
        return Ok(());
    }
    let levels = plan.lights.first().map_or(1, |l| l.table.levels);
    Err(RenderError::OutOfMemory(format!(
        "{}: the kernel tables need {} MiB ({} lights, {levels} kernel levels, {}), more than the \
         {} MiB the memory budget leaves after the LDI's {fragments} fragments; lower \
         sweep.slabs or use a smaller kernel (sweep.kernel), or raise --max-memory",
        scene.source,
        tables.div_ceil(1 << 20),
        plan.lights.len(),
        if backend == Backend::Gpu {
            "on the host and the device"
        } else {
            "with the sweep's tap columns"
        },
        free >> 20,
    )))
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

/// Stops with [`RenderError::Interrupted`] when the cancel flag is raised.
fn check_cancel(cancel: Option<&AtomicBool>) -> Result<(), RenderError> {
    if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
        return Err(RenderError::Interrupted);
    }
    Ok(())
}

/// A scene's geometry and LDI, built without sweeping (`convshadow ldi`).
pub struct BuiltLdi {
    /// The scene's meshes (with their closure reports) and rasterizer set-up.
    pub geometry: SceneGeometry,
    /// The layered depth image.
    pub ldi: Ldi,
    /// Its numbers.
    pub stats: LdiStats,
    /// Threads used.
    pub threads: usize,
    /// `"cpu"` or `"gpu"`: the backend that built it.
    pub backend: &'static str,
    /// The GPU adapter's name on the GPU backend.
    pub adapter: Option<String>,
    /// Why `--backend auto` fell back to the CPU, if it did.
    pub backend_note: Option<String>,
    /// Seconds building the LDI alone.
    pub seconds_ldi: f64,
    /// Seconds building geometry and LDI.
    pub seconds_total: f64,
}

/// Builds a scene's geometry and LDI on `backend` with `threads` workers (0 = one per core)
/// within `memory_budget` bytes; open meshes are reported in the result, not refused.
pub fn build_ldi(
    scene: &Scene,
    backend: Backend,
    threads: usize,
    memory_budget: u64,
) -> Result<BuiltLdi, RenderError> {
    // Refuse before allocating: the per-pixel arrays here (with the band known before the
    // geometry, then with the band it resolves), the fragments in `Ldi::build`.
    let least = scene.sweep.guard_band.lower_bound();
    let (choice, _) = open_within_budget(scene, least, false, backend, memory_budget)?;
    let pool = thread_pool(threads)?;
    let start = Instant::now();
    let geometry = SceneGeometry::build(scene)?;
    let budget = MemoryNeed::for_backend(scene, geometry.raster.guard, false, choice.opened())
        .check(scene, memory_budget)?;
    let t_ldi = Instant::now();
    let ldi = match &choice.gpu {
        Some(ctx) => convshadow_gpu::ldi::build_ldi(ctx, &geometry.raster, budget)?,
        None => pool.install(|| Ldi::build(&geometry.raster, budget))?,
    };
    let seconds_ldi = t_ldi.elapsed().as_secs_f64();
    let stats = pool.install(|| ldi.stats());
    Ok(BuiltLdi {
        geometry,
        ldi,
        stats,
        threads: pool.current_num_threads(),
        backend: choice.name(),
        adapter: choice.adapter(),
        backend_note: choice.note,
        seconds_ldi,
        seconds_total: start.elapsed().as_secs_f64(),
    })
}

/// Renders a scene on the CPU or, with `req.backend`, on the GPU.
pub fn render(scene: &Scene, req: &RenderRequest<'_>) -> Result<Rendered, RenderError> {
    let start = Instant::now();
    // Refuse before allocating: the per-pixel buffers first (with the band known before the
    // geometry, then with the band it resolves), the fragments in `Ldi::build`.
    let least = scene.sweep.guard_band.lower_bound();
    let (choice, _) = open_within_budget(scene, least, true, req.backend, req.memory_budget)?;
    let pool = thread_pool(req.threads)?;
    let geometry = SceneGeometry::build(scene)?;
    let fragment_budget =
        MemoryNeed::for_backend(scene, geometry.raster.guard, true, choice.opened())
            .check(scene, req.memory_budget)?;
    check_cancel(req.cancel)?;
    let ldi = match &choice.gpu {
        Some(ctx) => convshadow_gpu::ldi::build_ldi(ctx, &geometry.raster, fragment_budget)?,
        None => pool.install(|| Ldi::build(&geometry.raster, fragment_budget))?,
    };
    check_cancel(req.cancel)?;
    let stats = pool.install(|| ldi.stats());
    if !req.allow_open && (geometry.defect_edges() > 0 || stats.odd_pixels > 0) {
        let names: Vec<String> = geometry
            .meshes
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.report.is_closed())
            .map(|(i, m)| {
                format!(
                    "mesh[{i}] has {} boundary, {} non-manifold and {} flipped edges",
                    m.report.boundary_edges, m.report.nonmanifold_edges, m.report.flipped_edges
                )
            })
            .collect();
        return Err(RenderError::MeshDefect(format!(
            "{}: refusing to render: the inside/outside parity test needs closed, consistently \
                 wound meshes, but {}{} pixels have an odd fragment count. Pass --allow-open to \
                 render anyway.",
            scene.source,
            if names.is_empty() {
                String::new()
            } else {
                names.join("; ") + "; "
            },
            stats.odd_pixels
        )));
    }
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    // 3D textures (raw and NIfTI) load in chunks and stop once the cancel flag is raised. In the
    // request's pool: the distance penumbra builds its levels' tables in parallel.
    let plan = pool
        .install(|| RenderPlan::new_cancellable(scene, &geometry, req.cancel))
        .map_err(|e| match e.source {
            convshadow_common::texture3d::TextureError::Interrupted { .. } => {
                RenderError::Interrupted
            }
            _ => RenderError::BadPlan(e.to_string()),
        })?;
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    check_tables(
        scene,
        &plan,
        choice.opened(),
        fragment_budget,
        stats.fragments,
    )?;
    check_cancel(req.cancel)?;
    let t_sweep = Instant::now();
    let chunk_counts = ChunkCounts::default();
    let options = SweepOptions {
        progress: req.progress,
        cancel: req.cancel,
        // A light's pattern (gobo) is its initial light buffer; without one every light starts at 1.
        initial_light: plan.initial_light.as_deref(),
        every_slab: req.every_slab,
    };
    let cpu = CpuOptions {
        path: req.path.sweep_path(),
        skip_quiet: req.skip_quiet,
        chunk_counts: Some(&chunk_counts),
    };
    let out = match &choice.gpu {
        Some(ctx) => convshadow_gpu::sweep::sweep(ctx, &plan, &geometry.raster, &ldi, &options)?,
        None => pool
            .install(|| sweep_with(&plan, &geometry.raster, &ldi, &options, &cpu))
            .map_err(|e| match e {
                SweepError::Interrupted => RenderError::Interrupted,
            })?,
    };
    let seconds_sweep = t_sweep.elapsed().as_secs_f64();
    let image_hash = image_fingerprint(&out.image);
    Ok(Rendered {
        mesh_warnings: geometry.mesh_warnings(),
        image: RgbImage {
            width: scene.image.width,
            height: scene.image.height,
            data: out.image,
        },
        image_hash,
        ldi: stats,
        ldi_hash: ldi.fingerprint(),
        plan,
        light: out.light,
        slabs_swept: out.slabs_swept,
        threads: pool.current_num_threads(),
        seconds_ldi,
        seconds_plan,
        seconds_sweep,
        chunks: chunk_counts.snapshot(),
        seconds_total: start.elapsed().as_secs_f64(),
        backend: choice.name(),
        adapter: choice.adapter(),
        backend_note: choice.note,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn kernel_tables_over_the_budget_left_are_refused_after_the_plan() {
        let mut scene = Scene::default_scene();
        scene.image.width = 24;
        scene.image.height = 24;
        scene.sweep.slabs = convshadow_common::scene::SlabSpec::Count(48);
        scene.sweep.penumbra = Penumbra::Distance;
        scene.revalidate().unwrap();
        let req = |memory_budget| RenderRequest {
            threads: 1,
            memory_budget,
            ..RenderRequest::default()
        };
        let r = render(&scene, &req(1 << 30)).unwrap_or_else(|e| panic!("{e}"));
        // 48 slabs: levels 1..=16 of one slab, 17..=31 of one, 32..=47 of two, 48 alone.
        assert_eq!(r.plan.lights[0].table.levels, 16 + 15 + 8 + 1);
        let tables = kernel_table_bytes(&r.plan, Backend::Cpu);
        // At least every level's taps, each of 24 + 24 bytes.
        let min_taps: u64 = r.plan.lights.len() as u64 * 40;
        assert!(tables >= min_taps * 48, "{tables}");
        let need = MemoryNeed::for_backend(&scene, r.plan.guard, true, Backend::Cpu).total();
        let exact = need + r.ldi.fragments * BYTES_PER_FRAGMENT + tables;
        let err = render(&scene, &req(exact - 1))
            .err()
            .expect("one byte short of the tables")
            .to_string();
        assert!(err.contains("the kernel tables need"), "{err}");
        assert!(err.contains("40 kernel levels"), "{err}");
        let fits = render(&scene, &req(exact)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(fits.image_hash, r.image_hash);
        // The GPU holds the taps and level tables twice (host and device), without the CPU's
        // tap columns.
        let taps: u64 = r
            .plan
            .lights
            .iter()
            .map(|l| l.table.taps.len() as u64)
            .sum();
        assert_eq!(
            kernel_table_bytes(&r.plan, Backend::Gpu),
            2 * (tables - 24 * taps)
        );
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
        assert!(gpu.gpu_buffers >= cpu.light_buffers + 28 * cpu.grid_pixels + 24 * image);
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
