//! `convshadow render`: render a scene (or the embedded default scene) to PNG and/or EXR.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use convshadow_common::geometry::SceneGeometry;
use convshadow_common::guard::GuardBandSpec;
use convshadow_common::image_io::RgbImage;
use convshadow_common::kernel::{KERNEL_SYNTAX, KernelSpec};
use convshadow_common::plan::RenderPlan;
use convshadow_common::scene::{Penumbra, Scene, SlabSpec};
use convshadow_common::tonemap::Tonemap;
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_cpu::reference::{Reference, ReferenceOptions, samples_side};
use serde_json::json;

use super::frames;
use crate::cli::exit::{self, Failure};
use convshadow::pipeline::{
    Backend, CpuPath, MemoryNeed, RenderRequest, Rendered, image_fingerprint, render,
};

/// Most light directions `--reference-samples` takes (256²: seconds per pixel at most, so even
/// a 1×1 image cannot run for minutes).
pub const MAX_REFERENCE_SAMPLES: u32 = 65536;

/// `--backend` of `convshadow render`: the pipeline's devices, or the ground-truth reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RenderBackend {
    /// The CPU oracle.
    #[default]
    Cpu,
    /// The wgpu port (Vulkan: a hardware adapter, else Mesa lavapipe); exit code 5 without one.
    Gpu,
    /// The GPU when an adapter exists, else the CPU (and says so).
    Auto,
    /// The ground-truth reference: the sweep's view samples, with the light
    /// integrated over `--reference-samples` stratified directions of the Gaussian light and
    /// marched through the continuous scene. Slow (quadratic in depth): for small images.
    Reference,
}

impl RenderBackend {
    /// The pipeline's backend, or `None` for the reference.
    fn device(self) -> Option<Backend> {
        match self {
            RenderBackend::Cpu => Some(Backend::Cpu),
            RenderBackend::Gpu => Some(Backend::Gpu),
            RenderBackend::Auto => Some(Backend::Auto),
            RenderBackend::Reference => None,
        }
    }
}

/// Arguments of `convshadow render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML); without it, the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output image(s): `.png` (sRGB 8-bit) or `.exr` (linear float); may repeat.
    /// Default: render.png in the current folder.
    #[arg(short = 'o', long = "output")]
    pub outputs: Vec<PathBuf>,
    /// Override the image width (the height stays, and so does camera.view_width: a wider image
    /// shows the same width of the scene, a taller one more of it; use --size to keep the view).
    #[arg(long, value_parser = super::parse_side)]
    pub width: Option<u32>,
    /// Override the image height (the width and camera.view_width stay).
    #[arg(long, value_parser = super::parse_side)]
    pub height: Option<u32>,
    /// Image size WxH; when the aspect changes, camera.view_width grows so the scene's whole
    /// view stays in frame (and says so).
    #[arg(long, value_name = "WxH", conflicts_with_all = ["width", "height"])]
    pub size: Option<String>,
    /// Override camera.view_width (world units across the image).
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    pub view_width: Option<f64>,
    /// Override camera.direction (X,Y,Z; normalised).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub camera_direction: Option<String>,
    /// Override camera.center (X,Y,Z).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub camera_center: Option<String>,
    /// PNG output: exposure in stops (overrides image.exposure; EXR stays linear).
    #[arg(long, value_name = "STOPS", allow_hyphen_values = true)]
    pub exposure: Option<f64>,
    /// PNG output: tone curve clamp, reinhard or aces (overrides image.tonemap; default aces).
    #[arg(long, value_name = "CURVE")]
    pub tonemap: Option<String>,
    /// Render frames A..B (B excluded; A..=B includes it) of the 4D detail: frame k sets every
    /// detail material's time to its detail.time (or 0) + k·--time-step. Outputs need a frame
    /// pattern such as out_%04d.png.
    #[arg(long, value_name = "A..B", conflicts_with = "frame")]
    pub frames: Option<String>,
    /// Render frame K alone: the same bits as frame K of --frames.
    #[arg(long, value_name = "K")]
    pub frame: Option<u32>,
    /// Detail time advanced per frame (default 0.05).
    #[arg(long, value_name = "DT", allow_hyphen_values = true)]
    pub time_step: Option<f64>,
    /// Override the slab count: N, or `auto` (2 slabs per finest period of the detail along the
    /// view, times sweep.slab_factor; the count chosen is printed and in --stats-json).
    #[arg(long, value_name = "N|auto", value_parser = super::parse_slabs)]
    pub slabs: Option<SlabSpec>,
    /// Override the kernel (the help lists the kernels of `common::kernel::KERNEL_SYNTAX`).
    #[arg(long, help = format!("Override the kernel ({KERNEL_SYNTAX})"))]
    pub kernel: Option<String>,
    /// Override the seed.
    #[arg(long)]
    pub seed: Option<u32>,
    /// Override the penumbra model (`sweep.penumbra`): `iterated` (the paper's: right at
    /// sweep.optimal_distance only) or `distance` (follows each pixel's occluder distance).
    #[arg(long, value_name = "iterated|distance", value_parser = parse_penumbra)]
    pub penumbra: Option<Penumbra>,
    /// Override the guard band: `auto` (sized from the scene's lights, depth and meshes) or
    /// pixels beyond every image edge (0: none), as `sweep.guard_band`.
    #[arg(long, value_name = "auto|N", value_parser = parse_guard_band)]
    pub guard_band: Option<GuardBandSpec>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// CPU code path: `simd` (8 pixels at a time) or `scalar` (the readable reference); both
    /// give the same bits.
    #[arg(long, value_enum, default_value_t = CpuPath::Simd)]
    pub path: CpuPath,
    /// SIMD path: compute every chunk, even those whose result is known exactly (unoccluded and
    /// empty, or opaque in the dark). Same image; only for measuring what skipping saves.
    #[arg(long)]
    pub no_skip_quiet: bool,
    /// Backend: the CPU oracle, the GPU (wgpu/Vulkan; exit code 5 without an adapter), auto
    /// (the GPU when an adapter exists, else the CPU with a message), or the slow ground-truth
    /// reference (Monte Carlo over light directions, for small images).
    #[arg(long, value_enum, default_value_t = RenderBackend::Cpu)]
    pub backend: RenderBackend,
    /// Light directions per shading point and light for `--backend reference` (rounded up to a
    /// square k²; default 64). Its error falls about as 1/√M.
    #[arg(long)]
    pub reference_samples: Option<u32>,
    /// Turn the bilinear-variance compensation on or off (overrides the scene).
    #[arg(long)]
    pub variance_compensation: Option<bool>,
    /// Pre-integrated compositing (overrides sweep.preintegration): `--preintegration` or
    /// `--preintegration true` turns it on, `--preintegration false` off.
    #[arg(long, value_name = "BOOL", num_args = 0..=1, default_missing_value = "true")]
    pub preintegration: Option<bool>,
    /// Render even if meshes are open (reports the pixels with odd fragment counts).
    #[arg(long)]
    pub allow_open: bool,
    /// Memory budget in MiB for the LDI and the sweep's buffers (default: half the machine's
    /// memory); a scene that needs more is refused before allocating (exit code 4).
    #[arg(long)]
    pub max_memory: Option<u64>,
    /// Write the numbers as JSON (with --frames/--frame: one entry per frame under "frames").
    #[arg(long)]
    pub stats_json: Option<PathBuf>,
    /// No progress bar and no summary line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// One rendered frame of a sequence, for the stats.
struct FrameStats {
    frame: u32,
    time: Option<f64>,
    image_hash: u64,
    ldi_hash: u64,
    seconds_total: f64,
    outputs: Vec<PathBuf>,
}

/// Runs `convshadow render`.
pub fn run(args: &RenderArgs) -> Result<i32, Failure> {
    let mut scene = super::load_scene(args.scene.as_deref())?;
    super::override_size(&mut scene, args.width, args.height)?;
    apply_view_overrides(&mut scene, args)?;
    let (frame_list, time_step) = frame_list(args)?;
    apply_sweep_overrides(&mut scene, args)?;
    let outputs = output_paths(args, frame_list.as_deref())?;
    let bar = progress_bar(args);
    // One bar over all frames: frame i's slab s is at i·slabs + s + 1.
    let frame_index = std::sync::atomic::AtomicU64::new(0);
    let frame_count = frame_list.as_ref().map_or(1, Vec::len) as u64;
    let slab_count = std::sync::atomic::AtomicU64::new(match scene.sweep.slabs {
        SlabSpec::Count(n) => u64::from(n),
        SlabSpec::Distance(_) | SlabSpec::Auto => 0,
    });
    let progress = |slab: u32| {
        if let Some(b) = &bar {
            use std::sync::atomic::Ordering::Relaxed;
            let per = slab_count.load(Relaxed);
            b.set_position(frame_index.load(Relaxed) * per + u64::from(slab) + 1);
        }
    };
    if let Some(b) = &bar {
        // The slab count is known once geometry is built; a count override is known now.
        if let SlabSpec::Count(n) = scene.sweep.slabs {
            b.set_length(u64::from(n) * frame_count);
        }
        if frame_count > 1 {
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} {msg} slab {pos}/{len} {wide_bar} {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
        }
    }
    let samples = reference_samples(args)?;
    let budget = args
        .max_memory
        .map_or_else(convshadow_cpu::default_memory_budget, |m| {
            m.saturating_mul(1 << 20)
        });
    let Some(backend) = args.backend.device() else {
        // The reference has no cancel point: a signal ends the run at once, before any output.
        exit::install_exit_on_signal(None);
        let r = render_reference(&scene, args.threads, samples, budget, args.allow_open)?;
        return finish(&scene, args, &outputs, &r, bar.as_ref(), samples);
    };
    let request = RenderRequest {
        backend,
        threads: args.threads,
        path: args.path,
        skip_quiet: !args.no_skip_quiet,
        memory_budget: budget,
        allow_open: args.allow_open,
        progress: &progress,
        // SIGINT/SIGTERM raise it: the sweep stops and nothing is written (exit code 130).
        cancel: Some(exit::install_interrupt_handler()),
        every_slab: false,
    };
    let Some(list) = frame_list else {
        let r = render(&scene, &request)?;
        if let Some(note) = &r.backend_note {
            eprintln!("note: {}", crate::cli::exit::escape_line(note));
        }
        return finish(&scene, args, &outputs, &r, bar.as_ref(), 0);
    };
    let sequence = Sequence {
        scene: &scene,
        request: &request,
        outputs: &outputs,
        bar: bar.as_ref(),
        frame_index: &frame_index,
        slab_count: &slab_count,
        time_step,
    };
    let (r, done) = sequence.render(&list)?;
    finish_frames(&scene, args, &r, bar.as_ref(), &done, time_step)
}

/// The error of a bad value for `flag`.
fn bad_flag(flag: &str, e: String) -> Failure {
    Failure::new(exit::BAD_ARGUMENTS, format!("{flag}: {e}"))
}

/// `--size`, the camera overrides, `--exposure` and `--tonemap`.
fn apply_view_overrides(scene: &mut Scene, args: &RenderArgs) -> Result<(), Failure> {
    let bad = bad_flag;
    if let Some(text) = &args.size {
        let (w, h) = frames::parse_size(text).map_err(|e| bad("--size", e))?;
        if let Some(note) = frames::apply_size(scene, w, h)?
            && !args.quiet
        {
            eprintln!("note: {}", crate::cli::exit::escape_line(&note));
        }
    }
    let direction = args
        .camera_direction
        .as_deref()
        .map(frames::parse_vec3)
        .transpose()
        .map_err(|e| bad("--camera-direction", e))?;
    let center = args
        .camera_center
        .as_deref()
        .map(frames::parse_vec3)
        .transpose()
        .map_err(|e| bad("--camera-center", e))?;
    scene
        .override_camera(direction, center, args.view_width)
        .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, e.to_string()))?;
    if let Some(x) = args.exposure {
        scene.image.exposure = x;
    }
    if let Some(t) = &args.tonemap {
        scene.image.tonemap = t.parse::<Tonemap>().map_err(|e| bad("--tonemap", e))?;
    }
    Ok(())
}

/// The frames to render (`--frames`/`--frame`, `None` for a single image) and the time step.
fn frame_list(args: &RenderArgs) -> Result<(Option<Vec<u32>>, f64), Failure> {
    let bad = bad_flag;
    let frame_list: Option<Vec<u32>> = match (&args.frames, args.frame) {
        (Some(text), _) => {
            let r = frames::FrameRange::parse(text).map_err(|e| bad("--frames", e))?;
            Some((r.start..r.end).collect())
        }
        (None, Some(k)) => Some(vec![k]),
        (None, None) => None,
    };
    let time_step = args.time_step.unwrap_or(frames::DEFAULT_TIME_STEP);
    if !time_step.is_finite() {
        return Err(bad(
            "--time-step",
            format!("expected a finite number, got {time_step}"),
        ));
    }
    if args.time_step.is_some() && frame_list.is_none() {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            "--time-step only applies with --frames or --frame",
        ));
    }
    Ok((frame_list, time_step))
}

/// `--penumbra iterated|distance` (clap reports a bad value with the option's name).
pub(crate) fn parse_penumbra(s: &str) -> Result<Penumbra, String> {
    s.parse()
}

/// `--guard-band auto|N` (clap reports a bad value with the option's name, exit code 2).
fn parse_guard_band(s: &str) -> Result<GuardBandSpec, String> {
    s.parse()
}

/// `--slabs`, `--kernel`, `--seed`, `--penumbra`, `--guard-band`, `--variance-compensation` and
/// `--preintegration`, then the scene re-validated.
fn apply_sweep_overrides(scene: &mut Scene, args: &RenderArgs) -> Result<(), Failure> {
    if let Some(n) = args.slabs {
        scene.sweep.slabs = n;
    }
    if let Some(k) = &args.kernel {
        scene.sweep.kernel = k
            .parse::<KernelSpec>()
            .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("--kernel: {e}")))?;
    }
    if let Some(s) = args.seed {
        scene.sweep.seed = s;
    }
    if let Some(p) = args.penumbra {
        scene.sweep.penumbra = p;
    }
    if let Some(g) = args.guard_band {
        scene.sweep.guard_band = g;
    }
    if let Some(v) = args.variance_compensation {
        scene.sweep.variance_compensation = v;
    }
    if let Some(v) = args.preintegration {
        scene.sweep.preintegration = v;
    }
    scene
        .revalidate()
        .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("command-line override: {e}")))?;
    Ok(())
}

/// The output files (defaults, frame patterns), checked before any work: writable, not colliding,
/// with an image extension.
fn output_paths(args: &RenderArgs, frame_list: Option<&[u32]>) -> Result<Vec<PathBuf>, Failure> {
    let outputs = if args.outputs.is_empty() {
        match frame_list {
            Some(_) => vec![PathBuf::from("render_%04d.png")],
            None => vec![PathBuf::from("render.png")],
        }
    } else {
        args.outputs.clone()
    };
    if let Some(list) = frame_list
        && list.len() > 1
        && let Some(p) = outputs.iter().find(|p| !frames::has_frame_pattern(p))
    {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            format!(
                "{}: {} frames would overwrite one file; put a frame number pattern in the \
                 name, such as out_%04d.png",
                p.display(),
                list.len()
            ),
        ));
    }
    if args.backend == RenderBackend::Reference && frame_list.is_some() {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            "--frames/--frame do not apply to --backend reference",
        ));
    }
    let first_outputs: Vec<PathBuf> = match frame_list {
        Some(list) => outputs
            .iter()
            .map(|p| frames::frame_path(p, list[0]))
            .collect(),
        None => outputs.clone(),
    };
    super::refuse_collisions(first_outputs.iter().chain(&args.stats_json))?;
    for p in first_outputs.iter().chain(&args.stats_json) {
        convshadow_common::image_io::check_writable(p)?;
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if args.stats_json.as_ref() != Some(p) && !matches!(ext.as_deref(), Some("png" | "exr")) {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!(
                    "{}: unknown image extension; expected .png or .exr",
                    p.display()
                ),
            ));
        }
    }

    Ok(outputs)
}

/// The slab progress bar on a terminal (none when quiet, redirected, or for the reference).
fn progress_bar(args: &RenderArgs) -> Option<indicatif::ProgressBar> {
    // The reference has no per-slab progress to show.
    if !args.quiet && std::io::stderr().is_terminal() && args.backend != RenderBackend::Reference {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template("{spinner} slab {pos}/{len} {wide_bar} {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    }
}

/// `--reference-samples`: the light directions of the reference (0 for the other backends).
fn reference_samples(args: &RenderArgs) -> Result<u32, Failure> {
    Ok(match (args.backend, args.reference_samples) {
        (RenderBackend::Reference, None) => ReferenceOptions::default().samples,
        (RenderBackend::Reference, Some(0)) => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                "--reference-samples: expected at least 1 light direction, got 0",
            ));
        }
        (RenderBackend::Reference, Some(m)) if m > MAX_REFERENCE_SAMPLES => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!(
                    "--reference-samples: expected 1 to {MAX_REFERENCE_SAMPLES} light directions, got {m}"
                ),
            ));
        }
        (RenderBackend::Reference, Some(m)) => m,
        (_, Some(_)) => {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                "--reference-samples only applies to --backend reference",
            ));
        }
        (_, None) => 0,
    })
}

/// A frame sequence being rendered under one progress bar.
struct Sequence<'a> {
    scene: &'a Scene,
    request: &'a RenderRequest<'a>,
    outputs: &'a [PathBuf],
    bar: Option<&'a indicatif::ProgressBar>,
    frame_index: &'a std::sync::atomic::AtomicU64,
    slab_count: &'a std::sync::atomic::AtomicU64,
    time_step: f64,
}

impl Sequence<'_> {
    /// Renders and writes every frame of `list`; returns the last render and each frame's numbers.
    fn render(&self, list: &[u32]) -> Result<(Rendered, Vec<FrameStats>), Failure> {
        let (scene, request, outputs, bar) = (self.scene, self.request, self.outputs, self.bar);
        let (frame_index, slab_count, time_step) =
            (self.frame_index, self.slab_count, self.time_step);
        let frame_count = list.len() as u64;
        let mut done: Vec<FrameStats> = Vec::new();
        let mut last = None;
        for (i, &k) in list.iter().enumerate() {
            use std::sync::atomic::Ordering::Relaxed;
            frame_index.store(i as u64, Relaxed);
            if let Some(b) = &bar {
                b.set_message(format!("frame {}/{}", i + 1, list.len()));
            }
            let frame_scene = frames::scene_at_frame(scene, k, time_step);
            let r = render(&frame_scene, request)?;
            if i == 0 {
                if let Some(note) = &r.backend_note {
                    eprintln!("note: {}", crate::cli::exit::escape_line(note));
                }
                slab_count.store(u64::from(r.plan.slabs), Relaxed);
                if let Some(b) = &bar {
                    b.set_length(u64::from(r.plan.slabs) * frame_count);
                }
            }
            exit::check_interrupt()?;
            let paths: Vec<PathBuf> = outputs.iter().map(|p| frames::frame_path(p, k)).collect();
            for p in &paths {
                r.image.save_mapped(p, &scene.image.display_map())?;
            }
            done.push(FrameStats {
                frame: k,
                time: frames::frame_time(scene, k, time_step),
                image_hash: r.image_hash,
                ldi_hash: r.ldi_hash,
                seconds_total: r.seconds_total,
                outputs: paths,
            });
            last = Some(r);
        }
        let r = last.expect("a parsed frame list is not empty");
        Ok((r, done))
    }
}

/// Stats and summary of a sequence (each frame is already written).
fn finish_frames(
    scene: &Scene,
    args: &RenderArgs,
    last: &Rendered,
    bar: Option<&indicatif::ProgressBar>,
    done: &[FrameStats],
    time_step: f64,
) -> Result<i32, Failure> {
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let seconds: f64 = done.iter().map(|f| f.seconds_total).sum();
    if let Some(p) = &args.stats_json {
        let mut value = stats_value(scene, args, last, 0, &[]);
        if let Some(o) = value.as_object_mut() {
            for key in ["image_hash", "outputs", "seconds_ldi", "seconds_sweep"] {
                o.remove(key);
            }
            o.insert("seconds_total".into(), json!(seconds));
            o.insert("time_step".into(), json!(time_step));
            o.insert(
                "frames".into(),
                json!(
                    done.iter()
                        .map(|f| json!({
                            "frame": f.frame,
                            "time": f.time,
                            "image_hash": format!("{:016x}", f.image_hash),
                            "ldi_hash": format!("{:016x}", f.ldi_hash),
                            "seconds_total": f.seconds_total,
                            "outputs": f.outputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
                        }))
                        .collect::<Vec<_>>()
                ),
            );
        }
        super::write_json(p, &value)?;
    }
    if !args.quiet {
        for f in done {
            println!(
                "frame {} (time {}): image_hash {:016x}, {:.2} s → {}",
                f.frame,
                f.time.map_or_else(|| "-".to_string(), |t| format!("{t}")),
                f.image_hash,
                f.seconds_total,
                f.outputs
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        println!(
            "rendered {} frame{} of {}x{} px, {} slabs{}, {}: {:.2} s",
            done.len(),
            if done.len() == 1 { "" } else { "s" },
            scene.image.width,
            scene.image.height,
            last.plan.slabs,
            auto_note(last),
            plural(last.plan.lights.len(), "light"),
            seconds
        );
    }
    Ok(exit::OK)
}

/// `n thing` or `n things`.
pub fn plural(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}

/// Writes the outputs and the stats of a finished render and prints the summary line.
fn finish(
    scene: &Scene,
    args: &RenderArgs,
    outputs: &[PathBuf],
    r: &Rendered,
    bar: Option<&indicatif::ProgressBar>,
    samples: u32,
) -> Result<i32, Failure> {
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    exit::check_interrupt()?;
    for p in outputs {
        r.image.save_mapped(p, &scene.image.display_map())?;
    }
    if let Some(p) = &args.stats_json {
        super::write_json(p, &stats_value(scene, args, r, samples, outputs))?;
    }
    for w in &r.mesh_warnings {
        eprintln!("warning: {}", crate::cli::exit::escape_line(w));
    }
    if r.ldi.odd_pixels > 0 {
        eprintln!(
            "warning: {} pixels have an odd fragment count (open meshes, rendered with --allow-open)",
            r.ldi.odd_pixels
        );
    }
    let throughput = throughput(r);
    if !args.quiet {
        println!(
            "rendered {}x{} px, {} slabs{}{}, {}, {}, guard band {}, {} fragments: {:.2} s (LDI \
             {:.2} s, sweep {:.2} s, {:.1} M pixel·slab·light/s, {}) → {}",
            scene.image.width,
            scene.image.height,
            r.plan.slabs,
            auto_note(r),
            early_note(r),
            plural(r.plan.lights.len(), "light"),
            scene.sweep.kernel,
            r.plan.guard,
            r.ldi.fragments,
            r.seconds_total,
            r.seconds_ldi,
            r.seconds_sweep,
            throughput / 1e6,
            match &r.adapter {
                Some(a) => format!("GPU: {a}"),
                None if samples > 0 => format!(
                    "reference: {} light directions, {} threads",
                    samples_side(samples) * samples_side(samples),
                    r.threads
                ),
                None => format!("CPU: {} threads, {} path", r.threads, args.path.name()),
            },
            outputs
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(exit::OK)
}

/// ` (auto: …)` after the slab count when `slabs = "auto"` chose it, else nothing.
fn auto_note(r: &Rendered) -> String {
    match &r.plan.auto_slabs {
        None => String::new(),
        Some(a) => match (&a.finest_period, &a.limited_by) {
            (Some(p), Some(key)) => format!(
                " (auto: 2 per finest period {p:.3e} of {key} along the view, × slab_factor {})",
                a.factor
            ),
            _ => format!(" (auto: no detail, the minimum × slab_factor {})", a.factor),
        },
    }
}

/// ` (N swept: …)` after the slab count when the sweep finished early, else nothing.
fn early_note(r: &Rendered) -> String {
    if r.slabs_swept > 0 && r.slabs_swept < r.plan.slabs {
        format!(
            " ({} swept: every image pixel opaque after them)",
            r.slabs_swept
        )
    } else {
        String::new()
    }
}

/// The plan's pixel·slab·light updates per second of the sweep: the frame's rate, counting the
/// slabs an early finish left out (there is nothing in them to compute).
fn throughput(r: &Rendered) -> f64 {
    let updates = f64::from(r.plan.grid_width)
        * f64::from(r.plan.grid_height)
        * f64::from(r.plan.slabs)
        * r.plan.lights.len() as f64;
    updates / r.seconds_sweep.max(1e-9)
}

/// The `--stats-json` object of one render.
fn stats_value(
    scene: &Scene,
    args: &RenderArgs,
    r: &Rendered,
    samples: u32,
    outputs: &[PathBuf],
) -> serde_json::Value {
    let throughput = throughput(r);
    json!({
            "width": scene.image.width,
            "height": scene.image.height,
            "slabs": r.plan.slabs,
            "slabs_swept": r.slabs_swept,
            "slabs_auto": r.plan.auto_slabs.as_ref().map(|a| json!({
                "finest_period": a.finest_period,
                "limited_by": a.limited_by,
                "slab_factor": a.factor,
            })),
            "slab_distance": f64::from(r.plan.slab_distance),
            "kernel": scene.sweep.kernel.to_string(),
            "penumbra": scene.sweep.penumbra.to_string(),
            "preintegration": r.plan.preintegration,
            "guard_band": scene.sweep.guard_band.to_string(),
            "guard_band_px": {
                "left": r.plan.guard.left,
                "right": r.plan.guard.right,
                "top": r.plan.guard.top,
                "bottom": r.plan.guard.bottom,
            },
            "grid_width": r.plan.grid_width,
            "grid_height": r.plan.grid_height,
            "lights": r.plan.lights.len(),
            "channels": r.plan.channels,
            "fragments": r.ldi.fragments,
            "max_layers": r.ldi.max_layers,
            "odd_pixels": r.ldi.odd_pixels,
            "threads": r.threads,
            "path": args.path.name(),
            "chunks_full": r.chunks[0],
            "chunks_skipped_unoccluded": r.chunks[1],
            "chunks_skipped_dark": r.chunks[2],
            "backend": r.backend,
            "adapter": r.adapter,
            "reference_samples": (samples > 0).then_some(samples),
            "seconds_ldi": r.seconds_ldi,
            "seconds_plan": r.seconds_plan,
            "seconds_sweep": r.seconds_sweep,
            "seconds_total": r.seconds_total,
            "pixel_slab_lights_per_second": throughput,
            "ldi_hash": format!("{:016x}", r.ldi_hash),
            "image_hash": format!("{:016x}", r.image_hash),
            "outputs": outputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        "exposure": scene.image.exposure,
        "tonemap": scene.image.tonemap.name(),
    })
}

/// Renders with the ground-truth reference (`--backend reference`): the same checks and LDI as
/// the pipeline, then [`Reference::render`] with `samples` light directions per shading point.
/// No interrupt handler is installed for it: a signal ends the process at once, before any output
/// is written (outputs are only ever renamed into place complete).
fn render_reference(
    scene: &Scene,
    threads: usize,
    samples: u32,
    budget: u64,
    allow_open: bool,
) -> Result<Rendered, Failure> {
    let start = Instant::now();
    MemoryNeed::of(scene, scene.sweep.guard_band.lower_bound(), true).check(scene, budget)?;
    let pool = super::thread_pool(threads)?;
    let geometry = SceneGeometry::build(scene)?;
    let fragment_budget =
        MemoryNeed::of(scene, geometry.raster.guard, true).check(scene, budget)?;
    exit::check_interrupt()?;
    let ldi = pool.install(|| Ldi::build(&geometry.raster, fragment_budget))?;
    let stats = pool.install(|| ldi.stats());
    if !allow_open && (geometry.defect_edges() > 0 || stats.odd_pixels > 0) {
        return Err(Failure::new(
            exit::MESH_DEFECT,
            format!(
                "{}: refusing to render: the inside/outside test needs closed, consistently wound \
                 meshes, but {} mesh edges are open, non-manifold or flipped and {} pixels have \
                 an odd fragment count. Pass --allow-open to render anyway.",
                scene.source,
                geometry.defect_edges(),
                stats.odd_pixels
            ),
        ));
    }
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_plan = Instant::now();
    let plan = RenderPlan::new(scene, &geometry)
        .map_err(|e| Failure::new(exit::BAD_INPUT, e.to_string()))?;
    let seconds_plan = t_plan.elapsed().as_secs_f64();
    exit::check_interrupt()?;
    let t_render = Instant::now();
    let data = {
        let reference = Reference::new(scene, &geometry, &plan, 0.0);
        let options = ReferenceOptions {
            samples,
            ..ReferenceOptions::default()
        };
        pool.install(|| reference.render(&ldi, &options))
    };
    let seconds_sweep = t_render.elapsed().as_secs_f64();
    Ok(Rendered {
        mesh_warnings: geometry.mesh_warnings(),
        image_hash: image_fingerprint(&data),
        image: RgbImage {
            width: scene.image.width,
            height: scene.image.height,
            data,
        },
        ldi: stats,
        ldi_hash: ldi.fingerprint(),
        plan,
        light: Vec::new(),
        // The reference traces shadow rays: it sweeps no slab.
        slabs_swept: 0,
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
