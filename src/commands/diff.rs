//! `convshadow diff A B`: compare two images (EXR or PNG; A is the reference) with max absolute
//! error, RMSE, PSNR, mean FLIP (nv-flip), 8-bit sRGB differences and a ULP histogram, and
//! optionally write the numbers as JSON and a heat-map PNG.

use std::path::PathBuf;

use convshadow_common::image_io::RgbImage;
use convshadow_common::metrics::{DiffMetrics, ULP_BUCKETS, compare, heatmap};
use serde_json::json;

use crate::exit::{self, Failure};

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
}

/// Mean FLIP (LDR, from the 8-bit sRGB encodings) of B against reference A, via nv-flip.
pub fn mean_flip(a: &RgbImage, b: &RgbImage) -> f64 {
    if a.width == 0 || a.height == 0 {
        return 0.0;
    }
    let reference = nv_flip::FlipImageRgb8::with_data(a.width, a.height, &a.to_srgb8());
    let test = nv_flip::FlipImageRgb8::with_data(b.width, b.height, &b.to_srgb8());
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    f64::from(nv_flip::FlipPool::from_image(&error).mean())
}

/// The JSON form of a comparison (PSNR of identical images is `null`, i.e. infinite).
pub fn metrics_json(m: &DiffMetrics, flip: f64) -> serde_json::Value {
    let edges: Vec<String> = (0..ULP_BUCKETS)
        .map(|k| match k {
            0 => "0".to_string(),
            k if k == ULP_BUCKETS - 1 => format!(">={}", 1u64 << (k - 1)),
            k => format!("{}-{}", 1u64 << (k - 1), (1u64 << k) - 1),
        })
        .collect();
    json!({
        "width": m.width,
        "height": m.height,
        "max_abs_error": m.max_abs,
        "max_abs_error_at": [m.max_abs_at.0, m.max_abs_at.1, m.max_abs_at.2],
        "rmse": m.rmse,
        "psnr_db": if m.psnr.is_finite() { json!(m.psnr) } else { serde_json::Value::Null },
        "mean_flip": flip,
        "srgb8_pixels_differ": m.srgb8_pixels_differ,
        "srgb8_pixels_differ_fraction": m.srgb8_fraction(),
        "srgb8_max_diff": m.srgb8_max_diff,
        "values_differ": m.values_differ,
        "bit_identical": m.bit_identical(),
        "ulp_histogram": edges.iter().zip(m.ulp_histogram).map(|(e, c)| json!([e, c])).collect::<Vec<_>>(),
    })
}

/// Runs `convshadow diff`.
pub fn run(args: &DiffArgs) -> Result<i32, Failure> {
    for p in args.json.iter().chain(&args.heatmap) {
        convshadow_common::image_io::check_writable(p)?;
    }
    let load =
        |p: &PathBuf| RgbImage::load(p).map_err(|e| Failure::new(exit::BAD_INPUT, e.to_string()));
    let a = load(&args.a)?;
    let b = load(&args.b)?;
    let m = compare(&a, &b).map_err(|e| {
        Failure::new(
            exit::BAD_INPUT,
            format!("{} vs {}: {e}", args.a.display(), args.b.display()),
        )
    })?;
    let flip = mean_flip(&a, &b);
    let psnr = if m.psnr.is_finite() {
        format!("{:.2} dB", m.psnr)
    } else {
        "inf".to_string()
    };
    println!(
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
    if let Some(p) = &args.heatmap {
        let data = heatmap(&a, &b, m.max_abs);
        image::save_buffer_with_format(
            p,
            &data,
            a.width,
            a.height,
            image::ExtendedColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| {
            Failure::new(
                exit::OUTPUT_FAILED,
                format!("{}: cannot write: {e}", p.display()),
            )
        })?;
    }
    if let Some(p) = &args.json {
        super::write_json(p, &metrics_json(&m, flip))?;
    }
    Ok(exit::OK)
}
