//! The render pipeline as a library call: scene → geometry → LDI → plan → sweep → image.
//! The `render` command and the tests both go through [`render`] (and `convshadow ldi` through
//! [`build_ldi`], the first stages alone). Library code: failures are a typed [`RenderError`];
//! the exit codes they map to are `crate::exit_code` (the binary exits with them).
//!
//! [`render`] reads as the frame's stages (docs/ARCHITECTURE.md), one call each: the backend
//! opened within the memory budget, geometry (meshes, camera, slabs, rasterizer set-up), LDI,
//! plan, sweep, image. Around them: the open-mesh refusal after the LDI, a cancel point between
//! stages, and the budget's checks, each where its size becomes known (`pipeline/budget.rs`).
//!
//! Files: this one (the request, the result, the stages in order); `pipeline/aov.rs` (the
//! extra output layers: depth, one light's contribution); `pipeline/backend.rs` (where it runs:
//! backend, CPU path, threads); `pipeline/budget.rs` (the memory budget); `pipeline/error.rs`
//! ([`RenderError`]); `pipeline/reference.rs` ([`render_reference`], the ground-truth
//! shadow-ray renderer behind the same checks). Imports go one way: this file → aov, budget →
//! backend → error, and reference → this file.

mod aov;
mod backend;
mod budget;
mod error;
mod passes;
mod perspective;
mod point;
mod point_passes;
mod reference;

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_common::pixel::hash::Fingerprint;
use convshadow_common::plan::RenderPlan;
use convshadow_common::plan::kernel::{TableGuard, distance_levels};
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_cpu::ldi::{BuildLdi, Ldi, LdiStats};
use convshadow_cpu::sweep::{
    ChunkCounts, CpuOptions, SweepError, SweepOptions, SweepOutput, sweep_with,
};
use convshadow_io::image::RgbImage;

pub use aov::{Aov, LightColors, first_hit_depth};
pub use backend::{Backend, BackendChoice, CpuPath, MAX_THREADS, thread_pool};
pub use budget::{LDI_BYTES_PER_PIXEL, MemoryNeed, kernel_table_bytes, open_within_budget};
pub use error::RenderError;
pub use reference::render_reference;

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
    /// Extra layers to produce ([`Rendered::depth`], [`Rendered::light_layers`]); each light
    /// layer is one more sweep. None by default.
    pub aovs: Vec<Aov>,
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
            aovs: Vec::new(),
        }
    }
}

/// A finished render and its numbers.
pub struct Rendered {
    /// The linear float image.
    pub image: RgbImage,
    /// The composited opacity `A` of each image pixel, `width·height`: the front-to-back
    /// `A += (1 − A)·α_slab` before the background is added (`image = C + (1 − A)·background`).
    pub alpha: Vec<f32>,
    /// With [`Aov::Depth`] requested: the first-hit depth per image pixel
    /// ([`first_hit_depth`]).
    pub depth: Option<Vec<f32>>,
    /// Per [`Aov::Light`] requested, in request order: the light's index and its contribution
    /// to the image (linear RGB, `width·height·3`, the background excluded).
    pub light_layers: Vec<(usize, Vec<f32>)>,
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
    /// [`RenderRequest::every_slab`]); 0 for the shadow-ray reference, which sweeps none. With
    /// lights from in front of the viewer, both passes' slabs.
    pub slabs_swept: u32,
    /// Lights from in front of the viewer, swept in the turned-round pass (`Scene::passes`);
    /// [`Rendered::plan`] is the other pass's when there is one.
    pub turned_round_lights: usize,
    /// The sweep's pixel·slab·light updates over every pass (the grid, every slab of the plan,
    /// every light: the frame's work, whatever an early finish left out).
    pub updates: f64,
    /// Threads used.
    pub threads: usize,
    /// Seconds building geometry and the LDI.
    pub seconds_ldi: f64,
    /// Seconds building the render plan: its tables and the 3D textures it loads.
    pub seconds_plan: f64,
    /// Seconds in the sweep (the image's; the light layers' sweeps count in
    /// [`Rendered::seconds_total`] only).
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

/// A plan's pixel·slab·light updates: grid pixels × slabs × lights.
pub fn plan_updates(plan: &RenderPlan) -> f64 {
    f64::from(plan.grid_width)
        * f64::from(plan.grid_height)
        * f64::from(plan.slabs)
        * plan.lights.len() as f64
}

/// Fingerprint of a float image's bits.
pub fn image_fingerprint(data: &[f32]) -> u64 {
    let mut f = Fingerprint::default();
    f.floats(data);
    f.finish()
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
    let engine = Engine::open(scene, false, backend, threads, memory_budget)?;
    let start = Instant::now();
    let (geometry, fragment_budget) = engine.geometry(scene, memory_budget)?;
    let t_ldi = Instant::now();
    let ldi = engine.ldi(&geometry, fragment_budget)?;
    let seconds_ldi = t_ldi.elapsed().as_secs_f64();
    let stats = engine.pool.install(|| ldi.stats());
    Ok(BuiltLdi {
        geometry,
        ldi,
        stats,
        threads: engine.pool.current_num_threads(),
        backend: engine.choice.name(),
        adapter: engine.choice.adapter(),
        backend_note: engine.choice.note,
        seconds_ldi,
        seconds_total: start.elapsed().as_secs_f64(),
    })
}

/// Renders a scene on the CPU or, with `req.backend`, on the GPU: the stages in order, each
/// timed, with a cancel point between them; then the extra layers of `req.aovs` (a light the
/// scene lacks is refused first, [`RenderError::BadRequest`]).
///
/// A scene with lights from in front of the viewer is rendered in two passes, added
/// (`passes::render_passes`).
pub fn render(scene: &Scene, req: &RenderRequest<'_>) -> Result<Rendered, RenderError> {
    for aov in &req.aovs {
        if let Aov::Light(l) = *aov {
            check_light_index(scene, l)?;
        }
    }
    if scene.lights.iter().any(|l| l.point.is_some()) {
        return point_passes::render_with_point_lights(scene, req);
    }
    // A perspective camera, or an orthographic one whose light grid is not its image's pixels:
    // the light swept on its own grid, the eye's rays reading it.
    if scene.camera.is_perspective() || scene.sweep.light_resolution != 1.0 {
        return perspective::render_perspective(scene, req);
    }
    passes::render_passes(scene, &req.aovs, passes::Mirror::Yes, |pass, aovs| {
        render_pass(pass, req, aovs)
    })
}

/// [`render`] of one pass: every light at the same end of the sweep, `aovs` instead of
/// `req.aovs`.
fn render_pass(
    scene: &Scene,
    req: &RenderRequest<'_>,
    aovs: &[Aov],
) -> Result<Rendered, RenderError> {
    let start = Instant::now();
    // 1. The backend and the threads, once the scene's per-pixel need fits the budget.
    let engine = Engine::open(scene, true, req.backend, req.threads, req.memory_budget)?;
    // 2. Geometry, and with its guard band what the budget leaves for the LDI's fragments.
    let (geometry, fragment_budget) = engine.geometry(scene, req.memory_budget)?;
    check_cancel(req.cancel)?;
    // 3. The LDI; closed meshes only, unless allowed.
    let ldi = engine.ldi(&geometry, fragment_budget)?;
    check_cancel(req.cancel)?;
    let stats = engine.pool.install(|| ldi.stats());
    refuse_open_meshes(scene, &geometry, &stats, req.allow_open)?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    // 4. The plan, whose kernel tables must fit in what the fragments left.
    let t_plan = Instant::now();
    let allowance = budget::table_allowance(fragment_budget, stats.fragments);
    let plan = engine.plan(scene, &geometry, req.cancel, allowance, stats.fragments)?;
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    engine.check_tables(scene, &plan, fragment_budget, stats.fragments)?;
    check_cancel(req.cancel)?;
    // 5. The sweep.
    let t_sweep = Instant::now();
    let chunk_counts = ChunkCounts::default();
    let out = engine.sweep(&plan, &geometry, &ldi, req, &chunk_counts)?;
    let seconds_sweep = t_sweep.elapsed().as_secs_f64();
    // 6. The extra layers: one more sweep per light layer, on the plan with the other lights
    // and the background black (`pipeline/aov.rs`).
    let mut plan = plan;
    let light_layers = aov::light_layers(&mut plan, aovs, req.cancel, |plan| {
        let layer = engine.sweep(plan, &geometry, &ldi, req, &ChunkCounts::default());
        Ok(layer?.image)
    })?;
    let depth = aovs
        .contains(&Aov::Depth)
        .then(|| first_hit_depth(&plan, &ldi, geometry.z_origin));
    // 7. The image and its numbers.
    Ok(Rendered {
        mesh_warnings: geometry.mesh_warnings(),
        image_hash: image_fingerprint(&out.image),
        image: RgbImage {
            width: scene.image.width,
            height: scene.image.height,
            data: out.image,
        },
        alpha: out.alpha,
        depth,
        light_layers,
        ldi: stats,
        ldi_hash: ldi.fingerprint(),
        turned_round_lights: if plan.turned_round {
            plan.lights.len()
        } else {
            0
        },
        updates: plan_updates(&plan),
        plan,
        light: out.light,
        slabs_swept: out.slabs_swept,
        threads: engine.pool.current_num_threads(),
        seconds_ldi,
        seconds_plan,
        seconds_sweep,
        chunks: chunk_counts.snapshot(),
        seconds_total: start.elapsed().as_secs_f64(),
        backend: engine.choice.name(),
        adapter: engine.choice.adapter(),
        backend_note: engine.choice.note,
    })
}

/// Where the stages run: the backend opened and the CPU's worker threads. Each method is one
/// stage of the frame on that backend.
struct Engine {
    /// The GPU, or the CPU.
    choice: BackendChoice,
    /// Whether the memory need counted is a render's (else the LDI's alone).
    sweep: bool,
    /// The CPU's workers (the LDI's statistics and the plan use them on either backend).
    pool: rayon::ThreadPool,
}

impl Engine {
    /// Opens `backend` and the thread pool, once the scene's need (of a render, or with `sweep =
    /// false` of its LDI alone), counted with the narrowest guard band it can resolve to, fits
    /// in `budget` (checked again in [`Engine::geometry`] with the band resolved).
    fn open(
        scene: &Scene,
        sweep: bool,
        backend: Backend,
        threads: usize,
        budget: u64,
    ) -> Result<Engine, RenderError> {
        let least = scene.sweep.guard_band.lower_bound();
        let (choice, _) = open_within_budget(scene, least, sweep, backend, budget)?;
        let pool = thread_pool(threads)?;
        Ok(Engine {
            choice,
            sweep,
            pool,
        })
    }

    /// Geometry: the meshes built, read and placed, the camera, the slab range and the
    /// rasterizer set-up; then the scene's need again with the guard band now known, which
    /// leaves the LDI's fragment budget (returned with the geometry).
    fn geometry(&self, scene: &Scene, budget: u64) -> Result<(SceneGeometry, u64), RenderError> {
        let geometry = convshadow_io::build_geometry(scene)?;
        let backend = self.choice.opened();
        let need = MemoryNeed::for_backend(scene, geometry.raster.guard, self.sweep, backend);
        let fragment_budget = need.check(scene, budget)?;
        Ok((geometry, fragment_budget))
    }

    /// The LDI, within `fragment_budget` bytes of fragments.
    fn ldi(&self, geometry: &SceneGeometry, fragment_budget: u64) -> Result<Ldi, RenderError> {
        Ok(match &self.choice.gpu {
            Some(ctx) => convshadow_gpu::ldi::build_ldi(ctx, &geometry.raster, fragment_budget)?,
            None => self
                .pool
                .install(|| Ldi::build(&geometry.raster, fragment_budget))?,
        })
    }

    /// The plan: every table the sweep reads. 3D textures (raw and NIfTI) load in chunks and
    /// stop once the cancel flag is raised; the kernel tables stop too, and once they pass
    /// `allowance` bytes (what the budget leaves after the LDI's `fragments`). In the pool: the
    /// distance penumbra builds its levels' tables in parallel.
    fn plan(
        &self,
        scene: &Scene,
        geometry: &SceneGeometry,
        cancel: Option<&AtomicBool>,
        allowance: u64,
        fragments: u64,
    ) -> Result<RenderPlan, RenderError> {
        let backend = self.choice.opened();
        let (per_tap, per_word) = budget::table_entry_bytes(backend);
        let guard = TableGuard::new(cancel, per_tap, per_word, allowance);
        let plan = self
            .pool
            .install(|| convshadow_io::build_plan_guarded(scene, geometry, &guard))
            .map_err(|e| match e.source {
                convshadow_common::pixel::texture3d::TextureError::Interrupted { .. } => {
                    RenderError::Interrupted
                }
                _ => RenderError::BadPlan(e.to_string()),
            })?;
        match plan {
            Some(plan) => Ok(plan),
            None if guard.cancelled() => Err(RenderError::Interrupted),
            None => {
                let levels = match scene.sweep.penumbra {
                    Penumbra::Distance => distance_levels(geometry.slabs).len() as u32,
                    Penumbra::Iterated => 1,
                };
                let used = guard.used();
                Err(budget::tables_over_budget(
                    scene,
                    levels,
                    used,
                    "more than ",
                    backend,
                    allowance,
                    fragments,
                ))
            }
        }
    }

    /// Refuses kernel tables that do not fit in what the budget left after the LDI's
    /// `fragments` ([`budget::check_tables`]).
    fn check_tables(
        &self,
        scene: &Scene,
        plan: &RenderPlan,
        fragment_budget: u64,
        fragments: u64,
    ) -> Result<(), RenderError> {
        let backend = self.choice.opened();
        budget::check_tables(scene, plan, backend, fragment_budget, fragments)
    }

    /// The sweep, slab by slab; on the CPU with the request's path, counting its chunks.
    fn sweep(
        &self,
        plan: &RenderPlan,
        geometry: &SceneGeometry,
        ldi: &Ldi,
        req: &RenderRequest<'_>,
        chunk_counts: &ChunkCounts,
    ) -> Result<SweepOutput, RenderError> {
        let options = SweepOptions {
            progress: req.progress,
            cancel: req.cancel,
            // A light's pattern (gobo) is its initial light buffer; without one every light
            // starts at 1.
            initial_light: plan.initial_light.as_deref(),
            every_slab: req.every_slab,
        };
        let cpu = CpuOptions {
            path: req.path.sweep_path(),
            skip_quiet: req.skip_quiet,
            chunk_counts: Some(chunk_counts),
        };
        Ok(match &self.choice.gpu {
            Some(ctx) => convshadow_gpu::sweep::sweep(ctx, plan, &geometry.raster, ldi, &options)?,
            None => self
                .pool
                .install(|| sweep_with(plan, &geometry.raster, ldi, &options, &cpu))
                .map_err(|e| match e {
                    SweepError::Interrupted => RenderError::Interrupted,
                })?,
        })
    }
}

/// Refuses a light layer ([`Aov::Light`]) for a light the scene does not have.
pub fn check_light_index(scene: &Scene, light: usize) -> Result<(), RenderError> {
    let n = scene.lights.len();
    if light >= n {
        return Err(RenderError::BadRequest(format!(
            "--aov light{light}: the scene has {n} light{} (light0 … light{})",
            if n == 1 { "" } else { "s" },
            n.saturating_sub(1)
        )));
    }
    Ok(())
}

/// Refuses (unless `allow_open`) an LDI where a closed mesh has a pixel of odd fragment count:
/// the sweep's parity test would smear it. Open meshes are not refused: they are thin shells,
/// out of the parity test, with a warning ([`SceneGeometry::mesh_warnings`]).
fn refuse_open_meshes(
    scene: &Scene,
    geometry: &SceneGeometry,
    stats: &LdiStats,
    allow_open: bool,
) -> Result<(), RenderError> {
    if allow_open || stats.odd_pixels == 0 {
        return Ok(());
    }
    let closed: Vec<String> = (0..geometry.meshes.len())
        .filter(|&i| geometry.raster.parity_meshes & (1u32 << i) != 0)
        .map(|i| format!("mesh[{i}]"))
        .collect();
    Err(RenderError::MeshDefect(format!(
        "{}: refusing to render: the inside/outside parity test needs the closed meshes ({}) to \
         cross every pixel an even number of times, but {} pixels have an odd fragment count. \
         Pass --allow-open to render anyway.",
        scene.source,
        closed.join(", "),
        stats.odd_pixels
    )))
}

#[cfg(test)]
mod tests {
    use convshadow_common::contract::ldi::BYTES_PER_FRAGMENT;
    use convshadow_common::model::scene::Penumbra;

    use super::*;

    #[test]
    fn kernel_tables_over_the_budget_left_are_refused_after_the_plan() {
        let mut scene = Scene::default_scene();
        scene.image.width = 24;
        scene.image.height = 24;
        scene.sweep.slabs = convshadow_common::model::scene::SlabSpec::Count(48);
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
        // While it merges them the build holds its levels beside the merged table (at most as
        // many taps), and one slab-shift schedule: the guard counts that peak, up to twice the
        // tables and a few words per slab.
        let peak = 2 * tables + 4 * (2 * 48 + 40) * r.plan.lights.len() as u64;
        let err = render(&scene, &req(exact + tables / 2))
            .err()
            .expect("the tables alone fit, not the build's peak")
            .to_string();
        assert!(err.contains("the kernel tables need more than"), "{err}");
        let fits = render(
            &scene,
            &req(need + r.ldi.fragments * BYTES_PER_FRAGMENT + peak),
        )
        .unwrap_or_else(|e| panic!("{e}"));
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
}
