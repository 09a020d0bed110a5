//! `convshadow diff A B`: compare two images (EXR or PNG; A is the reference) with max absolute
//! error, RMSE, PSNR, mean FLIP (nv-flip), 8-bit sRGB differences and a ULP histogram, and
//! optionally write the numbers as JSON and a heat-map PNG. The numbers beyond
//! `convshadow_io::metrics` (FLIP, NaNs, the JSON form) are the library's `convshadow::diff`,
//! which the Python module's `convshadow.diff` shares.

use std::path::PathBuf;

use convshadow::diff::Comparison;
use convshadow_io::image::RgbImage;
use convshadow_io::metrics::heatmap;
use serde_json::json;

use crate::cli::exit::{self, Failure};

/// Arguments of `convshadow diff`.
#[derive(clap::Args, Debug)]
pub struct DiffArgs {
    /// The reference image (.exr linear float, or .png sRGB 8-bit).
    pub a: PathBuf,
    /// The image compared with it.
    pub b: PathBuf,
    /// Write the numbers as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write a heat-map PNG of the per-pixel error (black = bit-identical).
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Fail (exit code 1) when the RMSE exceeds this.
    #[arg(long, value_name = "X", value_parser = parse_limit)]
    pub max_rmse: Option<f64>,
    /// Fail (exit code 1) when the largest absolute error exceeds this.
    #[arg(long, value_name = "X", value_parser = parse_limit)]
    pub max_abs: Option<f64>,
    /// Fail (exit code 1) when the mean FLIP exceeds this.
    #[arg(long, value_name = "X", value_parser = parse_limit)]
    pub max_flip: Option<f64>,
    /// Fail (exit code 1) when more than N pixels differ in their 8-bit sRGB encoding.
    #[arg(long, value_name = "N")]
    pub max_differing_pixels: Option<u64>,
}

/// Parses a `--max-*` limit: a finite number >= 0. NaN would make the gate pass whatever the
/// images (no comparison with NaN is true), a negative limit would fail identical images, and
/// `inf` is no limit; each is a bad argument (exit code 2) rather than a gate that cannot work.
pub fn parse_limit(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        Ok(x) => Err(format!("expected a finite limit >= 0, got {x}")),
        Err(_) => Err(format!("expected a finite number >= 0, got {s:?}")),
    }
}

/// Exit code of `diff` when a threshold is exceeded (or a NaN meets any threshold).
pub const THRESHOLD_EXCEEDED: i32 = 1;

/// Runs `convshadow diff`.
pub fn run(args: &DiffArgs) -> Result<i32, Failure> {
    super::require_png("--heatmap", args.heatmap.as_ref())?;
    super::refuse_collisions(args.json.iter().chain(&args.heatmap))?;
    super::refuse_outputs_over_inputs(
        args.json.iter().chain(&args.heatmap),
        &[
            ("A".to_string(), args.a.as_path()),
            ("B".to_string(), args.b.as_path()),
        ],
    )?;
    for p in args.json.iter().chain(&args.heatmap) {
        convshadow_io::image::check_writable(p)?;
    }
    let load =
        |p: &PathBuf| RgbImage::load(p).map_err(|e| Failure::new(exit::BAD_INPUT, e.to_string()));
    let a = load(&args.a)?;
    let b = load(&args.b)?;
    let c = Comparison::of(&a, &b).map_err(|e| {
        Failure::new(
            exit::BAD_INPUT,
            format!("{} vs {}: {e}", args.a.display(), args.b.display()),
        )
    })?;
    let (m, flip, nans) = (&c.metrics, c.flip, &c.nans);
    let any_nan = c.any_nan();
    let psnr = if any_nan {
        "n/a (NaN)".to_string()
    } else if m.psnr.is_finite() {
        format!("{:.2} dB", m.psnr)
    } else {
        "inf".to_string()
    };
    convshadow::outln!(
        "diff {}x{}: max abs error {:.3e} at ({}, {}, channel {}), RMSE {:.3e}, PSNR {psnr}, mean \
         FLIP {flip:.5}, {} pixels ({:.4} %) differ in 8-bit sRGB (largest by {} levels), {} values \
         differ in their bits{}",
        m.width,
        m.height,
        m.max_abs,
        m.max_abs_at.0,
        m.max_abs_at.1,
        m.max_abs_at.2,
        m.rmse,
        m.srgb8_pixels_differ,
        100.0 * m.srgb8_fraction(),
        m.srgb8_max_diff,
        m.values_differ,
        if m.bit_identical() {
            " (bit-identical)"
        } else {
            ""
        },
    );
    for (n, name) in nans.iter().zip(["A", "B"]) {
        if let Some(text) = n.describe(name) {
            convshadow::outln!("  NaN: {text}");
        }
    }
    let mut failed = Vec::new();
    let mut check = |what: &str, value: f64, limit: Option<f64>| {
        if let Some(limit) = limit
            && (any_nan || value.is_nan() || value > limit)
        {
            failed.push(format!("{what} {value:.4e} (limit {limit:.4e})"));
        }
    };
    check("RMSE", m.rmse, args.max_rmse);
    check("max abs error", m.max_abs, args.max_abs);
    check("mean FLIP", flip, args.max_flip);
    // A count is compared and printed as an integer (not `1.6050e4`).
    if let Some(limit) = args.max_differing_pixels
        && (any_nan || m.srgb8_pixels_differ > limit)
    {
        failed.push(format!(
            "8-bit differing pixels {} (limit {limit})",
            m.srgb8_pixels_differ
        ));
    }
    if let Some(p) = &args.heatmap {
        let data = heatmap(&a, &b, m.max_abs);
        // Written to a temporary file and renamed: a failed write leaves no partial heat-map.
        convshadow_io::image::save_rgb8_png(p, a.width, a.height, data)?;
    }
    if let Some(p) = &args.json {
        let mut v = c.to_json();
        if let Some(o) = v.as_object_mut() {
            o.insert("thresholds_failed".into(), json!(failed));
        }
        super::write_json(p, &v)?;
    }
    if !failed.is_empty() {
        convshadow::errln!(
            "diff: threshold exceeded: {}{}",
            failed.join(", "),
            if any_nan {
                " (an image has NaN values: every threshold fails)"
            } else {
                ""
            }
        );
        return Ok(THRESHOLD_EXCEEDED);
    }
    Ok(exit::OK)
}
