//! `convshadow render`: render a scene (or the embedded default scene) to PNG and/or EXR.

use std::io::IsTerminal;
use std::path::PathBuf;

use convshadow_common::kernel::KernelSpec;
use convshadow_common::scene::SlabSpec;
use serde_json::json;

use crate::exit::{self, Failure};
use crate::pipeline::{Backend, CpuPath, RenderRequest, render};

/// Arguments of `convshadow render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML); without it, the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output image(s): `.png` (sRGB 8-bit) or `.exr` (linear float); may repeat.
    /// Default: render.png in the current folder.
    #[arg(short = 'o', long = "output")]
    pub outputs: Vec<PathBuf>,
    /// Override the image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Override the slab count.
    #[arg(long)]
    pub slabs: Option<u32>,
    /// Override the kernel (ellipse2, ellipse3, ellipseN:slab, dirac, poisson8, poisson16, gaussian:K, box).
    #[arg(long)]
    pub kernel: Option<String>,
    /// Override the seed.
    #[arg(long)]
    pub seed: Option<u32>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// CPU code path.
    #[arg(long, value_enum, default_value_t = CpuPath::Scalar)]
    pub path: CpuPath,
    /// Backend: the CPU oracle, the GPU (wgpu/Vulkan; exit code 5 without an adapter), or auto
    /// (the GPU when an adapter exists, else the CPU with a message).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// Turn the bilinear-variance compensation on or off (overrides the scene).
    #[arg(long)]
    pub variance_compensation: Option<bool>,
    /// Render even if meshes are open (reports the pixels with odd fragment counts).
    #[arg(long)]
    pub allow_open: bool,
    /// Memory budget in MiB for the LDI and the sweep's buffers (default: half the machine's
    /// memory); a scene that needs more is refused before allocating (exit code 4).
    #[arg(long)]
    pub max_memory: Option<u64>,
    /// Write the numbers as JSON.
    #[arg(long)]
    pub stats_json: Option<PathBuf>,
    /// No progress bar and no summary line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Runs `convshadow render`.
pub fn run(args: &RenderArgs) -> Result<i32, Failure> {
    let mut scene = super::load_scene(args.scene.as_deref())?;
    super::override_size(&mut scene, args.width, args.height)?;
    if let Some(n) = args.slabs {
        scene.sweep.slabs = SlabSpec::Count(n);
    }
    if let Some(k) = &args.kernel {
        scene.sweep.kernel = k
            .parse::<KernelSpec>()
            .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("--kernel: {e}")))?;
    }
    if let Some(s) = args.seed {
        scene.sweep.seed = s;
    }
    if let Some(v) = args.variance_compensation {
        scene.sweep.variance_compensation = v;
    }
    scene
        .revalidate()
        .map_err(|e| Failure::new(exit::BAD_ARGUMENTS, format!("command-line override: {e}")))?;
    let outputs = if args.outputs.is_empty() {
        vec![PathBuf::from("render.png")]
    } else {
        args.outputs.clone()
    };
    for p in outputs.iter().chain(&args.stats_json) {
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

    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template("{spinner} slab {pos}/{len} {wide_bar} {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };
    let progress = |slab: u32| {
        if let Some(b) = &bar {
            b.set_position(u64::from(slab) + 1);
        }
    };
    if let Some(b) = &bar {
        // The slab count is known once geometry is built; a count override is known now.
        if let SlabSpec::Count(n) = scene.sweep.slabs {
            b.set_length(u64::from(n));
        }
    }
    let request = RenderRequest {
        backend: args.backend,
        threads: args.threads,
        path: args.path,
        memory_budget: args
            .max_memory
            .map_or_else(convshadow_cpu::default_memory_budget, |m| {
                m.saturating_mul(1 << 20)
            }),
        allow_open: args.allow_open,
        progress: &progress,
        // SIGINT/SIGTERM raise it: the sweep stops and nothing is written (exit code 130).
        cancel: Some(exit::install_interrupt_handler()),
    };
    let r = render(&scene, &request)?;
    if let Some(note) = &r.backend_note {
        eprintln!("note: {note}");
    }
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    exit::check_interrupt()?;
    for p in &outputs {
        r.image.save(p)?;
    }
    let updates = f64::from(r.plan.grid_width)
        * f64::from(r.plan.grid_height)
        * f64::from(r.plan.slabs)
        * r.plan.lights.len() as f64;
    let throughput = updates / r.seconds_sweep.max(1e-9);
    if let Some(p) = &args.stats_json {
        let value = json!({
            "width": scene.image.width,
            "height": scene.image.height,
            "slabs": r.plan.slabs,
            "slab_distance": f64::from(r.plan.slab_distance),
            "kernel": scene.sweep.kernel.to_string(),
            "lights": r.plan.lights.len(),
            "channels": r.plan.channels,
            "fragments": r.ldi.fragments,
            "max_layers": r.ldi.max_layers,
            "odd_pixels": r.ldi.odd_pixels,
            "threads": r.threads,
            "path": args.path.name(),
            "backend": r.backend,
            "adapter": r.adapter,
            "seconds_ldi": r.seconds_ldi,
            "seconds_sweep": r.seconds_sweep,
            "seconds_total": r.seconds_total,
            "pixel_slab_lights_per_second": throughput,
            "ldi_hash": format!("{:016x}", r.ldi_hash),
            "image_hash": format!("{:016x}", r.image_hash),
            "outputs": outputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
        });
        super::write_json(p, &value)?;
    }
    if r.ldi.odd_pixels > 0 {
        eprintln!(
            "warning: {} pixels have an odd fragment count (open meshes, rendered with --allow-open)",
            r.ldi.odd_pixels
        );
    }
    if !args.quiet {
        println!(
            "rendered {}x{} px, {} slabs, {} lights, {}, {} fragments: {:.2} s (LDI {:.2} s, sweep \
             {:.2} s, {:.1} M pixel·slab·light/s, {}) → {}",
            scene.image.width,
            scene.image.height,
            r.plan.slabs,
            r.plan.lights.len(),
            scene.sweep.kernel,
            r.ldi.fragments,
            r.seconds_total,
            r.seconds_ldi,
            r.seconds_sweep,
            throughput / 1e6,
            match &r.adapter {
                Some(a) => format!("GPU: {a}"),
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
