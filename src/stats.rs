//! The numbers of one render as `convshadow render --stats-json` writes them, shared with the
//! Python module (its `stats` dict), and the sweep's throughput of the summary line.

use std::path::PathBuf;

use convshadow_common::model::scene::Scene;
use serde_json::json;

use crate::pipeline::{CpuPath, Rendered};

/// The sweep's pixel·slab·light updates per second ([`Rendered::updates`], every pass): the
/// frame's rate, counting the slabs an early finish left out (there is nothing in them to
/// compute).
pub fn throughput(r: &Rendered) -> f64 {
    r.updates / r.seconds_sweep.max(1e-9)
}

/// The `--stats-json` object of one render.
///
/// `path` is the CPU path asked for, `samples` the reference's light directions (0 for the
/// other backends), `outputs` the files written.
pub fn render_stats(
    scene: &Scene,
    r: &Rendered,
    path: CpuPath,
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
            "media": scene.sweep.media.to_string(),
            "preintegration": r.plan.preintegration,
            "subpixel_shadows": !r.plan.subpixel_meshes.is_empty(),
            "guard_band": scene.sweep.guard_band.to_string(),
            "guard_band_px": {
                "left": r.plan.guard.left,
                "right": r.plan.guard.right,
                "top": r.plan.guard.top,
                "bottom": r.plan.guard.bottom,
            },
            "grid_width": r.plan.grid_width,
            "grid_height": r.plan.grid_height,
            "lights": scene.lights.len(),
            "lights_toward_viewer": r.turned_round_lights,
            "channels": r.plan.channels,
            "fragments": r.ldi.fragments,
            "max_layers": r.ldi.max_layers,
            "odd_pixels": r.ldi.odd_pixels,
            "threads": r.threads,
            "path": path.name(),
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
