//! Running the grid: each case against its reference, then the files.

use std::time::Instant;

use convshadow_common::model::scene::{Penumbra, Scene, SlabSpec};
use convshadow_common::plan::RenderPlan;
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_cpu::sweep::{SweepOptions, sweep};
use convshadow_io::metrics::rmse;
use convshadow_reference::disk::DiskSetup;
use convshadow_reference::edge::{self, EdgeSetup, model_profile, run_light};
use convshadow_reference::{Reference, ReferenceOptions};

use super::grid::{
    NARROWBAND_REFERENCE_SLABS, ReportOptions, SLAB_COUNTS, TILTS, VARIANCES, disk_setup,
    edge_setup, kernels,
};
use super::row::{Report, Row};
use super::{csv, direction, markdown, perspective, plot, point};

/// Runs one edge case.
pub fn edge_row(setup: &EdgeSetup, level: &str) -> Row {
    let (profile, seconds) = setup.profile();
    let d = setup.distance();
    let sigma = setup.variance.sqrt();
    let center = setup.expected_isoline();
    let std_correct = d * sigma / setup.pixel_size;
    let std_iter = (d * setup.optimal_distance).sqrt() * sigma / setup.pixel_size;
    let correct = model_profile(profile.len(), center, std_correct);
    let iterated = model_profile(profile.len(), center, std_iter);
    let from = setup.first_trusted_column();
    // The window: the penumbra of either model plus 3 px, inside the trusted columns.
    let half = 4.0 * std_correct.max(std_iter) + 3.0;
    let lo = ((center - half).floor().max(from as f64)) as usize;
    let hi = ((center + half).ceil() as usize).min(profile.len());
    let measure = |p: &[f64]| (edge::half_crossing(p, from), edge::width_10_90(p, from));
    let (iso, width) = measure(&profile);
    let (iso_c, width_c) = measure(&correct);
    let (_, width_i) = measure(&iterated);
    let diff = |a: Option<f64>, b: Option<f64>| Some(a? - b?);
    let mut note = String::new();
    if iso.is_none() || width.is_none() {
        note = "the profile never crosses 0.1/0.5/0.9 in the trusted columns".into();
    }
    Row {
        family: "edge".into(),
        kernel: setup.kernel.clone(),
        penumbra: setup.penumbra.to_string(),
        slabs: setup.slabs,
        variance_level: level.into(),
        variance: Some(setup.variance),
        tilt_deg: Some(setup.tilt_deg),
        distance_over_d1: Some(d / setup.optimal_distance),
        compensation: setup.compensation,
        preintegration: false,
        width: setup.width,
        height: setup.height,
        time_ms: seconds * 1e3,
        rmse_correct: Some(rmse((lo..hi).map(|i| (profile[i], correct[i])))),
        rmse_iterated: Some(rmse((lo..hi).map(|i| (profile[i], iterated[i])))),
        isoline_err_px: diff(iso, iso_c),
        width_err_correct_px: diff(width, width_c),
        width_err_iterated_px: diff(width, width_i),
        width_px: width,
        rmse_reference: None,
        reference_self_err: None,
        view_angle_deg: None,
        fov_deg: None,
        light_resolution: None,
        note: if note.is_empty() {
            "analytic case: closed-form references, no shadow-ray reference needed".into()
        } else {
            note
        },
    }
}

/// Disk references for one (d, tilt, σ²): the correct and the iterated light per pixel.
struct DiskReference {
    correct: Vec<f64>,
    iterated: Vec<f64>,
    window: Vec<usize>,
    perimeter: f64,
}

fn disk_reference(setup: &DiskSetup) -> DiskReference {
    let scene = setup.scene().unwrap_or_else(|e| panic!("{e}"));
    let g = convshadow_io::build_geometry(&scene).unwrap_or_else(|e| panic!("{e}"));
    let d = setup.distance();
    let correct = setup.reference_light(&g, d * d);
    let iterated = setup.reference_light(&g, d * setup.optimal_distance);
    let poly = setup.polygon(&g);
    let perimeter: f64 = (0..poly.len())
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt()
        })
        .sum();
    // Window: pixels away from the border (8 px) where either reference is below 1 − 1e-9 or
    // within 3 px of such a pixel's box: the shadow and its penumbra.
    let (w, h) = (setup.width as usize, setup.height as usize);
    let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            if correct[i].min(iterated[i]) < 1.0 - 1e-9 {
                x0 = x0.min(x);
                x1 = x1.max(x);
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
        }
    }
    let window = (y0.saturating_sub(3).max(8)..(y1 + 4).min(h - 8))
        .flat_map(|y| (x0.saturating_sub(3).max(8)..(x1 + 4).min(w - 8)).map(move |x| y * w + x))
        .collect();
    DiskReference {
        correct,
        iterated,
        window,
        perimeter,
    }
}

/// Area (px²) of `{v < level}` over the window.
fn area_below(v: &[f64], window: &[usize], level: f64) -> f64 {
    window.iter().filter(|&&i| v[i] < level).count() as f64
}

fn disk_row(setup: &DiskSetup, level: &str, r: &DiskReference) -> Row {
    let scene = setup.scene().unwrap_or_else(|e| panic!("{e}"));
    let (plan, out, seconds) = run_light(&scene, None);
    let w = plan.grid_width as usize;
    let light: Vec<f64> = (0..plan.grid_height as usize * w)
        .map(|i| edge::light_at(&plan, &out, i % w, i / w))
        .collect();
    let win = &r.window;
    // Mean isoline displacement: symmetric difference of the half-shadow regions / perimeter.
    let sym = win
        .iter()
        .filter(|&&i| (light[i] < 0.5) != (r.correct[i] < 0.5))
        .count() as f64;
    let width = |v: &[f64]| (area_below(v, win, 0.9) - area_below(v, win, 0.1)) / r.perimeter;
    let (wm, wc, wi) = (width(&light), width(&r.correct), width(&r.iterated));
    Row {
        family: "disk".into(),
        kernel: setup.kernel.clone(),
        penumbra: setup.penumbra.to_string(),
        slabs: setup.slabs,
        variance_level: level.into(),
        variance: Some(setup.variance[0]),
        tilt_deg: Some(setup.tilt_deg),
        distance_over_d1: Some(setup.distance() / setup.optimal_distance),
        compensation: setup.compensation,
        preintegration: false,
        width: setup.width,
        height: setup.height,
        time_ms: seconds * 1e3,
        rmse_correct: Some(rmse(win.iter().map(|&i| (light[i], r.correct[i])))),
        rmse_iterated: Some(rmse(win.iter().map(|&i| (light[i], r.iterated[i])))),
        isoline_err_px: Some(sym / r.perimeter),
        width_err_correct_px: Some(wm - wc),
        width_err_iterated_px: Some(wm - wi),
        width_px: Some(wm),
        rmse_reference: None,
        reference_self_err: None,
        view_angle_deg: None,
        fov_deg: None,
        light_resolution: None,
        note: "analytic case (numerical f64 disk convolution); isoline error = mean unsigned \
               displacement (symmetric-difference area / perimeter); widths = area between the \
               0.1 and 0.9 levels / perimeter"
            .into(),
    }
}

/// A sweep of a full scene: (plan, geometry, ldi, image, seconds).
fn render_scene(scene: &Scene) -> (RenderPlan, SceneGeometry, Ldi, Vec<f32>, f64) {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 8 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = convshadow_io::build_plan(scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let t = Instant::now();
    let out =
        sweep(&plan, &g.raster, &ldi, &SweepOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    (plan, g, ldi, out.image, t.elapsed().as_secs_f64())
}

/// RMSE of two float images, through [`rmse`].
fn rmse_f32(a: &[f32], b: &[f32]) -> f64 {
    rmse(a.iter().zip(b).map(|(x, y)| (f64::from(*x), f64::from(*y))))
}

/// The default scene at `size`² with `slabs`: one row per kernel against the reference.
fn scene_rows(
    size: u32,
    slabs: u32,
    samples: u32,
    penumbras: &[Penumbra],
    verbose: bool,
) -> Vec<Row> {
    let mut base = Scene::default_scene();
    base.image.width = size;
    base.image.height = size;
    base.sweep.slabs = SlabSpec::Count(slabs);
    // The reference depends on the view samples (slab count, jitter), not on the kernel.
    let (plan, g, ldi, _, _) = render_scene(&base);
    let reference = Reference::new(&base, &g, &plan, 0.0);
    let t = Instant::now();
    let ref_m = reference.render(
        &ldi,
        &ReferenceOptions {
            samples,
            ..Default::default()
        },
    );
    let ref_4m = reference.render(
        &ldi,
        &ReferenceOptions {
            samples: 4 * samples,
            ..Default::default()
        },
    );
    let self_err = rmse_f32(&ref_m, &ref_4m);
    if verbose {
        crate::errln!(
            "scene {size}² slabs {slabs}: reference M={samples} and {} in {:.1} s, self error {self_err:.2e}",
            4 * samples,
            t.elapsed().as_secs_f64()
        );
    }
    kernels()
        .flat_map(|k| penumbras.iter().map(move |&p| (k, p)))
        .map(|(k, penumbra)| {
            let mut scene = base.clone();
            scene.sweep.kernel = k.parse().unwrap_or_else(|e: String| panic!("{e}"));
            scene.sweep.penumbra = penumbra;
            let (_, _, _, image, seconds) = render_scene(&scene);
            Row {
                family: "scene".into(),
                kernel: k.to_string(),
                penumbra: penumbra.to_string(),
                slabs,
                variance_level: "scene".into(),
                compensation: scene.sweep.variance_compensation,
                preintegration: false,
                width: size,
                height: size,
                time_ms: seconds * 1e3,
                // Against the 4·M run, the better estimate of the truth.
                rmse_reference: Some(rmse_f32(&image, &ref_4m)),
                reference_self_err: Some(self_err),
                note: "full scene (the scene's own lights): no closed form, so only the \
                       shadow-ray reference; variance/tilt/distance are the scene's"
                    .into(),
                ..Row::default()
            }
        })
        .collect()
}

/// The narrow-band example scene (`scenes/narrowband.toml`, compiled in) at `size`² with `slabs`
/// and pre-integration on or off.
pub fn narrowband_scene(size: u32, slabs: u32, preintegration: bool) -> Scene {
    let mut scene = Scene::parse(
        include_str!("../../scenes/narrowband.toml"),
        "scenes/narrowband.toml",
        std::path::Path::new("scenes"),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    scene.image.width = size;
    scene.image.height = size;
    scene.sweep.slabs = SlabSpec::Count(slabs);
    scene.sweep.preintegration = preintegration;
    scene
}

/// The narrow-band family at `size`²: per slab count, `ellipse2` without and with
/// pre-integration, against the 2048-slab sweep without it.
fn narrowband_rows(size: u32, slab_counts: &[u32], verbose: bool) -> Vec<Row> {
    let n_ref = NARROWBAND_REFERENCE_SLABS;
    let (_, _, _, reference, _) = render_scene(&narrowband_scene(size, n_ref, false));
    let (_, _, _, finer, _) = render_scene(&narrowband_scene(size, 2 * n_ref, false));
    let self_err = rmse_f32(&reference, &finer);
    if verbose {
        crate::errln!(
            "narrowband {size}²: reference {n_ref} slabs, self error (vs {}) {self_err:.2e}",
            2 * n_ref
        );
    }
    let mut rows = Vec::new();
    for &n in slab_counts {
        for pre in [false, true] {
            let scene = narrowband_scene(size, n, pre);
            let (_, _, _, image, seconds) = render_scene(&scene);
            rows.push(Row {
                family: "narrowband".into(),
                kernel: scene.sweep.kernel.to_string(),
                penumbra: scene.sweep.penumbra.to_string(),
                slabs: n,
                variance_level: "scene".into(),
                compensation: scene.sweep.variance_compensation,
                preintegration: pre,
                width: size,
                height: size,
                time_ms: seconds * 1e3,
                rmse_reference: Some(rmse_f32(&image, &reference)),
                reference_self_err: Some(self_err),
                note: format!(
                    "scenes/narrowband.toml against its {n_ref}-slab sweep without pre-integration (self-error: against {} slabs); no closed form",
                    2 * n_ref
                ),
                ..Row::default()
            });
        }
    }
    rows
}

/// The narrow-band family: both compositing modes at each slab count (one reference for all).
fn narrowband_cases(cases: &mut Cases<'_>) {
    let (size, slab_counts): (u32, &[u32]) = if cases.options.quick {
        (48, &[64, 128])
    } else {
        (64, &SLAB_COUNTS)
    };
    let group = cases.next..cases.next + 2 * slab_counts.len();
    cases.next = group.end;
    if !group.clone().any(|i| cases.want(i)) {
        return;
    }
    for (i, row) in group.zip(narrowband_rows(size, slab_counts, cases.options.verbose)) {
        if cases.want(i) {
            cases.push(row);
        }
    }
}

/// The rows computed so far and the case numbering: cases are numbered in row order; with
/// `options.case` only that one is computed.
struct Cases<'a> {
    options: &'a ReportOptions,
    /// The index the next case gets (after all families: the case count).
    next: usize,
    rows: Vec<Row>,
}

impl Cases<'_> {
    /// Whether case `i` is computed.
    fn want(&self, i: usize) -> bool {
        self.options.case.is_none_or(|c| c == i)
    }

    /// Logs `row` (when verbose) and keeps it.
    fn push(&mut self, row: Row) {
        log_row(self.options, &row);
        self.rows.push(row);
    }
}

/// One line per case on stderr, when verbose.
fn log_row(options: &ReportOptions, r: &Row) {
    if options.verbose {
        crate::errln!(
            "{} {} n={} var={} tilt={:?} d/d1={:?} comp={} pre={} {:.1} ms rmse_c={:?} rmse_i={:?} ref={:?}",
            r.family,
            r.kernel,
            r.slabs,
            r.variance_level,
            r.tilt_deg,
            r.distance_over_d1,
            r.compensation,
            r.preintegration,
            r.time_ms,
            r.rmse_correct,
            r.rmse_iterated,
            r.rmse_reference
        );
    }
}

/// The edge family: distance × slabs × variance × tilt × kernel × compensation.
fn edge_cases(cases: &mut Cases<'_>) {
    let quick = cases.options.quick;
    let slab_counts: &[u32] = if quick { &[64, 128] } else { &SLAB_COUNTS };
    let variances: Vec<(&str, f64)> = if quick {
        vec![VARIANCES[0], VARIANCES[2]]
    } else {
        VARIANCES.to_vec()
    };
    for k in [0.25, 1.0, 4.0] {
        for &n in slab_counts {
            for &(level, var) in &variances {
                for tilt in TILTS {
                    for kernel in kernels() {
                        for comp in [true, false] {
                            if !comp && quick && kernel != "ellipse2" {
                                continue;
                            }
                            for penumbra in cases.options.penumbras() {
                                cases.next += 1;
                                if !cases.want(cases.next - 1) {
                                    continue;
                                }
                                let setup = edge_setup(k, n, tilt, var, kernel, comp, penumbra);
                                cases.push(edge_row(&setup, level));
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The disk family's (distance, slabs, variance level, variance, tilt) points, in case order.
fn disk_grid(quick: bool) -> Vec<(f64, u32, &'static str, f64, f64)> {
    if quick {
        vec![(4.0, 128, "high", 0.05, 45.0)]
    } else {
        let mut v = Vec::new();
        for k in [1.0, 4.0] {
            for &(level, var) in &VARIANCES {
                for tilt in TILTS {
                    for n in SLAB_COUNTS {
                        v.push((k, n, level, var, tilt));
                    }
                }
            }
        }
        v
    }
}

/// The disk family: one case per kernel at each [`disk_grid`] point, the reference shared
/// while d, σ² and tilt stay the same.
fn disk_cases(cases: &mut Cases<'_>) -> Result<(), String> {
    let penumbras = cases.options.penumbras();
    let kernel_count = kernels().count() * penumbras.len();
    let mut cached: Option<((u64, u64, u64), DiskReference)> = None;
    for (k, n, level, var, tilt) in disk_grid(cases.options.quick) {
        let group = cases.next..cases.next + kernel_count;
        if !group.clone().any(|i| cases.want(i)) {
            cases.next = group.end;
            continue;
        }
        let key = (k.to_bits(), var.to_bits(), tilt.to_bits());
        if cached.as_ref().is_none_or(|c| c.0 != key) {
            // The reference depends on d, σ² and tilt only (the disk polygon is the same mesh).
            cached = Some((
                key,
                disk_reference(&disk_setup(
                    k,
                    64,
                    tilt,
                    var,
                    "ellipse2",
                    Penumbra::Iterated,
                )),
            ));
        }
        let reference = &cached.as_ref().map(|c| &c.1).ok_or("no disk reference")?;
        for kernel in kernels() {
            for &penumbra in &penumbras {
                cases.next += 1;
                if !cases.want(cases.next - 1) {
                    continue;
                }
                let setup = disk_setup(k, n, tilt, var, kernel, penumbra);
                cases.push(disk_row(&setup, level, reference));
            }
        }
    }
    Ok(())
}

/// The full-scene family: one case per kernel at each slab count.
fn scene_cases(cases: &mut Cases<'_>) {
    let penumbras = cases.options.penumbras();
    let kernel_count = kernels().count() * penumbras.len();
    let (size, scene_slabs): (u32, &[u32]) = if cases.options.quick {
        (24, &[64])
    } else {
        (24, &SLAB_COUNTS)
    };
    for &n in scene_slabs {
        let group = cases.next..cases.next + kernel_count;
        cases.next = group.end;
        if !group.clone().any(|i| cases.want(i)) {
            continue;
        }
        let rows = scene_rows(size, n, 16, &penumbras, cases.options.verbose);
        for (i, row) in group.zip(rows) {
            if cases.want(i) {
                cases.push(row);
            }
        }
    }
}

/// The light-direction family: light × view angle × penumbra model (`ellipse2`), then a soft
/// point light × view angle (distance penumbra).
fn direction_cases(cases: &mut Cases<'_>) -> Result<(), String> {
    let quick = cases.options.quick;
    let angles: &[f64] = if quick {
        &direction::QUICK_VIEW_ANGLES
    } else {
        &direction::VIEW_ANGLES
    };
    for light in direction::lights(quick) {
        for &theta in angles {
            for penumbra in cases.options.penumbras() {
                cases.next += 1;
                if cases.want(cases.next - 1) {
                    cases.push(direction::direction_row(theta, light, penumbra)?);
                }
            }
        }
    }
    // A soft point light: the distance penumbra only (the sweep refuses it the iterated one).
    if cases.options.penumbras().contains(&Penumbra::Distance) {
        for &theta in angles {
            cases.next += 1;
            if cases.want(cases.next - 1) {
                cases.push(direction::point_direction_row(theta)?);
            }
        }
    }
    Ok(())
}

/// The perspective family: field of view × penumbra model (`ellipse2`), then with the distance
/// penumbra the light grid's resolution × the edge on and off the default grid's pixel
/// boundaries (a speed-against-error axis); the same in the quick and the full report.
fn perspective_cases(cases: &mut Cases<'_>) -> Result<(), String> {
    for fov in perspective::FIELDS_OF_VIEW {
        for penumbra in cases.options.penumbras() {
            cases.next += 1;
            if cases.want(cases.next - 1) {
                cases.push(perspective::perspective_row(fov, penumbra, 1.0, 0.0)?);
            }
        }
        for (resolution, off) in perspective::LIGHT_RESOLUTIONS {
            cases.next += 1;
            if cases.want(cases.next - 1) {
                cases.push(perspective::perspective_row(
                    fov,
                    Penumbra::Distance,
                    resolution,
                    off,
                )?);
            }
        }
    }
    Ok(())
}

/// The point-light family: orthographic and perspective × the light grid's resolution; the same
/// in the quick and the full report.
fn point_cases(cases: &mut Cases<'_>) -> Result<(), String> {
    for perspective in [false, true] {
        for resolution in point::LIGHT_RESOLUTIONS {
            cases.next += 1;
            if cases.want(cases.next - 1) {
                cases.push(point::point_row(perspective, resolution)?);
            }
        }
    }
    Ok(())
}

/// Refuses an `options.case` past the last of the `count` cases.
fn check_case(options: &ReportOptions, count: usize) -> Result<(), String> {
    if let Some(c) = options.case
        && c >= count
    {
        return Err(format!(
            "--case {c}: the {} report has {count} cases, 0 to {}",
            if options.quick { "quick" } else { "full" },
            count - 1
        ));
    }
    Ok(())
}

/// Writes `report.csv` and, for the whole report, the plot and `report.md`.
fn write_files(options: &ReportOptions, rows: Vec<Row>, start: Instant) -> Result<Report, String> {
    // Each file goes to a temporary file in the folder and is renamed into place: a failed
    // write leaves the previous file (or none), never an empty or partial one.
    let write = |name: &str, text: &str| {
        let p = options.out.join(name);
        convshadow_io::image::write_atomically(&p, |w| w.write_all(text.as_bytes()))
            .map_err(|e| e.to_string())
    };
    write("report.csv", &csv::csv(&rows))?;
    if options.case.is_some() {
        return Ok(Report {
            rows,
            seconds: start.elapsed().as_secs_f64(),
            plot_text: false,
        });
    }
    let panels = plot::panels(&rows);
    let plot_text = plot::draw(&options.out.join("speed_vs_error.png"), &panels)?;
    let seconds = start.elapsed().as_secs_f64();
    let report = Report {
        rows,
        seconds,
        plot_text,
    };
    write("report.md", &markdown::markdown(&report, options))?;
    Ok(report)
}

/// The number of cases of the report `options` asks for (the quick or full grid, one or both
/// penumbra models), counted without running any.
pub fn case_count(options: &ReportOptions) -> usize {
    // No case is wanted: every family only counts (`Cases::want` is false for all).
    let counting = ReportOptions {
        case: Some(usize::MAX),
        verbose: false,
        ..options.clone()
    };
    let mut cases = Cases {
        options: &counting,
        next: 0,
        rows: Vec::new(),
    };
    edge_cases(&mut cases);
    // Without a wanted case the disk family computes no reference, so it cannot fail.
    let _ = disk_cases(&mut cases);
    scene_cases(&mut cases);
    narrowband_cases(&mut cases);
    // Without a wanted case the direction, perspective and point families render nothing, so
    // they cannot fail.
    let _ = direction_cases(&mut cases);
    let _ = perspective_cases(&mut cases);
    let _ = point_cases(&mut cases);
    cases.next
}

/// The files a run of `options` writes in `options.out`: `report.csv`, and for the whole
/// report also `speed_vs_error.png` and `report.md`.
pub fn output_files(options: &ReportOptions) -> Vec<std::path::PathBuf> {
    let names: &[&str] = if options.case.is_some() {
        &["report.csv"]
    } else {
        &["report.csv", "speed_vs_error.png", "report.md"]
    };
    names.iter().map(|n| options.out.join(n)).collect()
}

/// Checks before any case runs what would otherwise fail after them: `--case` within the
/// grid (before anything is created), then the folder (created if missing) and each file it
/// will write ([`convshadow_io::image::check_writable`]).
pub fn check_outputs(options: &ReportOptions) -> Result<(), String> {
    check_case(options, case_count(options))?;
    std::fs::create_dir_all(&options.out)
        .map_err(|e| format!("{}: cannot create: {e}", options.out.display()))?;
    for p in output_files(options) {
        convshadow_io::image::check_writable(&p).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Runs the report and writes its files (after [`check_outputs`]).
pub fn run(options: &ReportOptions) -> Result<Report, String> {
    let start = Instant::now();
    check_outputs(options)?;
    let mut cases = Cases {
        options,
        next: 0,
        rows: Vec::new(),
    };
    edge_cases(&mut cases);
    disk_cases(&mut cases)?;
    scene_cases(&mut cases);
    narrowband_cases(&mut cases);
    direction_cases(&mut cases)?;
    perspective_cases(&mut cases)?;
    point_cases(&mut cases)?;
    check_case(options, cases.next)?;
    write_files(options, cases.rows, start)
}
