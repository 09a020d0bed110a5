//! A perspective camera on the CPU sweep (docs/how-it-works.md, "A perspective camera"): the
//! light is swept on an orthographic slab grid around the view axis that holds every mesh within
//! the view's frustum (the same slab planes and depths as the eye's), and the eye's rays read it
//! slab by slab (`convshadow_cpu::sweep::sweep_perspective`).

use std::time::Instant;

use convshadow_common::contract::ldi::{BYTES_PER_FRAGMENT, Ldi};
use convshadow_common::model::scene::{
    CameraSpec, GuardBandSpec, MAX_IMAGE_SIDE, Projection, Scene, SlabSpec,
};
use convshadow_common::prepare::camera::Camera;
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_common::prepare::raster::RasterSetup;
use convshadow_cpu::sweep::{
    ChunkCounts, CpuOptions, EyePoint, EyeView, SweepOptions, SweepOutput, sweep_perspective,
};
use convshadow_io::image::RgbImage;
use glam::DVec3;

use super::aov::{first_hit_depth_in, light_layers};
use super::budget::LDI_BYTES_PER_PIXEL;
use super::passes::{Mirror, render_passes};
use super::point::{on_point_grid, point_grid};
use super::{
    Aov, Backend, Engine, RenderError, RenderRequest, Rendered, check_cancel, image_fingerprint,
    plan_updates, refuse_open_meshes,
};
use convshadow_common::plan::RenderPlan;
use convshadow_common::plan::point_light::{PointShading, PointSource, phase_constants};

/// The orthographic scene whose sweep carries the light for `scene`'s perspective camera: the
/// same view axis and `up`, cells of the eye's pixel size (the footprint at the `look_at`
/// distance) over `sweep.light_resolution`, centred on the eye (so every view depth is the eye's
/// bit for bit), `eye`'s slab count, and a grid that holds every vertex within the frustum,
/// symmetric about the axis.
///
/// An orthographic camera's grid (`sweep.light_resolution` ≠ 1) is its own view: the same camera,
/// cells of its pixel over the light resolution, an even number of them across each way (at
/// least the image's width; centred on it), its own guard band.
pub(super) fn grid_scene(scene: &Scene, eye: &SceneGeometry) -> Result<Scene, RenderError> {
    let cam = &eye.camera;
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    let too_large = |gw: f64, gh: f64| {
        RenderError::OutOfMemory(format!(
            "{}: the view's light grid would be {gw} × {gh} pixels, more than {MAX_IMAGE_SIDE} a \
             side; lower sweep.light_resolution{}",
            scene.source,
            if cam.focal_px.is_some() {
                ", narrow camera.fov_deg or the scene's depth"
            } else {
                " or the image size"
            }
        ))
    };
    // Half-widths in the grid's cells (eye pixels times the light resolution).
    let cells = scene.sweep.light_resolution;
    let cell = cam.pixel_size / cells;
    let (gw, gh) = match cam.focal_px {
        None => {
            let side = |image: f64| 2.0 * (0.5 * image * cells).ceil();
            (side(w), side(h))
        }
        Some(focal) => {
            let (mut half_x, mut half_y, mut z_max) = (0.0f64, 0.0f64, 0.0f64);
            for m in &eye.meshes {
                for p in &m.mesh.positions {
                    let g = cam.to_grid(*p);
                    half_x = half_x.max((g.x - 0.5 * w).abs());
                    half_y = half_y.max((g.y - 0.5 * h).abs());
                    z_max = z_max.max(g.z);
                }
            }
            // Nothing beyond the frustum at the farthest depth can shadow what the eye sees, but
            // through the guard band the grid adds for the lights' reach.
            let frustum = z_max / (focal * cam.pixel_size);
            let side = |half: f64, image: f64| {
                2.0 * (half.min(0.5 * image * frustum) * cells + 2.0).ceil()
            };
            (side(half_x, w), side(half_y, h))
        }
    };
    if gw > f64::from(MAX_IMAGE_SIDE) || gh > f64::from(MAX_IMAGE_SIDE) {
        return Err(too_large(gw, gh));
    }
    let mut grid = scene.clone();
    grid.camera = CameraSpec {
        view_width: gw * cell,
        projection: Projection::Orthographic,
        ..scene.camera.clone()
    };
    grid.image.width = gw as u32;
    grid.image.height = gh as u32;
    grid.sweep.slabs = SlabSpec::Count(eye.slabs);
    Ok(grid)
}

/// The bytes the eye adds to its slab grid's need before any fragment (`budget::MemoryNeed` counts
/// the grid's): its LDI's per-pixel arrays, its per-pixel state (cursor, inside bits, colour,
/// alpha, and a byte for each run of 8 pixels' 4-byte wake, rounded up), its image as floats,
/// 8-bit and encoded, and on the GPU its device buffers (cursors, colours, LDI offsets, the RGBA
/// image and its read-back copy). (A row's samples between cursor and shading, about 100 bytes
/// per pixel of one row per thread, are left out: rows, not the image.)
fn eye_need(eye: &SceneGeometry, backend: Backend) -> u64 {
    let pixels = u64::from(eye.camera.width) * u64::from(eye.camera.height);
    let host = LDI_BYTES_PER_PIXEL + (4 + 4 + 12 + 4 + 1) + (12 + 4 + 3 + 3);
    let device = if backend == Backend::Gpu {
        8 + 16 + 4 + 16 + 16
    } else {
        0
    };
    (host + device) * pixels
}

/// The fragment budget the grid's need left, less the eye's need ([`eye_need`]); refused when the
/// eye does not fit.
fn within_budget_after_eye(
    scene: &Scene,
    eye: &SceneGeometry,
    fragment_budget: u64,
    backend: Backend,
) -> Result<u64, RenderError> {
    let need = eye_need(eye, backend);
    fragment_budget.checked_sub(need).ok_or_else(|| {
        RenderError::OutOfMemory(format!(
            "{}: the perspective view's {} × {} image needs {} MiB more (its LDI arrays, per-pixel \
             state and output) than the memory budget leaves beside its light grid; lower \
             image.width/image.height or raise --max-memory",
            scene.source,
            eye.camera.width,
            eye.camera.height,
            (need - fragment_budget).div_ceil(1 << 20)
        ))
    })
}

/// The eye's rays on the slab grid of `plan`: grid pixels per image pixel of offset per unit of
/// view depth (`light_resolution / (focal · pixel_size)`: the grid's cells are the eye's pixel
/// at `look_at` over the light resolution), and where the view axis meets the grid's image (its
/// centre: the grid is symmetric about the axis), in its image pixels (the guard band not
/// counted: the sweep's buffers add it, the reference's tracer works without it).
pub(super) fn eye_on_grid(
    eye: &SceneGeometry,
    plan: &RenderPlan,
    light_resolution: f64,
) -> EyeOnGrid {
    let cam = &eye.camera;
    let (zoom, scale) = match cam.focal_px {
        Some(f) => (light_resolution / (f * cam.pixel_size), 0.0),
        // An orthographic eye reads the grid at the same scale at every depth.
        None => (0.0, light_resolution),
    };
    EyeOnGrid {
        zoom,
        scale,
        axis: [f64::from(plan.width / 2), f64::from(plan.height / 2)],
    }
}

/// Where the eye's rays read the grid ([`eye_on_grid`]): grid pixel `axis + offset·(scale + z·zoom)`
/// for an eye pixel `offset` from the image centre at view depth z.
pub(super) struct EyeOnGrid {
    /// Grid pixels per image pixel of offset per unit of view depth (perspective; else 0).
    pub(super) zoom: f64,
    /// Grid pixels per image pixel of offset at any depth (orthographic; else 0).
    pub(super) scale: f64,
    /// Where the view axis meets the grid's image, its image pixels (no guard band).
    pub(super) axis: [f64; 2],
}

/// The eye's LDI and rasterizer set-up as a turned-round pass walks them: each ray's fragments
/// far to near at the turned grid's relative depths (`−z` from the eye, less the grid's origin
/// `z_grid` in those depths),
/// the normals as the turned camera sees them (x and z reversed).
pub(super) fn turned_eye(eye: &SceneGeometry, eye_ldi: &Ldi, z_grid: f64) -> (Ldi, RasterSetup) {
    let z_eye = eye.z_origin;
    let ldi = eye_ldi.turned_round(|d| (-(z_eye + f64::from(d)) - z_grid) as f32);
    let mut raster = eye.raster.clone();
    for t in &mut raster.triangles {
        t.normal = [-t.normal[0], t.normal[1], -t.normal[2]];
    }
    (ldi, raster)
}

/// [`super::render`] for a perspective camera, or an orthographic one whose light grid is not its
/// image's pixels (`sweep.light_resolution` ≠ 1): the eye's geometry once, then a pass per end of
/// the sweep (`passes::render_passes`; the lights travelling towards the viewer swept from the
/// far end, their image the eye's, not mirrored).
pub(super) fn render_perspective(
    scene: &Scene,
    req: &RenderRequest<'_>,
) -> Result<Rendered, RenderError> {
    let eye = eye_geometry(scene)?;
    render_passes(scene, &req.aovs, Mirror::No, |pass, aovs| {
        render_perspective_pass(pass, &eye, req, aovs, None)
    })
}

/// The eye's geometry for the eye pass: a perspective camera's, or an orthographic camera's
/// without its guard band (its LDI is its image's pixels alone: the guard band is the grid's).
pub(super) fn eye_geometry(scene: &Scene) -> Result<SceneGeometry, RenderError> {
    Ok(if scene.camera.is_perspective() {
        convshadow_io::build_geometry(scene)?
    } else {
        let mut bare = scene.clone();
        bare.sweep.guard_band = GuardBandSpec::Pixels(0);
        convshadow_io::build_geometry(&bare)?
    })
}

/// One pass of [`render_perspective`]: `pass` has its lights (and, turned round, its camera's
/// direction reversed), `eye` the scene's eye. `point`: `pass` has one light, a point or spot
/// light, swept on its own grid ([`point_grid`]) instead of the slab grid, where the eye's rays
/// meet the meshes between these points ([`super::point::visible_points`]).
pub(super) fn render_perspective_pass(
    pass: &Scene,
    eye: &SceneGeometry,
    req: &RenderRequest<'_>,
    aovs: &[Aov],
    point: Option<&[DVec3]>,
) -> Result<Rendered, RenderError> {
    let scene = pass;
    let start = Instant::now();
    let point_grid = match point {
        Some(visible) => {
            let frame = grid_scene(scene, eye)?;
            let frame = Camera::new(&frame.camera, &frame.image);
            Some(point_grid(scene, eye, frame, visible, 0)?)
        }
        None => None,
    };
    let grid = match &point_grid {
        Some(p) => p.scene.clone(),
        None => grid_scene(scene, eye)?,
    };
    let engine = Engine::open(&grid, true, req.backend, req.threads, req.memory_budget)?;
    let (geometry, fragment_budget) = engine.geometry(&grid, req.memory_budget)?;
    let fragment_budget =
        within_budget_after_eye(scene, eye, fragment_budget, engine.choice.opened())?;
    // `camera.near`: the grid's sweep starts where the eye's does, in the eye's slabs (the
    // turned-round grid sweeps the meshes' own range from the far end).
    let near = matches!(
        scene.camera.projection,
        Projection::Perspective { near: Some(_), .. }
    );
    let geometry = match &point_grid {
        // A point light's grid measures view depth from the light: the eye's slabs there.
        Some(p) => geometry.with_slabs(&grid, p.origin, eye.slab_distance, eye.slabs)?,
        None if near && !scene.turned_round => {
            geometry.with_slabs(&grid, eye.z_origin, eye.slab_distance, eye.slabs)?
        }
        None => geometry,
    };
    if !scene.turned_round
        && point_grid.is_none()
        && (geometry.z_origin, geometry.slab_distance, geometry.slabs)
            != (eye.z_origin, eye.slab_distance, eye.slabs)
    {
        return Err(RenderError::BadPlan(format!(
            "{}: the perspective view's light grid and its eye disagree on the slabs ({} slabs of \
             {:e} from {:e} against {} of {:e} from {:e}); please report this",
            scene.source,
            geometry.slabs,
            geometry.slab_distance,
            geometry.z_origin,
            eye.slabs,
            eye.slab_distance,
            eye.z_origin
        )));
    }
    check_cancel(req.cancel)?;
    // Both LDIs' fragments within the one budget: the eye's first, the grid's in what it left.
    let eye_ldi = engine.ldi(eye, fragment_budget)?;
    let eye_bytes = eye_ldi.depth.len() as u64 * BYTES_PER_FRAGMENT;
    let ldi = engine.ldi(&geometry, fragment_budget.saturating_sub(eye_bytes))?;
    check_cancel(req.cancel)?;
    let stats = engine.pool.install(|| eye_ldi.stats());
    refuse_open_meshes(scene, eye, &stats, req.allow_open)?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    let fragments = stats.fragments + engine.pool.install(|| ldi.stats()).fragments;
    let allowance = super::budget::table_allowance(fragment_budget, fragments);
    let mut plan = engine.plan(&grid, &geometry, req.cancel, allowance, fragments)?;
    if point_grid.is_some() {
        on_point_grid(&mut plan, &grid, &geometry);
    }
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    engine.check_tables(&grid, &plan, fragment_budget, fragments)?;
    check_cancel(req.cancel)?;
    let t_sweep = Instant::now();
    let cam = &eye.camera;
    // Turned round, the grid's relative depth 0 in the turned camera's depths (a point light's
    // grid measures its depths from the light).
    let turned_origin = point_grid
        .as_ref()
        .map_or(geometry.z_origin, |p| p.frame_z_origin);
    let turned = scene
        .turned_round
        .then(|| turned_eye(eye, &eye_ldi, turned_origin));
    let (view_ldi, view_raster, z_origin) = match &turned {
        Some((ldi, raster)) => (ldi, raster, -turned_origin),
        None => (&eye_ldi, &eye.raster, eye.z_origin),
    };
    let EyeOnGrid { zoom, scale, axis } = eye_on_grid(eye, &plan, pass.sweep.light_resolution);
    let phase: Vec<[f32; 3]> = (scene.meshes.iter())
        .map(|m| phase_constants(scene.materials[m.material].phase_g))
        .collect();
    let point_shading = point_grid.as_ref().map(|p| {
        let light = scene.lights[0].point.as_ref().expect("a point pass");
        let pattern = (scene.lights[0].pattern.as_ref())
            .zip(plan.spot_patterns.first().and_then(Option::as_ref));
        let source = PointSource::new(light, pattern, &p.frame, p.frame_z_origin);
        PointShading::new(&source, scene.lights[0].color, scene.turned_round)
    });
    let eye_point = point_grid
        .as_ref()
        .zip(point_shading.as_ref())
        .map(|(p, shading)| {
            let frame_axis = [p.frame.width as f32 * 0.5, p.frame.height as f32 * 0.5];
            let focal = geometry
                .camera
                .focal_px
                .expect("a point light's grid is perspective");
            EyePoint {
                shading,
                phase: &phase,
                frame_axis,
                offset: [
                    shading.center[0] - frame_axis[0],
                    shading.center[1] - frame_axis[1],
                ],
                depth: p.depth as f32,
                // Turned round, the grid looks back along the view: its depth from the light
                // is the light's view depth less the sample's.
                focal: (if scene.turned_round { -1.0 } else { 1.0 } * p.frame.pixel_size * focal)
                    as f32,
            }
        });
    let view = EyeView {
        ldi: view_ldi,
        raster: view_raster,
        width: cam.width,
        height: cam.height,
        zoom: zoom as f32,
        scale: scale as f32,
        z_origin: z_origin as f32,
        turned_round: scene.turned_round,
        point: eye_point,
        axis: [
            (axis[0] + f64::from(plan.guard.left)) as f32,
            (axis[1] + f64::from(plan.guard.top)) as f32,
        ],
    };
    // A light's pattern (gobo) is its initial light buffer, the same for every layer's sweep.
    let initial_light = plan.initial_light.clone();
    let options = SweepOptions {
        progress: req.progress,
        cancel: req.cancel,
        initial_light: initial_light.as_deref(),
        every_slab: req.every_slab,
    };
    let chunk_counts = ChunkCounts::default();
    let cpu = CpuOptions {
        path: req.path.sweep_path(),
        skip_quiet: req.skip_quiet,
        chunk_counts: Some(&chunk_counts),
    };
    let run = |plan: &RenderPlan, cpu: &CpuOptions<'_>| -> Result<SweepOutput, RenderError> {
        match &engine.choice.gpu {
            Some(ctx) => Ok(convshadow_gpu::eye::sweep_perspective(
                ctx,
                plan,
                &geometry.raster,
                &ldi,
                &view,
                &options,
            )?),
            None => engine
                .pool
                .install(|| sweep_perspective(plan, &geometry.raster, &ldi, &view, &options, cpu))
                .map_err(|_| RenderError::Interrupted),
        }
    };
    let out = run(&plan, &cpu)?;
    let seconds_sweep = t_sweep.elapsed().as_secs_f64();
    // The extra layers, as `super::render_pass` makes them: one more sweep per light layer on
    // the plan with the other lights and the background black; the depth from the eye's LDI.
    let light_layers = light_layers(&mut plan, aovs, req.cancel, |plan| {
        Ok(run(plan, &CpuOptions::default())?.image)
    })?;
    let image = (cam.width as usize, cam.height as usize);
    let depth = aovs
        .contains(&Aov::Depth)
        .then(|| first_hit_depth_in(&eye_ldi, (0, 0), image, eye.z_origin));
    Ok(Rendered {
        mesh_warnings: eye.mesh_warnings(),
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
        ldi_hash: eye_ldi.fingerprint(),
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
