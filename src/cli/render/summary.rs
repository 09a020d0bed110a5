//! What `convshadow render` does once a render is done: writes its outputs (a sequence's frames
//! are written as they finish) and `--stats-json`, prints the mesh warnings and the summary line.

use std::path::{Path, PathBuf};

use convshadow::pipeline::Rendered;
use convshadow::stats::{render_stats, throughput};
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
        crate::cli::write_json(p, &render_stats(scene, r, args.path, samples, outputs))?;
        written.push(p.clone());
    }
    exit::check_interrupt_after(&written)?;
    for w in &r.mesh_warnings {
        convshadow::errln!("warning: {}", crate::cli::exit::escape_line(w));
    }
    if r.ldi.odd_pixels > 0 {
        convshadow::errln!(
            "warning: {} pixels have an odd fragment count of a closed mesh (rendered with \
             --allow-open)",
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
            lights_note(scene, r),
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
        let mut value = render_stats(scene, last, args.path, 0, &[]);
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
            lights_note(scene, last),
            seconds
        );
    }
    Ok(exit::OK)
}

/// `n lights`, and how many of them the turned-round pass swept.
fn lights_note(scene: &Scene, r: &Rendered) -> String {
    let all = plural(scene.lights.len(), "light");
    match r.turned_round_lights {
        0 => all,
        n => format!("{all} ({n} from in front of the viewer: a second pass, from the far end)"),
    }
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
