//! The numbers the report produces: one [`Row`] per case and the finished [`Report`], and the
//! mean its tables and its figure aggregate with. Every other file of the report reads these;
//! this one reads none of them.

/// One row of `report.csv`.
#[derive(Clone, Debug, Default)]
pub struct Row {
    /// `edge`, `disk`, `scene`, `narrowband`, `direction` or `perspective`.
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
    /// The angle between the light's travel and the view direction (degrees; `direction`).
    pub view_angle_deg: Option<f64>,
    /// A perspective camera's vertical field of view (degrees; `perspective`).
    pub fov_deg: Option<f64>,
    /// A perspective camera's light grid cells per eye pixel (`sweep.light_resolution`;
    /// `perspective`).
    pub light_resolution: Option<f64>,
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

/// The mean of `v`, NaN when empty.
pub(crate) fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v {
        s += x;
        n += 1;
    }
    if n == 0 { f64::NAN } else { s / n as f64 }
}
