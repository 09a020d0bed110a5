//! What `convshadow render` does once a render is done: writes its outputs (a sequence's frames
//! are written as they finish) and `--stats-json`, prints the mesh warnings and the summary line.

use std::path::{Path, PathBuf};

use convshadow::pipeline::Rendered;
use convshadow_common::model::scene::Scene;
use convshadow_io::image::ExrChannel;
use convshadow_reference::samples_side;
use serde_json::json;

use super::args::RenderArgs;
use crate::cli::exit::{self, Failure};

/// One rendered frame of a sequence, for the stats.
pub(super) struct FrameStats {
    pub(super) frame: u32,
    pub(super) time: Option<f64>,
    pub(super) image_hash: u64,
    pub(super) ldi_hash: u64,
    pub(super) seconds_total: f64,
    pub(super) outputs: Vec<PathBuf>,
}

/// Writes one output of a render: a PNG through the scene's display map; an EXR with the linear
/// RGB, the alpha `A` and the `--aov` layers the render made (`Z`, `lightN.R/G/B`).
pub(super) fn save_output(scene: &Scene, r: &Rendered, path: &Path) -> Result<(), Failure> {
    let is_exr = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        r.image.save_mapped(path, &scene.image.display_map())?;
        return Ok(());
    }
    let mut planes: Vec<(String, Vec<f32>)> = Vec::new();
    for (l, layer) in &r.light_layers {
        for (k, c) in ["R", "G", "B"].iter().enumerate() {
            let plane = layer.iter().skip(k).step_by(3).copied().collect();
            planes.push((format!("light{l}.{c}"), plane));
        }
    }
    let mut channels = vec![ExrChannel {
        name: "A",
        data: &r.alpha,
    }];
    if let Some(depth) = &r.depth {
        channels.push(ExrChannel {
            name: "Z",
            data: depth,
        });
    }
    channels.extend(planes.iter().map(|(name, data)| ExrChannel { name, data }));
    r.image.save_exr(path, &channels)?;
    Ok(())
}

/// Writes the outputs and the stats of a finished render and prints the summary line.
pub(super) fn finish(
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
    // A signal while the outputs are written stops before the next one and names those done.
    let mut written: Vec<PathBuf> = Vec::new();
    for p in outputs {
        exit::check_interrupt_after(&written)?;
        save_output(scene, r, p)?;
        written.push(p.clone());
    }
    if let Some(p) = &args.stats_json {
        exit::check_interrupt_after(&written)?;
        crate::cli::write_json(p, &stats_value(scene, args, r, samples, outputs))?;
        written.push(p.clone());
    }
    exit::check_interrupt_after(&written)?;
    for w in &r.mesh_warnings {
        convshadow::errln!("warning: {}", crate::cli::exit::escape_line(w));
    }
    if r.ldi.odd_pixels > 0 {
        convshadow::errln!(
            "warning: {} pixels have an odd fragment count (open meshes, rendered with --allow-open)",
            r.ldi.odd_pixels
        );
    }
    let throughput = throughput(r);
    if !args.quiet {
        convshadow::outln!(
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

/// Stats and summary of a sequence (each frame is already written).
pub(super) fn finish_frames(
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
        crate::cli::write_json(p, &value)?;
    }
    if !args.quiet {
        for f in done {
            convshadow::outln!(
                "frame {} (time {}): image_hash {:016x}, {:.2} s → {}",
                f.frame,
                f.time
                    .map_or_else(|| "-".to_string(), crate::cli::frames::display_time),
                f.image_hash,
                f.seconds_total,
                f.outputs
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        convshadow::outln!(
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
fn plural(n: usize, thing: &str) -> String {
    if n == 1 {
        format!("1 {thing}")
    } else {
        format!("{n} {thing}s")
    }
}

/// ` (auto: …)` after the slab count when `slabs = "auto"` chose it, else nothing.
fn auto_note(r: &Rendered) -> String {
    match &r.plan.auto_slabs {
        None => String::new(),
        Some(a) => match (&a.finest_period, &a.limited_by) {
            (Some(p), Some(key)) if a.minimum => format!(
                " (auto: the minimum × slab_factor {}; the finest length along the view, \
                 {p:.3e} of {key}, asks fewer)",
                a.factor
            ),
            (Some(p), Some(key)) if key.starts_with("mesh[") => format!(
                " (auto: 2 across the thinnest feature {p:.3e} of {key} along the view, × \
                 slab_factor {})",
                a.factor
            ),
            (Some(p), Some(key)) => format!(
                " (auto: 2 per finest period {p:.3e} of {key} along the view, × slab_factor {})",
                a.factor
            ),
            _ => format!(
                " (auto: no detail or mesh thickness seen, the minimum × slab_factor {})",
                a.factor
            ),
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
            "version": env!("CARGO_PKG_VERSION"),
            "width": scene.image.width,
            "height": scene.image.height,
            "slabs": r.plan.slabs,
            "slabs_swept": r.slabs_swept,
            "slabs_auto": r.plan.auto_slabs.as_ref().map(|a| json!({
                "finest_period": a.finest_period,
                "limited_by": a.limited_by,
                "minimum": a.minimum,
                "thinnest": a.thinnest.map(|t| json!({
                    "mesh": t.mesh,
                    "thickness": t.thickness,
                })),
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
