//! The speed-against-error report (issue 4, DESIGN §3): renders a grid of cases, measures the
//! sweep's time and its errors against references, and writes `report.csv`, `report.md` and
//! `speed_vs_error.png`.
//!
//! Families of cases, each with its own reference:
//! - `edge`: the opaque edge at d = d1/4, d1, 4·d1 ([`edge`]); references: the correct shadow
//!   (Gaussian CDF of std d·σ) and the iterated model (std √(d·d1)·σ, paper eq. 8);
//! - `disk`: the disk over a plane ([`disk`]); references: the disk's indicator convolved with
//!   the correct and the iterated Gaussian, numerically in f64;
//! - `scene`: the embedded default scene at a small size; reference: the ground-truth shadow-ray
//!   renderer (`convshadow_cpu::reference`), whose own error (M against 4·M samples) is reported.
//!
//! "Slab count" for the edge and disk is the number of convolutions between occluder and
//! receiver (d = n·e); for the scene it is the scene's slab count.

pub mod disk;
pub mod edge;
pub mod impulse;
pub mod plot;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use convshadow_common::geometry::SceneGeometry;
use convshadow_common::plan::RenderPlan;
use convshadow_common::scene::{Scene, SlabSpec};
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_cpu::reference::{Reference, ReferenceOptions};
use convshadow_cpu::sweep::{SweepOptions, sweep};

use self::disk::DiskSetup;
use self::edge::{EdgeSetup, model_profile, run_light};

/// The kernels of the report.
pub const KERNELS: [&str; 7] = [
    "ellipse2",
    "ellipse3",
    "dirac",
    "poisson8",
    "poisson16",
    "gaussian:19",
    "box",
];
/// The slab counts of the full report.
pub const SLAB_COUNTS: [u32; 4] = [64, 128, 256, 512];
/// Light variance levels σ² (name, value) of the analytic cases.
pub const VARIANCES: [(&str, f64); 3] = [("zero", 0.0), ("low", 0.002), ("high", 0.05)];
/// Light tilts (degrees) of the analytic cases.
pub const TILTS: [f64; 2] = [0.0, 45.0];
/// d1 of the analytic cases (world units); the pixel size is 0.01.
pub const D1: f64 = 0.16;
/// Pixel size of the analytic cases.
pub const PX: f64 = 0.01;

/// What to run.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// The quick subset (see [`ReportOptions::describe`]).
    pub quick: bool,
    /// Output folder.
    pub out: PathBuf,
    /// Print one line per case on stderr.
    pub verbose: bool,
}

impl ReportOptions {
    /// A sentence saying which cases run.
    pub fn describe(&self) -> String {
        if self.quick {
            "quick subset: edge at d = d1/4, d1, 4·d1 × all 7 kernels × slabs 64, 128 × variance \
             zero, high × tilt 0°, 45° (compensation on), plus ellipse2 with compensation off; disk at \
             d = 4·d1, tilt 45°, high variance, slabs 128, all kernels; default scene at 24×24, \
             slabs 64, all kernels, reference M = 16 (self-error against M = 64)"
                .to_string()
        } else {
            "full grid: edge at d = d1/4, d1, 4·d1 × 7 kernels × slabs 64, 128, 256, 512 × variance \
             zero, low, high × tilt 0°, 45°, with compensation on and off; disk at d = d1 and 4·d1 \
             × 7 kernels × 4 slab counts × 3 variances × 2 tilts (compensation on); default scene \
             at 24×24 × 7 kernels × slabs 64, 128, 256, 512, reference M = 16 (self-error against \
             M = 64)"
                .to_string()
        }
    }
}

/// One row of `report.csv`.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// `edge`, `disk` or `scene`.
    pub family: String,
    /// Kernel name.
    pub kernel: String,
    /// Slab count (see the module documentation).
    pub slabs: u32,
    /// Variance level name (`zero`, `low`, `high`, or `scene`).
    pub variance_level: String,
    /// σ² of the light (analytic cases).
    pub variance: Option<f64>,
    /// Tilt ωx in degrees (analytic cases).
    pub tilt_deg: Option<f64>,
    /// d / d1 (analytic cases).
    pub distance_over_d1: Option<f64>,
    /// `sweep.variance_compensation`.
    pub compensation: bool,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Sweep time for the frame (ms).
    pub time_ms: f64,
    /// RMSE against the correct shadow.
    pub rmse_correct: Option<f64>,
    /// RMSE against the iterated model.
    pub rmse_iterated: Option<f64>,
    /// Half-shadow isoline position error against the correct shadow (px).
    pub isoline_err_px: Option<f64>,
    /// 10–90 % penumbra width error against the correct shadow (px).
    pub width_err_correct_px: Option<f64>,
    /// 10–90 % penumbra width error against the iterated model (px).
    pub width_err_iterated_px: Option<f64>,
    /// Measured 10–90 % penumbra width (px).
    pub width_px: Option<f64>,
    /// Image RMSE against the ground-truth reference.
    pub rmse_reference: Option<f64>,
    /// The reference's own error: RMS difference between its M and 4·M sample runs.
    pub reference_self_err: Option<f64>,
    /// Why cells are empty.
    pub note: String,
}

const CSV_HEADER: &str = "family,kernel,slabs,variance_level,variance,tilt_deg,distance_over_d1,\
compensation,width,height,time_ms,rmse_correct,rmse_iterated,isoline_err_px,width_err_correct_px,\
width_err_iterated_px,width_px,rmse_reference,reference_self_err,note";

impl Row {
    fn csv(&self) -> String {
        let o = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6}"));
        format!(
            "{},{},{},{},{},{},{},{},{},{},{:.3},{},{},{},{},{},{},{},{},\"{}\"",
            self.family,
            self.kernel,
            self.slabs,
            self.variance_level,
            o(self.variance),
            o(self.tilt_deg),
            o(self.distance_over_d1),
            self.compensation,
            self.width,
            self.height,
            self.time_ms,
            o(self.rmse_correct),
            o(self.rmse_iterated),
            o(self.isoline_err_px),
            o(self.width_err_correct_px),
            o(self.width_err_iterated_px),
            o(self.width_px),
            o(self.rmse_reference),
            o(self.reference_self_err),
            self.note.replace('"', "'"),
        )
    }
}

/// The numbers of one finished report.
pub struct Report {
    /// Every case.
    pub rows: Vec<Row>,
    /// Seconds for the whole report.
    pub seconds: f64,
    /// Whether the plot has text.
    pub plot_text: bool,
}

/// The machine: `nproc` and the CPU model from /proc/cpuinfo.
pub fn machine() -> String {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    format!("{cpus} logical CPUs (nproc), {model}")
}

/// RMSE of `got` against `want` over the indices in `window`.
fn rmse(got: &[f64], want: &[f64], window: impl Iterator<Item = usize>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for i in window {
        s += (got[i] - want[i]) * (got[i] - want[i]);
        n += 1;
    }
    (s / n.max(1) as f64).sqrt()
}

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
        slabs: setup.slabs,
        variance_level: level.into(),
        variance: Some(setup.variance),
        tilt_deg: Some(setup.tilt_deg),
        distance_over_d1: Some(d / setup.optimal_distance),
        compensation: setup.compensation,
        width: setup.width,
        height: setup.height,
        time_ms: seconds * 1e3,
        rmse_correct: Some(rmse(&profile, &correct, lo..hi)),
        rmse_iterated: Some(rmse(&profile, &iterated, lo..hi)),
        isoline_err_px: diff(iso, iso_c),
        width_err_correct_px: diff(width, width_c),
        width_err_iterated_px: diff(width, width_i),
        width_px: width,
        rmse_reference: None,
        reference_self_err: None,
        note: if note.is_empty() {
            "analytic case: closed-form references, no shadow-ray reference needed".into()
        } else {
            note
        },
    }
}

/// The edge set-up of the report for distance factor `k` (d = k·d1), slab count, tilt, σ².
pub fn edge_setup(
    k: f64,
    slabs: u32,
    tilt: f64,
    variance: f64,
    kernel: &str,
    comp: bool,
) -> EdgeSetup {
    EdgeSetup {
        slabs,
        slab_distance: k * D1 / f64::from(slabs),
        optimal_distance: D1,
        pixel_size: PX,
        width: 384,
        height: 64,
        tilt_deg: tilt,
        variance,
        kernel: kernel.to_string(),
        compensation: comp,
        seed: 0,
    }
}

/// The disk set-up of the report.
pub fn disk_setup(k: f64, slabs: u32, tilt: f64, variance: f64, kernel: &str) -> DiskSetup {
    DiskSetup {
        slabs,
        slab_distance: k * D1 / f64::from(slabs),
        optimal_distance: D1,
        pixel_size: PX,
        width: 256,
        height: 192,
        radius: 0.2,
        tilt_deg: tilt,
        variance: [variance, variance],
        rotation_deg: 0.0,
        kernel: kernel.to_string(),
        compensation: true,
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
    let g = SceneGeometry::build(&scene).unwrap_or_else(|e| panic!("{e}"));
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
        slabs: setup.slabs,
        variance_level: level.into(),
        variance: Some(setup.variance[0]),
        tilt_deg: Some(setup.tilt_deg),
        distance_over_d1: Some(setup.distance() / setup.optimal_distance),
        compensation: setup.compensation,
        width: setup.width,
        height: setup.height,
        time_ms: seconds * 1e3,
        rmse_correct: Some(rmse(&light, &r.correct, win.iter().copied())),
        rmse_iterated: Some(rmse(&light, &r.iterated, win.iter().copied())),
        isoline_err_px: Some(sym / r.perimeter),
        width_err_correct_px: Some(wm - wc),
        width_err_iterated_px: Some(wm - wi),
        width_px: Some(wm),
        rmse_reference: None,
        reference_self_err: None,
        note: "analytic case (numerical f64 disk convolution); isoline error = mean unsigned \
               displacement (symmetric-difference area / perimeter); widths = area between the \
               0.1 and 0.9 levels / perimeter"
            .into(),
    }
}

/// A sweep of a full scene: (plan, geometry, ldi, image, seconds).
fn render_scene(scene: &Scene) -> (RenderPlan, SceneGeometry, Ldi, Vec<f32>, f64) {
    let g = SceneGeometry::build(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 8 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = RenderPlan::new(scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let t = Instant::now();
    let out =
        sweep(&plan, &g.raster, &ldi, &SweepOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    (plan, g, ldi, out.image, t.elapsed().as_secs_f64())
}

fn rmse_f32(a: &[f32], b: &[f32]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2))
        .sum();
    (s / a.len().max(1) as f64).sqrt()
}

/// The default scene at `size`² with `slabs`: one row per kernel against the reference.
fn scene_rows(size: u32, slabs: u32, samples: u32, verbose: bool) -> Vec<Row> {
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
        eprintln!(
            "scene {size}² slabs {slabs}: reference M={samples} and {} in {:.1} s, self error {self_err:.2e}",
            4 * samples,
            t.elapsed().as_secs_f64()
        );
    }
    KERNELS
        .iter()
        .map(|k| {
            let mut scene = base.clone();
            scene.sweep.kernel = k.parse().unwrap_or_else(|e: String| panic!("{e}"));
            let (_, _, _, image, seconds) = render_scene(&scene);
            Row {
                family: "scene".into(),
                kernel: k.to_string(),
                slabs,
                variance_level: "scene".into(),
                compensation: scene.sweep.variance_compensation,
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

/// Runs the report and writes its files.
pub fn run(options: &ReportOptions) -> Result<Report, String> {
    let start = Instant::now();
    std::fs::create_dir_all(&options.out)
        .map_err(|e| format!("{}: cannot create: {e}", options.out.display()))?;
    let mut rows = Vec::new();
    let log = |r: &Row| {
        if options.verbose {
            eprintln!(
                "{} {} n={} var={} tilt={:?} d/d1={:?} comp={} {:.1} ms rmse_c={:?} rmse_i={:?} ref={:?}",
                r.family,
                r.kernel,
                r.slabs,
                r.variance_level,
                r.tilt_deg,
                r.distance_over_d1,
                r.compensation,
                r.time_ms,
                r.rmse_correct,
                r.rmse_iterated,
                r.rmse_reference
            );
        }
    };
    let quick = options.quick;
    // Edge.
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
                    for kernel in KERNELS {
                        for comp in [true, false] {
                            if !comp && quick && kernel != "ellipse2" {
                                continue;
                            }
                            let row = edge_row(&edge_setup(k, n, tilt, var, kernel, comp), level);
                            log(&row);
                            rows.push(row);
                        }
                    }
                }
            }
        }
    }
    // Disk.
    let disk_grid: Vec<(f64, u32, &str, f64, f64)> = if quick {
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
    };
    let mut cached: Option<((u64, u64, u64), DiskReference)> = None;
    for (k, n, level, var, tilt) in disk_grid {
        let key = (k.to_bits(), var.to_bits(), tilt.to_bits());
        if cached.as_ref().is_none_or(|c| c.0 != key) {
            // The reference depends on d, σ² and tilt only (the disk polygon is the same mesh).
            cached = Some((
                key,
                disk_reference(&disk_setup(k, 64, tilt, var, "ellipse2")),
            ));
        }
        let reference = &cached.as_ref().map(|c| &c.1).ok_or("no disk reference")?;
        for kernel in KERNELS {
            let row = disk_row(&disk_setup(k, n, tilt, var, kernel), level, reference);
            log(&row);
            rows.push(row);
        }
    }
    // Full scene.
    let (size, scene_slabs): (u32, &[u32]) = if quick {
        (24, &[64])
    } else {
        (24, &SLAB_COUNTS)
    };
    for &n in scene_slabs {
        for row in scene_rows(size, n, 16, options.verbose) {
            log(&row);
            rows.push(row);
        }
    }

    // Files.
    let mut csv = String::from(CSV_HEADER);
    csv.push('\n');
    for r in &rows {
        csv.push_str(&r.csv());
        csv.push('\n');
    }
    let write = |name: &str, text: &str| {
        let p = options.out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("report.csv", &csv)?;
    let panels = plot_panels(&rows);
    let plot_text = plot::draw(&options.out.join("speed_vs_error.png"), &panels)?;
    let seconds = start.elapsed().as_secs_f64();
    let report = Report {
        rows,
        seconds,
        plot_text,
    };
    write("report.md", &markdown(&report, options))?;
    Ok(report)
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    if n == 0 { f64::NAN } else { s / n as f64 }
}

/// Per (kernel, slabs): mean time and mean of `err` over the rows selected by `keep`.
fn aggregate(
    rows: &[Row],
    keep: &dyn Fn(&Row) -> bool,
    err: &dyn Fn(&Row) -> Option<f64>,
) -> Vec<plot::Series> {
    KERNELS
        .iter()
        .map(|k| {
            let mut slabs: Vec<u32> = rows
                .iter()
                .filter(|r| r.kernel == *k && keep(r))
                .map(|r| r.slabs)
                .collect();
            slabs.sort_unstable();
            slabs.dedup();
            let points = slabs
                .iter()
                .filter_map(|&n| {
                    let sel: Vec<&Row> = rows
                        .iter()
                        .filter(|r| r.kernel == *k && r.slabs == n && keep(r))
                        .collect();
                    let t = mean(sel.iter().map(|r| r.time_ms));
                    let e = mean(sel.iter().filter_map(|r| err(r)));
                    (t.is_finite() && e.is_finite()).then_some((t, e, n))
                })
                .collect();
            plot::Series {
                name: k.to_string(),
                points,
            }
        })
        .collect()
}

fn plot_panels(rows: &[Row]) -> Vec<plot::Panel> {
    let edge_on = |r: &Row| r.family == "edge" && r.compensation;
    vec![
        plot::Panel {
            title: "edge: error vs the correct shadow".into(),
            y_desc: "mean RMSE (light)".into(),
            series: aggregate(rows, &edge_on, &|r| r.rmse_correct),
        },
        plot::Panel {
            title: "edge: error vs the iterated model".into(),
            y_desc: "mean RMSE (light)".into(),
            series: aggregate(rows, &edge_on, &|r| r.rmse_iterated),
        },
        plot::Panel {
            title: "default scene vs shadow-ray reference".into(),
            y_desc: "image RMSE (linear)".into(),
            series: aggregate(rows, &|r| r.family == "scene", &|r| r.rmse_reference),
        },
    ]
}

fn fmt(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 0.01 || v == 0.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NAN, |m, x| {
        if m.is_nan() || x.abs() > m {
            x.abs()
        } else {
            m
        }
    })
}

fn markdown(report: &Report, options: &ReportOptions) -> String {
    let rows = &report.rows;
    let mut md = String::new();
    let _ = writeln!(md, "# convshadow speed-against-error report\n");
    let _ = writeln!(
        md,
        "Machine: {}. Report time {:.0} s. Cases: {}.\n",
        machine(),
        report.seconds,
        options.describe()
    );
    let _ = writeln!(
        md,
        "Times are the sweep's wall time for one frame (edge 384×64, disk 256×192, scene as \
         given) on all cores; they are noisy when the machine is shared. Light values are in \
         [0, 1]. Every number is in `report.csv`.\n"
    );
    if !report.plot_text {
        let _ = writeln!(
            md,
            "Note: no TrueType font was found, so `speed_vs_error.png` has no text \
             (set CONVSHADOW_FONT to a .ttf file).\n"
        );
    }
    // Table 1: edge, compensation on, per kernel × slabs.
    let _ = writeln!(
        md,
        "## Edge (compensation on): mean over distances, variances and tilts\n"
    );
    let _ = writeln!(
        md,
        "| kernel | slabs | time ms | RMSE vs correct | RMSE vs iterated | max abs isoline err px | max abs 10–90 width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for k in KERNELS {
        let mut ns: Vec<u32> = rows
            .iter()
            .filter(|r| r.family == "edge")
            .map(|r| r.slabs)
            .collect();
        ns.sort_unstable();
        ns.dedup();
        for n in ns {
            let sel: Vec<&Row> = rows
                .iter()
                .filter(|r| r.family == "edge" && r.compensation && r.kernel == k && r.slabs == n)
                .collect();
            if sel.is_empty() {
                continue;
            }
            let _ = writeln!(
                md,
                "| {k} | {n} | {} | {} | {} | {} | {} |",
                fmt(mean(sel.iter().map(|r| r.time_ms))),
                fmt(mean(sel.iter().filter_map(|r| r.rmse_correct))),
                fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
                fmt(max_abs(sel.iter().filter_map(|r| r.isoline_err_px))),
                fmt(max_abs(sel.iter().filter_map(|r| r.width_err_iterated_px))),
            );
        }
    }
    // Table 2: zero-variance penumbra widths and compensation before/after.
    let _ = writeln!(
        md,
        "\n## Over-blur: zero-variance light, measured 10–90 % width (px; a sampled step measures 0.8)\n"
    );
    let _ = writeln!(
        md,
        "| kernel | compensation | tilt | max width px | mean RMSE vs iterated, all variances |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|");
    for k in KERNELS {
        for comp in [true, false] {
            for tilt in TILTS {
                let sel: Vec<&Row> = rows
                    .iter()
                    .filter(|r| {
                        r.family == "edge"
                            && r.kernel == k
                            && r.compensation == comp
                            && r.tilt_deg == Some(tilt)
                    })
                    .collect();
                if sel.is_empty() {
                    continue;
                }
                let zero = max_abs(
                    sel.iter()
                        .filter(|r| r.variance_level == "zero")
                        .filter_map(|r| r.width_px),
                );
                let _ = writeln!(
                    md,
                    "| {k} | {} | {tilt}° | {} | {} |",
                    if comp { "on" } else { "off" },
                    fmt(zero),
                    fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
                );
            }
        }
    }
    // Table 3: the √d growth: RMSE vs correct and vs iterated per distance.
    let _ = writeln!(
        md,
        "\n## Penumbra growth (paper §6): edge, ellipse2, compensation on, high variance\n"
    );
    let _ = writeln!(
        md,
        "| d / d1 | slabs | RMSE vs correct | RMSE vs iterated | width err vs correct px | width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| {
        r.family == "edge"
            && r.kernel == "ellipse2"
            && r.compensation
            && r.variance_level == "high"
            && r.tilt_deg == Some(45.0)
    }) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} |",
            fmt(r.distance_over_d1.unwrap_or(f64::NAN)),
            r.slabs,
            fmt(r.rmse_correct.unwrap_or(f64::NAN)),
            fmt(r.rmse_iterated.unwrap_or(f64::NAN)),
            fmt(r.width_err_correct_px.unwrap_or(f64::NAN)),
            fmt(r.width_err_iterated_px.unwrap_or(f64::NAN)),
        );
    }
    // Table 4: disk.
    let _ = writeln!(
        md,
        "\n## Disk over a plane: mean over its cases per kernel\n"
    );
    let _ = writeln!(
        md,
        "| kernel | time ms | RMSE vs correct | RMSE vs iterated | mean isoline displacement px | width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for k in KERNELS {
        let sel: Vec<&Row> = rows
            .iter()
            .filter(|r| r.family == "disk" && r.kernel == k)
            .collect();
        if sel.is_empty() {
            continue;
        }
        let _ = writeln!(
            md,
            "| {k} | {} | {} | {} | {} | {} |",
            fmt(mean(sel.iter().map(|r| r.time_ms))),
            fmt(mean(sel.iter().filter_map(|r| r.rmse_correct))),
            fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
            fmt(mean(sel.iter().filter_map(|r| r.isoline_err_px))),
            fmt(mean(sel.iter().filter_map(|r| r.width_err_iterated_px))),
        );
    }
    // Table 5: scene.
    let _ = writeln!(md, "\n## Default scene against the shadow-ray reference\n");
    let _ = writeln!(
        md,
        "| kernel | slabs | size | time ms | image RMSE vs reference | reference self-error (M vs 4M) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.family == "scene") {
        let _ = writeln!(
            md,
            "| {} | {} | {}×{} | {} | {} | {} |",
            r.kernel,
            r.slabs,
            r.width,
            r.height,
            fmt(r.time_ms),
            fmt(r.rmse_reference.unwrap_or(f64::NAN)),
            fmt(r.reference_self_err.unwrap_or(f64::NAN)),
        );
    }
    if rows.iter().any(|r| r.family == "scene") {
        let _ = writeln!(
            md,
            "\nThe image RMSE is against the 4·M reference. The self-error is the M run's \
             difference from it, an estimate of the M run's own error; the 4·M run's is smaller \
             still (its error falls at least 1.6× each time M quadruples: \
             `tests/hard_cases.rs`)."
        );
    }
    md
}

/// Where the report writes by default.
pub fn default_out() -> PathBuf {
    Path::new("report").to_path_buf()
}
