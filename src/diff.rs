//! The numbers of `convshadow diff` beyond `convshadow_io::metrics`: mean FLIP, the NaNs of an
//! image and the JSON form of a comparison. The binary's `diff` and the Python module's
//! `convshadow.diff` both report these.

use convshadow_io::image::RgbImage;
use convshadow_io::metrics::{DiffMetrics, MetricsError, ULP_BUCKETS, compare};
use serde_json::json;

/// NaN values of one image: how many, and the first one's (x, y, channel).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NanReport {
    /// NaN values (pixel channels).
    pub count: u64,
    /// The first NaN in row-major order.
    pub first: Option<(u32, u32, u32)>,
}

impl NanReport {
    /// The NaNs of `img`.
    pub fn of(img: &RgbImage) -> NanReport {
        let mut r = NanReport::default();
        for (i, v) in img.data.iter().enumerate() {
            if v.is_nan() {
                if r.first.is_none() {
                    let p = (i / 3) as u32;
                    r.first = Some((p % img.width.max(1), p / img.width.max(1), (i % 3) as u32));
                }
                r.count += 1;
            }
        }
        r
    }

    /// "`name` has N NaN values (first at …)", or `None` without NaNs.
    pub fn describe(&self, name: &str) -> Option<String> {
        self.first.map(|(x, y, c)| {
            format!(
                "{name} has {} NaN value{} (first at ({x}, {y}, channel {c}))",
                self.count,
                if self.count == 1 { "" } else { "s" }
            )
        })
    }
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

/// One comparison of B against the reference A: the metrics, mean FLIP and each image's NaNs.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Errors, PSNR, 8-bit sRGB differences and the ULP histogram.
    pub metrics: DiffMetrics,
    /// Mean FLIP ([`mean_flip`]).
    pub flip: f64,
    /// The NaNs of A and of B.
    pub nans: [NanReport; 2],
}

impl Comparison {
    /// Compares B with the reference A (images of different sizes cannot be compared).
    pub fn of(a: &RgbImage, b: &RgbImage) -> Result<Comparison, MetricsError> {
        let metrics = compare(a, b)?;
        Ok(Comparison {
            metrics,
            flip: mean_flip(a, b),
            nans: [NanReport::of(a), NanReport::of(b)],
        })
    }

    /// Whether either image has a NaN value.
    pub fn any_nan(&self) -> bool {
        self.nans.iter().any(|n| n.count > 0)
    }

    /// The JSON form `convshadow diff --json` writes (less its `thresholds_failed`): the
    /// [`metrics_json`], PSNR `"nan"` when an image has NaN values, and `nan_a` / `nan_b`.
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = metrics_json(&self.metrics, self.flip);
        if let Some(o) = v.as_object_mut() {
            if self.any_nan() {
                // PSNR is only infinite for identical finite images.
                o.insert("psnr_db".into(), serde_json::Value::String("nan".into()));
            }
            for (n, key) in self.nans.iter().zip(["nan_a", "nan_b"]) {
                o.insert(
                    key.into(),
                    json!({"count": n.count, "first": n.first.map(|(x, y, c)| [x, y, c])}),
                );
            }
        }
        v
    }
}
