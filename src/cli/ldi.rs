//! `convshadow ldi`: build the layered depth image and report its numbers and mesh defects.

use std::path::PathBuf;

use serde_json::json;

use crate::cli::exit::{self, Failure};
use convshadow::pipeline::{BuiltLdi, build_ldi};

/// Arguments of `convshadow ldi`.
#[derive(clap::Args, Debug)]
pub struct LdiArgs {
    /// Scene file (TOML); without it, the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Override the image width.
    #[arg(long, value_parser = super::parse_side)]
    pub width: Option<u32>,
    /// Override the image height.
    #[arg(long, value_parser = super::parse_side)]
    pub height: Option<u32>,
    /// Worker threads (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = super::parse_threads)]
    pub threads: usize,
    /// Write the numbers as JSON.
    #[arg(long)]
    pub stats_json: Option<PathBuf>,
    /// Backend: the CPU oracle, the GPU (wgpu/Vulkan; exit code 5 without an adapter), or auto
    /// (the GPU when an adapter exists, else the CPU with a message).
    #[arg(long, value_enum, default_value_t = convshadow::pipeline::Backend::Cpu)]
    pub backend: convshadow::pipeline::Backend,
    /// Write the layer count per pixel as a grey PNG (white = the most layers), over the whole
    /// grid: the image and its guard band.
    #[arg(long)]
    pub layers_png: Option<PathBuf>,
    /// Memory budget in MiB for the LDI (default: half the machine's memory).
    #[arg(long)]
    pub max_memory: Option<u64>,
}

/// Runs `convshadow ldi`; open meshes are reported (thin shells, a warning each), and exit code
/// 6 says a closed mesh left a pixel with an odd fragment count.
pub fn run(args: &LdiArgs) -> Result<i32, Failure> {
    // The LDI build has no cancel point: a signal ends the run at once, before any output.
    crate::cli::exit::install_exit_on_signal(None);
    let mut scene = super::load_scene(args.scene.as_deref())?;
    super::override_size(&mut scene, args.width, args.height)?;
    super::require_png("--layers-png", args.layers_png.as_ref())?;
    super::refuse_collisions(args.stats_json.iter().chain(&args.layers_png))?;
    super::refuse_outputs_over_inputs(
        args.stats_json.iter().chain(&args.layers_png),
        &super::scene_inputs(args.scene.as_deref(), &scene),
    )?;
    for p in args.stats_json.iter().chain(&args.layers_png) {
        convshadow_io::image::check_writable(p)?;
    }
    let budget = convshadow::overrides::memory_budget(args.max_memory);
    let built = build_ldi(&scene, args.backend, args.threads, budget)?;
    if let Some(note) = &built.backend_note {
        convshadow::errln!("note: {}", crate::cli::exit::escape_line(note));
    }
    let hash = built.ldi.fingerprint();
    print_summary(&built, hash);
    if let Some(path) = &args.layers_png {
        write_layers_png(path, &built)?;
    }
    if let Some(path) = &args.stats_json {
        write_stats(path, &built, hash)?;
    }
    let (geometry, stats) = (&built.geometry, &built.stats);
    for w in geometry.mesh_warnings() {
        convshadow::errln!("warning: {}", crate::cli::exit::escape_line(&w));
    }
    if stats.odd_pixels > 0 {
        convshadow::errln!(
            "error: {} pixels have an odd fragment count of a closed mesh: the inside/outside \
             parity test would smear them",
            stats.odd_pixels
        );
        return Ok(exit::MESH_DEFECT);
    }
    Ok(exit::OK)
}

/// Per mesh: (boundary, non-manifold, flipped) edge counts, and the degenerate triangles dropped.
fn defect_counts(built: &BuiltLdi) -> (Vec<usize>, Vec<usize>, Vec<usize>, usize) {
    let geometry = &built.geometry;
    let degenerate: usize = geometry
        .meshes
        .iter()
        .map(|m| m.report.degenerate_triangles)
        .sum();
    let boundary: Vec<usize> = geometry
        .meshes
        .iter()
        .map(|m| m.report.boundary_edges)
        .collect();
    let nonmanifold: Vec<usize> = geometry
        .meshes
        .iter()
        .map(|m| m.report.nonmanifold_edges)
        .collect();
    let flipped: Vec<usize> = geometry
        .meshes
        .iter()
        .map(|m| m.report.flipped_edges)
        .collect();
    (boundary, nonmanifold, flipped, degenerate)
}

/// The summary lines on stdout.
fn print_summary(built: &BuiltLdi, hash: u64) {
    let BuiltLdi {
        geometry,
        ldi,
        stats,
        adapter,
        seconds_ldi,
        ..
    } = built;
    let (_, _, _, degenerate) = defect_counts(built);
    convshadow::outln!(
        "ldi: {}x{} px (grid {}x{}, guard band {}), {} triangles rasterized of {}, {} fragments, \
         max {} layers, {} odd pixels, {} degenerate triangles dropped, {:.3} s build ({:.1} M \
         fragments/s)",
        geometry.camera.width,
        geometry.camera.height,
        ldi.width,
        ldi.height,
        geometry.raster.guard,
        geometry.raster.triangles.len(),
        geometry
            .meshes
            .iter()
            .map(|m| m.mesh.triangles.len())
            .sum::<usize>(),
        stats.fragments,
        stats.max_layers,
        stats.odd_pixels,
        degenerate,
        seconds_ldi,
        stats.fragments as f64 / seconds_ldi.max(1e-9) / 1e6,
    );
    for (i, m) in geometry.meshes.iter().enumerate() {
        convshadow::outln!(
            "  mesh[{i}]: {} triangles, {} boundary edges, {} non-manifold edges, {} flipped edges{}",
            m.mesh.triangles.len(),
            m.report.boundary_edges,
            m.report.nonmanifold_edges,
            m.report.flipped_edges,
            if m.report.is_closed() {
                ""
            } else {
                "  (NOT CLOSED)"
            }
        );
    }
    convshadow::outln!("  ldi_hash {hash:016x}");
    if let Some(a) = &adapter {
        convshadow::outln!("  backend gpu: {a}");
    }
}

/// `--layers-png`: the layer count per pixel as an 8-bit image, scaled to the maximum (the whole
/// grid: the image and its guard band).
fn write_layers_png(path: &std::path::Path, built: &BuiltLdi) -> Result<(), Failure> {
    let (ldi, stats) = (&built.ldi, &built.stats);
    let max = stats.max_layers.max(1);
    let n = (ldi.width * ldi.height) as usize;
    let data = (0..n)
        .map(|p| ((ldi.offsets[p + 1] - ldi.offsets[p]) * 255 / max) as u8)
        .collect();
    convshadow_io::image::save_gray_png(path, ldi.width, ldi.height, data)?;
    Ok(())
}

/// `--stats-json`: the LDI's numbers.
fn write_stats(path: &std::path::Path, built: &BuiltLdi, hash: u64) -> Result<(), Failure> {
    let BuiltLdi {
        geometry,
        ldi,
        stats,
        threads,
        backend,
        adapter,
        seconds_ldi,
        seconds_total,
        ..
    } = built;
    let (boundary, nonmanifold, flipped, degenerate) = defect_counts(built);
    let value = json!({
        "version": env!("CARGO_PKG_VERSION"),
        "width": geometry.camera.width,
        "height": geometry.camera.height,
        "grid_width": ldi.width,
        "grid_height": ldi.height,
        "guard_band_px": {
            "left": geometry.raster.guard.left,
            "right": geometry.raster.guard.right,
            "top": geometry.raster.guard.top,
            "bottom": geometry.raster.guard.bottom,
        },
        "triangles": geometry.raster.triangles.len(),
        "fragments": stats.fragments,
        "max_layers": stats.max_layers,
        "odd_pixels": stats.odd_pixels,
        "degenerate_triangles": degenerate,
        "boundary_edges": boundary,
        "nonmanifold_edges": nonmanifold,
        "flipped_edges": flipped,
        "shell_meshes": geometry.shell_meshes(),
        "threads": threads,
        "backend": backend,
        "adapter": adapter,
        "seconds_ldi": seconds_ldi,
        "seconds_total": seconds_total,
        "ldi_hash": format!("{hash:016x}"),
    });
    super::write_json(path, &value)?;
    Ok(())
}
