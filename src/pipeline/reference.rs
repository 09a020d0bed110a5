//! The ground-truth reference (`convshadow render --backend reference`, the Python module's
//! `backend="reference"`): the shadow-ray renderer behind the same checks and LDI as the
//! pipeline.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use convshadow_common::model::scene::Scene;
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_io::image::RgbImage;
use convshadow_reference::{Reference, ReferenceOptions};

use super::passes::{Mirror, render_passes};
use super::{
    Aov, LightColors, MemoryNeed, RenderError, Rendered, check_cancel, first_hit_depth,
    image_fingerprint, refuse_open_meshes, thread_pool,
};

/// Renders with the ground-truth reference: the same checks and LDI as the pipeline, then
/// [`Reference::render_with_alpha`] with `samples` light directions per shading point, on
/// `threads` workers (0 = one per core) within `budget` bytes; each light layer of `aovs` is one
/// more reference render, on the plan with the other lights and the background black (as the
/// pipeline's, `pipeline/aov.rs`). `cancel` is read between the stages (the reference itself
/// has no cancel point). Lights from in front of the viewer are a second pass, as the
/// pipeline's (`passes::render_passes`).
pub fn render_reference(
    scene: &Scene,
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
    aovs: &[Aov],
    cancel: Option<&AtomicBool>,
) -> Result<Rendered, RenderError> {
    if scene.camera.is_perspective() && scene.passes().back.is_some() {
        // The tracer sends its shadow rays towards depth 0 only (docs/ARCHITECTURE.md).
        return Err(RenderError::BadPlan(format!(
            "{}: key `camera.projection`: with a perspective camera the shadow-ray reference \
             takes lights from behind the viewer only (travelling less than 90° from the view) \
             yet, not a light travelling towards the viewer; the sweep (`--backend cpu` or \
             `gpu`) renders it",
            scene.source
        )));
    }
    render_passes(scene, aovs, Mirror::Yes, |pass, aovs| {
        reference_pass(pass, threads, samples, budget, allow_open, aovs, cancel)
    })
}

/// [`render_reference`] of one pass (every light at the same end of the sweep).
fn reference_pass(
    scene: &Scene,
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
    aovs: &[Aov],
    cancel: Option<&AtomicBool>,
) -> Result<Rendered, RenderError> {
    let start = Instant::now();
    MemoryNeed::of(scene, scene.sweep.guard_band.lower_bound(), true).check(scene, budget)?;
    let pool = thread_pool(threads)?;
    let geometry = convshadow_io::build_geometry(scene)?;
    let fragment_budget =
        MemoryNeed::of(scene, geometry.raster.guard, true).check(scene, budget)?;
    check_cancel(cancel)?;
    let ldi = pool.install(|| Ldi::build(&geometry.raster, fragment_budget))?;
    let stats = pool.install(|| ldi.stats());
    refuse_open_meshes(scene, &geometry, &stats, allow_open)?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    let plan = convshadow_io::build_plan(scene, &geometry)
        .map_err(|e| RenderError::BadPlan(e.to_string()))?;
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    check_cancel(cancel)?;
    let t_render = Instant::now();
    let options = ReferenceOptions {
        samples,
        ..ReferenceOptions::default()
    };
    let (data, alpha) = {
        let reference = Reference::new(scene, &geometry, &plan, 0.0);
        pool.install(|| reference.render_with_alpha(&ldi, &options))
    };
    let seconds_sweep = t_render.elapsed().as_secs_f64();
    let mut plan = plan;
    let colors = LightColors::of(&plan);
    let mut light_layers = Vec::new();
    for aov in aovs {
        if let Aov::Light(l) = *aov {
            check_cancel(cancel)?;
            colors.isolate(&mut plan, l);
            let reference = Reference::new(scene, &geometry, &plan, 0.0);
            light_layers.push((l, pool.install(|| reference.render(&ldi, &options))));
            colors.restore(&mut plan);
        }
    }
    let depth = aovs
        .contains(&Aov::Depth)
        .then(|| first_hit_depth(&plan, &ldi, geometry.z_origin));
    Ok(Rendered {
        mesh_warnings: geometry.mesh_warnings(),
        image_hash: image_fingerprint(&data),
        image: RgbImage {
            width: scene.image.width,
            height: scene.image.height,
            data,
        },
        alpha,
        depth,
        light_layers,
        ldi: stats,
        ldi_hash: ldi.fingerprint(),
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
