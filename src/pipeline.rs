//! The render pipeline as a library call: scene → geometry → LDI → plan → sweep → image.
//! The `render` command and the tests both go through [`render`].

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use convshadow_common::geometry::SceneGeometry;
use convshadow_common::hash::Fingerprint;
use convshadow_common::image_io::RgbImage;
use convshadow_common::plan::RenderPlan;
use convshadow_common::scene::Scene;
use convshadow_cpu::ldi::{Ldi, LdiStats};
use convshadow_cpu::sweep::{SweepError, SweepOptions, sweep};

use crate::exit::{self, Failure};

/// Which CPU code path runs the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CpuPath {
    /// The plain-Rust reference path.
    Scalar,
}

impl CpuPath {
    /// The name used in stats.
    pub fn name(self) -> &'static str {
        match self {
            CpuPath::Scalar => "scalar",
        }
    }
}

/// How to render.
pub struct RenderRequest<'a> {
    /// Worker threads (0 = one per core).
    pub threads: usize,
    /// CPU code path.
    pub path: CpuPath,
    /// Memory budget in bytes for the LDI.
    pub memory_budget: u64,
    /// Render even if meshes are open (the odd pixels are reported).
    pub allow_open: bool,
    /// Called after each slab.
    pub progress: &'a (dyn Fn(u32) + Sync),
    /// Raised to stop the sweep.
    pub cancel: Option<&'a AtomicBool>,
}

impl Default for RenderRequest<'_> {
    fn default() -> Self {
        RenderRequest {
            threads: 0,
            path: CpuPath::Scalar,
            memory_budget: convshadow_cpu::default_memory_budget(),
            allow_open: false,
            progress: &|_| {},
            cancel: None,
        }
    }
}

/// A finished render and its numbers.
pub struct Rendered {
    /// The linear float image.
    pub image: RgbImage,
    /// 64-bit fingerprint of the image's float bits (`image_hash`).
    pub image_hash: u64,
    /// LDI numbers.
    pub ldi: LdiStats,
    /// LDI fingerprint.
    pub ldi_hash: u64,
    /// The plan (tables) used.
    pub plan: RenderPlan,
    /// Light buffers after the last slab.
    pub light: Vec<f32>,
    /// Threads used.
    pub threads: usize,
    /// Seconds building geometry and the LDI.
    pub seconds_ldi: f64,
    /// Seconds in the sweep.
    pub seconds_sweep: f64,
    /// Seconds in all.
    pub seconds_total: f64,
}

/// Fingerprint of a float image's bits.
pub fn image_fingerprint(data: &[f32]) -> u64 {
    let mut f = Fingerprint::default();
    f.floats(data);
    f.finish()
}

/// Renders a scene on the CPU.
pub fn render(scene: &Scene, req: &RenderRequest<'_>) -> Result<Rendered, Failure> {
    let start = Instant::now();
    let pool = crate::commands::thread_pool(req.threads)?;
    let geometry = SceneGeometry::build(scene)?;
    let ldi = pool.install(|| Ldi::build(&geometry.raster, req.memory_budget))?;
    let stats = pool.install(|| ldi.stats());
    if !req.allow_open && (geometry.defect_edges() > 0 || stats.odd_pixels > 0) {
        let names: Vec<String> = geometry
            .meshes
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.report.is_closed())
            .map(|(i, m)| {
                format!(
                    "mesh[{i}] has {} boundary, {} non-manifold and {} flipped edges",
                    m.report.boundary_edges, m.report.nonmanifold_edges, m.report.flipped_edges
                )
            })
            .collect();
        return Err(Failure::new(
            exit::MESH_DEFECT,
            format!(
                "{}: refusing to render: the inside/outside parity test needs closed, consistently \
                 wound meshes, but {}{} pixels have an odd fragment count. Pass --allow-open to \
                 render anyway.",
                scene.source,
                if names.is_empty() {
                    String::new()
                } else {
                    names.join("; ") + "; "
                },
                stats.odd_pixels
            ),
        ));
    }
    let plan = RenderPlan::new(scene, &geometry)
        .map_err(|e| Failure::new(exit::BAD_INPUT, e.to_string()))?;
    let seconds_ldi = start.elapsed().as_secs_f64();
    let t_sweep = Instant::now();
    let options = SweepOptions {
        progress: req.progress,
        cancel: req.cancel,
        initial_light: None,
    };
    let out = pool
        .install(|| match req.path {
            CpuPath::Scalar => sweep(&plan, &geometry.raster, &ldi, &options),
        })
        .map_err(|e| match e {
            SweepError::Interrupted => {
                Failure::new(exit::INTERRUPTED, "interrupted; no output written")
            }
        })?;
    let seconds_sweep = t_sweep.elapsed().as_secs_f64();
    let image_hash = image_fingerprint(&out.image);
    Ok(Rendered {
        image: RgbImage {
            width: scene.image.width,
            height: scene.image.height,
            data: out.image,
        },
        image_hash,
        ldi: stats,
        ldi_hash: ldi.fingerprint(),
        plan,
        light: out.light,
        threads: pool.current_num_threads(),
        seconds_ldi,
        seconds_sweep,
        seconds_total: start.elapsed().as_secs_f64(),
    })
}
