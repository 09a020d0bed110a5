//! The speed-against-error report: renders a grid of cases, measures the
//! sweep's time and its errors against references, and writes `report.csv`, `report.md` and
//! `speed_vs_error.png`.
//!
//! Families of cases, each with its own reference:
//! - `edge`: the opaque edge at d = d1/4, d1, 4·d1 ([`edge`], in `convshadow_reference`); references: the correct shadow
//!   (Gaussian CDF of std d·σ) and the iterated model (std √(d·d1)·σ, paper eq. 8);
//! - `disk`: the disk over a plane ([`disk`], the same); references: the disk's indicator convolved with
//!   the correct and the iterated Gaussian, numerically in f64;
//! - `scene`: the embedded default scene at a small size; reference: the ground-truth shadow-ray
//!   renderer (`convshadow_reference::shadow_ray`), whose own error (M against 4·M samples) is reported;
//! - `narrowband`: `scenes/narrowband.toml` (a 0.05-wide opacity band over fBm) at a small size,
//!   `ellipse2`, with and without pre-integrated compositing; reference: the same scene swept
//!   with 2048 slabs without pre-integration, whose own error (against 4096 slabs) is reported.
//!
//! "Slab count" for the edge and disk is the number of convolutions between occluder and
//! receiver (d = n·e); for the scene it is the scene's slab count.
//!
//! Files: [`grid`] (the cases), [`runner`] (running them against their references), [`csv`] and
//! [`markdown`] (the writers), [`plot`] (the figure).

pub mod csv;
pub mod grid;
pub mod markdown;
pub mod plot;
pub mod runner;

use std::path::{Path, PathBuf};

pub use convshadow_reference::{disk, edge, impulse};
pub use grid::*;
pub use runner::*;

/// One row of `report.csv`.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// `edge`, `disk` or `scene`.
    pub family: String,
    /// Kernel name.
    pub kernel: String,
    /// Penumbra model (`iterated` or `distance`).
    pub penumbra: String,
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
    /// `sweep.preintegration` (pre-integrated compositing).
    pub preintegration: bool,
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

/// The numbers of one finished report.
pub struct Report {
    /// Every case.
    pub rows: Vec<Row>,
    /// Seconds for the whole report.
    pub seconds: f64,
    /// Whether the plot has text.
    pub plot_text: bool,
}

/// Where the report writes by default.
pub fn default_out() -> PathBuf {
    Path::new("report").to_path_buf()
}
