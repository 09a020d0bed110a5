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
//!   with 2048 slabs without pre-integration, whose own error (against 4096 slabs) is reported;
//! - `direction`: a directional light at 0°–180° from the view axis ([`direction`]), an opaque
//!   half-plane's shadow on a translucent sheet; reference: its closed form along each view ray;
//! - `perspective`: a perspective camera at fov 30° and 90° over a half-plane's shadow on a
//!   receiver ([`perspective`]); reference: the closed form where each pixel's ray meets it;
//! - `point`: a soft point light's penumbra on a wall behind a half-plane ([`point`]),
//!   orthographic and perspective, two light-grid resolutions; reference: the visibility
//!   integrated over the light's Gaussian at each pixel's wall point.
//!
//! "Slab count" for the edge and disk is the number of convolutions between occluder and
//! receiver (d = n·e); for the scene it is the scene's slab count.
//!
//! Files: [`row`] (the numbers of a case and of a report, which every other file reads),
//! [`grid`] (the cases), [`runner`] (running them against their references, then the writers),
//! [`direction`], [`perspective`] and [`point`] (those families' cases), [`csv`] and [`markdown`] (the writers), [`plot`] (the figure). Imports go one way: runner →
//! writers → grid and row.

pub mod csv;
pub mod direction;
pub mod grid;
pub mod markdown;
pub mod perspective;
pub mod plot;
pub mod point;
pub mod row;
pub mod runner;

use std::path::{Path, PathBuf};

pub use convshadow_reference::{disk, edge, impulse};
pub use grid::*;
pub use row::*;
pub use runner::*;

/// Where the report writes by default.
pub fn default_out() -> PathBuf {
    Path::new("report").to_path_buf()
}
