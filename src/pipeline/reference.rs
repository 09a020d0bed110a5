//! The ground-truth reference (`convshadow render --backend reference`, the Python module's
//! `backend="reference"`): the shadow-ray renderer behind the same checks and LDI as the
//! pipeline.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use convshadow_common::contract::ldi::LdiStats;
use convshadow_common::model::scene::{Scene, SceneError};
use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_io::image::RgbImage;
use convshadow_reference::shadow_ray::{TurnedEye, closed_mesh_holding};
use convshadow_reference::{Reference, ReferenceOptions};

use super::passes::{Mirror, render_passes};
use super::perspective;
use super::{
    Aov, LightColors, MemoryNeed, RenderError, Rendered, check_cancel, first_hit_depth,
    image_fingerprint, refuse_open_meshes, thread_pool,
};

/// How a reference render runs: its workers, light samples, memory, open meshes and cancel flag.
#[derive(Clone, Copy)]
struct ReferenceRun<'a> {
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
    cancel: Option<&'a AtomicBool>,
}

/// Renders with the ground-truth reference: the same checks and LDI as the pipeline, then
/// [`Reference::render_with_alpha`] with `samples` light directions per shading point, on
/// `threads` workers (0 = one per core) within `budget` bytes; each light layer of `aovs` is one
/// more reference render, on the plan with the other lights and the background black (as the
/// pipeline's, `pipeline/aov.rs`). `cancel` is read between the stages (the reference itself
/// has no cancel point). Lights from in front of the viewer are a second pass, as the
/// pipeline's (`passes::render_passes`); with a perspective camera that pass traces on the
/// turned-round slab grid the sweep uses, along the eye's rays.
pub fn render_reference(
    scene: &Scene,
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
    aovs: &[Aov],
    cancel: Option<&AtomicBool>,
) -> Result<Rendered, RenderError> {
    refuse_lights_inside_meshes(scene)?;
    let run = ReferenceRun {
        threads,
        samples,
        budget,
        allow_open,
        cancel,
    };
    if scene.camera.is_perspective() && scene.passes().back.is_some() {
        let eye = convshadow_io::build_geometry(scene)?;
        return render_passes(scene, aovs, Mirror::No, |pass, aovs| {
            if pass.turned_round {
                perspective_far_end_pass(pass, &eye, run, aovs)
            } else {
                reference_pass(pass, run, aovs)
            }
        });
    }
    render_passes(scene, aovs, Mirror::Yes, |pass, aovs| {
        reference_pass(pass, run, aovs)
    })
}

/// A point or spot light inside a closed mesh is refused, naming the light and the mesh (exit code
/// 3): the mesh's inside would surround the light, and a shadow ray's inside test counts
/// crossings from the light's end, where every point must be outside.
fn refuse_lights_inside_meshes(scene: &Scene) -> Result<(), RenderError> {
    if scene.lights.iter().all(|l| l.point.is_none()) {
        return Ok(());
    }
    let geometry = convshadow_io::build_geometry(scene)?;
    for (i, light) in scene.lights.iter().enumerate() {
        let Some(point) = &light.point else { continue };
        if let Some(m) = closed_mesh_holding(&geometry, point.position) {
            return Err(RenderError::Scene(SceneError {
                file: scene.source.clone(),
                key: format!("light[{i}].position"),
                message: format!(
                    "the light is inside closed mesh[{m}]: a point or spot light must lie \
                     outside every closed mesh (its inside would surround the light)"
                ),
            }));
        }
    }
    Ok(())
}

/// [`render_reference`] of one pass (every light at the same end of the sweep).
fn reference_pass(
    scene: &Scene,
    run: ReferenceRun<'_>,
    aovs: &[Aov],
) -> Result<Rendered, RenderError> {
    let start = Instant::now();
    MemoryNeed::of(scene, scene.sweep.guard_band.lower_bound(), true).check(scene, run.budget)?;
    let pool = thread_pool(run.threads)?;
    let geometry = convshadow_io::build_geometry(scene)?;
    let fragment_budget =
        MemoryNeed::of(scene, geometry.raster.guard, true).check(scene, run.budget)?;
    check_cancel(run.cancel)?;
    let ldi = pool.install(|| Ldi::build(&geometry.raster, fragment_budget))?;
    let stats = pool.install(|| ldi.stats());
    refuse_open_meshes(scene, &geometry, &stats, run.allow_open)?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    let plan = convshadow_io::build_plan(scene, &geometry)
        .map_err(|e| RenderError::BadPlan(e.to_string()))?;
    let depth = aovs
        .contains(&Aov::Depth)
        .then(|| first_hit_depth(&plan, &ldi, geometry.z_origin));
    let view = View {
        ldi: &ldi,
        stats,
        ldi_hash: ldi.fingerprint(),
        eye: None,
        depth,
        times: (start, seconds_ldi, t_plan),
    };
    trace(scene, &geometry, plan, &view, run, aovs, &pool)
}

/// [`render_reference`]'s turned-round pass for a perspective camera: the tracer on the slab
/// grid the sweep turns round (`perspective::grid_scene` of `pass`, whose camera is turned), the
/// view samples along `eye`'s rays walked far to near (`perspective::turned_eye`).
fn perspective_far_end_pass(
    pass: &Scene,
    eye: &SceneGeometry,
    run: ReferenceRun<'_>,
    aovs: &[Aov],
) -> Result<Rendered, RenderError> {
    let start = Instant::now();
    let grid = perspective::grid_scene(pass, eye)?;
    MemoryNeed::of(&grid, grid.sweep.guard_band.lower_bound(), true).check(&grid, run.budget)?;
    let pool = thread_pool(run.threads)?;
    let geometry = convshadow_io::build_geometry(&grid)?;
    let fragment_budget =
        MemoryNeed::of(&grid, geometry.raster.guard, true).check(&grid, run.budget)?;
    check_cancel(run.cancel)?;
    let eye_ldi = pool.install(|| Ldi::build(&eye.raster, fragment_budget))?;
    let stats = pool.install(|| eye_ldi.stats());
    refuse_open_meshes(pass, eye, &stats, run.allow_open)?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    let plan = convshadow_io::build_plan(&grid, &geometry)
        .map_err(|e| RenderError::BadPlan(e.to_string()))?;
    let (ldi, raster) = perspective::turned_eye(eye, &eye_ldi, geometry.z_origin);
    let perspective::EyeOnGrid { zoom, axis, .. } =
        perspective::eye_on_grid(eye, &plan, pass.sweep.light_resolution);
    let view = View {
        ldi: &ldi,
        stats,
        ldi_hash: eye_ldi.fingerprint(),
        eye: Some(TurnedEye {
            width: eye.camera.width,
            height: eye.camera.height,
            axis,
            zoom,
            z_origin: -geometry.z_origin,
            raster: &raster,
        }),
        // The depth layer is the front pass's.
        depth: None,
        times: (start, seconds_ldi, t_plan),
    };
    trace(&grid, &geometry, plan, &view, run, aovs, &pool)
}

/// What the reference's view samples walk: the LDI (and its statistics and hash, reported), the
/// eye's rays where the tracer's grid is a turned-round one, the depth layer if asked, and when
/// the pass started, how long its LDI took and when its plan started.
struct View<'a> {
    ldi: &'a Ldi,
    stats: LdiStats,
    ldi_hash: u64,
    eye: Option<TurnedEye<'a>>,
    depth: Option<Vec<f32>>,
    times: (Instant, f64, Instant),
}

/// The reference's image (and light layers) of `scene` on `geometry` and `plan`, along `view`.
fn trace(
    scene: &Scene,
    geometry: &SceneGeometry,
    plan: RenderPlan,
    view: &View<'_>,
    run: ReferenceRun<'_>,
    aovs: &[Aov],
    pool: &rayon::ThreadPool,
) -> Result<Rendered, RenderError> {
    let (start, seconds_ldi, t_plan) = view.times;
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    check_cancel(run.cancel)?;
    let t_render = Instant::now();
    let options = ReferenceOptions {
        samples: run.samples,
        ..ReferenceOptions::default()
    };
    fn reference<'a>(
        scene: &Scene,
        geometry: &'a SceneGeometry,
        plan: &'a RenderPlan,
        eye: Option<TurnedEye<'a>>,
    ) -> Reference<'a> {
        let r = Reference::new(scene, geometry, plan, 0.0);
        match eye {
            Some(eye) => r.with_turned_eye(eye),
            None => r,
        }
    }
    let (data, alpha) = pool.install(|| {
        reference(scene, geometry, &plan, view.eye).render_with_alpha(view.ldi, &options)
    });
    let seconds_sweep = t_render.elapsed().as_secs_f64();
    let mut plan = plan;
    let colors = LightColors::of(&plan);
    let mut light_layers = Vec::new();
    for aov in aovs {
        if let Aov::Light(l) = *aov {
            check_cancel(run.cancel)?;
            colors.isolate(&mut plan, l);
            light_layers.push((
                l,
                pool.install(|| {
                    reference(scene, geometry, &plan, view.eye).render(view.ldi, &options)
                }),
            ));
            colors.restore(&mut plan);
        }
    }
    let (width, height) = view
        .eye
        .map_or((scene.image.width, scene.image.height), |e| {
            (e.width, e.height)
        });
    Ok(Rendered {
        mesh_warnings: geometry.mesh_warnings(),
        image_hash: image_fingerprint(&data),
        image: RgbImage {
            width,
            height,
            data,
        },
        alpha,
        depth: view.depth.clone(),
        light_layers,
        ldi: view.stats,
        ldi_hash: view.ldi_hash,
        turned_round_lights: if plan.turned_round {
            plan.lights.len()
        } else {
            0
        },
        plan,
        light: Vec::new(),
        // The reference traces shadow rays: it sweeps no slab.
        slabs_swept: 0,
        updates: 0.0,
        threads: pool.current_num_threads(),
        seconds_ldi,
        seconds_plan,
        seconds_sweep,
        chunks: [0; 3],
        seconds_total: start.elapsed().as_secs_f64(),
        backend: "reference",
        adapter: None,
        backend_note: None,
    })
}
