//! The grid of cases: kernels, slab counts, light variances and tilts, and the edge and disk
//! set-ups of one case.

use std::path::PathBuf;

use convshadow_common::model::kernel::KERNEL_NAMES;
use convshadow_common::model::scene::Penumbra;
use convshadow_reference::disk::DiskSetup;
use convshadow_reference::edge::EdgeSetup;

/// The kernels of the report: the one kernel list, without the per-slab phase variant (the
/// same pattern as its per-pixel twin, it adds no point to the figure).
pub fn kernels() -> impl Iterator<Item = &'static str> + Clone {
    KERNEL_NAMES.into_iter().filter(|k| !k.ends_with(":slab"))
}
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
/// The slab count of the narrow-band family's reference (and twice it for its self-error).
pub const NARROWBAND_REFERENCE_SLABS: u32 = 2048;

/// What to run.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// The quick subset (see [`ReportOptions::describe`]).
    pub quick: bool,
    /// Output folder.
    pub out: PathBuf,
    /// Print one line per case on stderr.
    pub verbose: bool,
    /// Run only case I (0-based, in the order of `report.csv`'s rows) and write its row alone to
    /// `report.csv` (no markdown, no plot): for running the cases as separate jobs.
    pub case: Option<usize>,
    /// Run one penumbra model only; `None`: both, every case.
    pub penumbra: Option<Penumbra>,
}

impl ReportOptions {
    /// The penumbra models every case runs with.
    pub fn penumbras(&self) -> Vec<Penumbra> {
        match self.penumbra {
            Some(p) => vec![p],
            None => vec![Penumbra::Iterated, Penumbra::Distance],
        }
    }
}

impl ReportOptions {
    /// A sentence saying which cases run.
    pub fn describe(&self) -> String {
        if self.quick {
            "quick subset: edge at d = d1/4, d1, 4·d1 × all 7 kernels × slabs 64, 128 × variance \
             zero, high × tilt 0°, 45° (compensation on), plus ellipse2 with compensation off; disk at \
             d = 4·d1, tilt 45°, high variance, slabs 128, all kernels; default scene at 24×24, \
             slabs 64, all kernels, reference M = 16 (self-error against M = 64); narrow-band \
             scene at 48×48, ellipse2 with and without pre-integration, slabs 64, 128, against \
             2048 slabs (self-error against 4096); a directional light at 0°, 100°, 180° from the view \
             over a half-plane and a translucent sheet (isotropic light), and a soft point light \
             (distance penumbra); a perspective camera \
             at fov 30° and 90° over a half-plane's shadow on a receiver; a soft point light's \
             penumbra on a wall, orthographic and perspective, light resolution 1 and 4"
                .to_string()
        } else {
            "full grid: edge at d = d1/4, d1, 4·d1 × 7 kernels × slabs 64, 128, 256, 512 × variance \
             zero, low, high × tilt 0°, 45°, with compensation on and off; disk at d = d1 and 4·d1 \
             × 7 kernels × 4 slab counts × 3 variances × 2 tilts (compensation on); default scene \
             at 24×24 × 7 kernels × slabs 64, 128, 256, 512, reference M = 16 (self-error against \
             M = 64); narrow-band scene at 64×64, ellipse2 with and without pre-integration × \
             slabs 64, 128, 256, 512, against 2048 slabs (self-error against 4096); a directional \
             light at 0°, 45°, 80°, 100°, 135°, 180° from the view over a half-plane and a \
             translucent sheet (isotropic and rotated anisotropic light) and a soft point light \
             (distance penumbra); a perspective camera at \
             fov 30° and 90° over a half-plane's shadow on a receiver; a soft point light's \
             penumbra on a wall, orthographic and perspective, light resolution 1 and 4"
                .to_string()
        }
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
    penumbra: Penumbra,
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
        variance_y: None,
        rotation_deg: 0.0,
        penumbra,
        kernel: kernel.to_string(),
        compensation: comp,
        seed: 0,
    }
}

/// The disk set-up of the report.
pub fn disk_setup(
    k: f64,
    slabs: u32,
    tilt: f64,
    variance: f64,
    kernel: &str,
    penumbra: Penumbra,
) -> DiskSetup {
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
        penumbra,
    }
}
