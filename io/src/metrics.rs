//! Image-difference metrics for `convshadow diff` and the CPU ↔ GPU tests:
//! maximum absolute error, RMSE, PSNR, 8-bit sRGB differences, a ULP histogram and a heat-map.
//! FLIP is computed by the caller with the nv-flip crate (an existing implementation).

use convshadow_common::model::display::linear_to_srgb8;

use crate::image::RgbImage;

/// Buckets of the ULP histogram: 0, 1, 2–3, 4–7, …, 2^(k−1)…2^k − 1, and the last one for
/// everything from 2^(ULP_BUCKETS−2) up (including NaN mismatches and sign differences).
pub const ULP_BUCKETS: usize = 24;

/// Why two images cannot be compared.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MetricsError {
    /// The images differ in size.
    #[error("the images differ in size: {0}x{1} vs {2}x{3}")]
    SizeMismatch(u32, u32, u32, u32),
    /// A buffer does not hold width·height·3 values.
    #[error("an image buffer holds {0} values, expected {1}")]
    BadBuffer(usize, usize),
}

/// The numbers of one comparison (A is the reference).
#[derive(Clone, Debug, PartialEq)]
pub struct DiffMetrics {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Largest |A − B| over all channels (linear values).
    pub max_abs: f64,
    /// Where the largest error is: (x, y, channel).
    pub max_abs_at: (u32, u32, u32),
    /// Root mean square error over all channels.
    pub rmse: f64,
    /// Peak signal-to-noise ratio in dB with peak 1.0 (infinite for identical images).
    pub psnr: f64,
    /// Pixels whose 8-bit sRGB encoding differs in any channel.
    pub srgb8_pixels_differ: u64,
    /// The largest 8-bit sRGB difference (levels).
    pub srgb8_max_diff: u8,
    /// Values (pixel channels) whose bits differ.
    pub values_differ: u64,
    /// ULP distances of all values, bucketed (see [`ULP_BUCKETS`]).
    pub ulp_histogram: [u64; ULP_BUCKETS],
}

impl DiffMetrics {
    /// Fraction of pixels whose 8-bit sRGB encoding differs.
    pub fn srgb8_fraction(&self) -> f64 {
        let n = u64::from(self.width) * u64::from(self.height);
        if n == 0 {
            0.0
        } else {
            self.srgb8_pixels_differ as f64 / n as f64
        }
    }

    /// Whether every value has the same bits.
    pub fn bit_identical(&self) -> bool {
        self.values_differ == 0
    }
}

/// Distance in units in the last place between two floats (same order as the float line;
/// +0 and −0 are 0 apart; any NaN mismatch is `u32::MAX`).
pub fn ulp_distance(a: f32, b: f32) -> u32 {
    if a.to_bits() == b.to_bits() {
        return 0;
    }
    if a.is_nan() || b.is_nan() {
        return u32::MAX;
    }
    let key = |f: f32| {
        let i = f.to_bits() as i32;
        // Map to a monotonic signed integer line (−0 and +0 both to 0).
        if i < 0 {
            -(i & 0x7fff_ffff) as i64
        } else {
            i as i64
        }
    };
    (key(a) - key(b)).unsigned_abs().min(u64::from(u32::MAX)) as u32
}

/// The histogram bucket of a ULP distance.
pub fn ulp_bucket(d: u32) -> usize {
    if d == 0 {
        0
    } else {
        ((32 - d.leading_zeros()) as usize).min(ULP_BUCKETS - 1)
    }
}

/// The absolute difference of two values, in f64: 0 for equal values, equal infinities included
/// (`inf − inf` is NaN, which would make bit-identical images fail `--max-rmse 0`); infinite
/// when they differ and either is NaN or infinite.
pub fn value_error(a: f32, b: f32) -> f64 {
    if a == b {
        return 0.0;
    }
    let d = (f64::from(a) - f64::from(b)).abs();
    if d.is_nan() { f64::INFINITY } else { d }
}

/// Compares two linear float RGB images (A is the reference).
pub fn compare(a: &RgbImage, b: &RgbImage) -> Result<DiffMetrics, MetricsError> {
    if a.width != b.width || a.height != b.height {
        return Err(MetricsError::SizeMismatch(
            a.width, a.height, b.width, b.height,
        ));
    }
    let n = a.width as usize * a.height as usize * 3;
    for img in [a, b] {
        if img.data.len() != n {
            return Err(MetricsError::BadBuffer(img.data.len(), n));
        }
    }
    let mut max_abs = 0.0f64;
    let mut max_at = 0usize;
    let mut sq = 0.0f64;
    let mut values_differ = 0u64;
    let mut ulp_histogram = [0u64; ULP_BUCKETS];
    for (i, (&x, &y)) in a.data.iter().zip(&b.data).enumerate() {
        let d = value_error(x, y);
        if d > max_abs {
            max_abs = d;
            max_at = i;
        }
        sq += d * d;
        let u = ulp_distance(x, y);
        if x.to_bits() != y.to_bits() {
            values_differ += 1;
        }
        ulp_histogram[ulp_bucket(u)] += 1;
    }
    let mse = if n == 0 { 0.0 } else { sq / n as f64 };
    let psnr = if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    };
    let mut srgb8_pixels_differ = 0u64;
    let mut srgb8_max_diff = 0u8;
    for (pa, pb) in a.data.chunks_exact(3).zip(b.data.chunks_exact(3)) {
        let mut differs = false;
        for c in 0..3 {
            let d = linear_to_srgb8(pa[c]).abs_diff(linear_to_srgb8(pb[c]));
            differs |= d > 0;
            srgb8_max_diff = srgb8_max_diff.max(d);
        }
        srgb8_pixels_differ += u64::from(differs);
    }
    let w = a.width as usize;
    let pixel = max_at / 3;
    Ok(DiffMetrics {
        width: a.width,
        height: a.height,
        max_abs,
        max_abs_at: (
            (pixel % w.max(1)) as u32,
            (pixel / w.max(1)) as u32,
            (max_at % 3) as u32,
        ),
        rmse: mse.sqrt(),
        psnr,
        srgb8_pixels_differ,
        srgb8_max_diff,
        values_differ,
        ulp_histogram,
    })
}

/// Root mean square of the differences of `(got, want)` pairs, summed in order in f64 (0 for
/// none): the one RMSE of the report and the tests.
pub fn rmse(pairs: impl IntoIterator<Item = (f64, f64)>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for (a, b) in pairs {
        s += (a - b) * (a - b);
        n += 1;
    }
    (s / n.max(1) as f64).sqrt()
}

/// A heat-map of the per-pixel largest channel error, as 8-bit RGB: black where the pixel is
/// bit-identical, then dark red → red → yellow → white with the error on a log scale from
/// 1e-7 (and any non-zero difference) to `max_abs` (at least 1e-6).
pub fn heatmap(a: &RgbImage, b: &RgbImage, max_abs: f64) -> Vec<u8> {
    let top = max_abs.max(1e-6).log10();
    let bottom = 1e-7f64.log10();
    let mut out = Vec::with_capacity(a.data.len());
    for (pa, pb) in a.data.chunks_exact(3).zip(b.data.chunks_exact(3)) {
        let mut e = 0.0f64;
        let mut differs = false;
        for c in 0..3 {
            differs |= pa[c].to_bits() != pb[c].to_bits();
            e = e.max(value_error(pa[c], pb[c]));
        }
        if !differs {
            out.extend([0, 0, 0]);
            continue;
        }
        // t in (0, 1]: a differing pixel is never black.
        let t = if top > bottom {
            ((e.max(1e-30).log10() - bottom) / (top - bottom)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let t = 0.15 + 0.85 * t;
        let ramp = |lo: f64, hi: f64| (((t - lo) / (hi - lo)).clamp(0.0, 1.0) * 255.0) as u8;
        out.extend([ramp(0.0, 0.5), ramp(0.5, 0.85), ramp(0.85, 1.0)]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32, u32) -> f32) -> RgbImage {
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                for c in 0..3 {
                    data.push(f(x, y, c));
                }
            }
        }
        RgbImage {
            width: w,
            height: h,
            data,
        }
    }

    #[test]
    fn identical_images_have_zero_error_and_a_black_heatmap() {
        let a = image(16, 8, |x, y, c| (x + 2 * y + c) as f32 / 64.0);
        let m = compare(&a, &a.clone()).unwrap();
        assert_eq!(m.max_abs, 0.0);
        assert_eq!(m.rmse, 0.0);
        assert!(m.psnr.is_infinite());
        assert_eq!(m.srgb8_pixels_differ, 0);
        assert_eq!(m.srgb8_max_diff, 0);
        assert!(m.bit_identical());
        assert_eq!(m.ulp_histogram[0], 16 * 8 * 3);
        assert!(heatmap(&a, &a, m.max_abs).iter().all(|&v| v == 0));
    }

    #[test]
    fn an_injected_difference_is_seen_by_every_metric() {
        let a = image(16, 8, |x, y, c| (x + 2 * y + c) as f32 / 64.0);
        let mut b = a.clone();
        // Pixel (5, 3), green: +0.25. Pixel (0, 0), red: one ULP.
        let i = (3 * 16 + 5) * 3 + 1;
        b.data[i] += 0.25;
        b.data[0] = f32::from_bits(b.data[0].to_bits() + 1);
        let m = compare(&a, &b).unwrap();
        assert_eq!(m.max_abs, 0.25);
        assert_eq!(m.max_abs_at, (5, 3, 1));
        let expect_rmse = (0.0625f64 / (16.0 * 8.0 * 3.0)).sqrt();
        assert!((m.rmse - expect_rmse).abs() < 1e-9, "{}", m.rmse);
        assert!((m.psnr - (-20.0 * expect_rmse.log10())).abs() < 1e-6);
        assert_eq!(m.values_differ, 2);
        assert_eq!(m.ulp_histogram[1], 1, "one value one ULP apart");
        assert_eq!(
            m.srgb8_pixels_differ, 1,
            "the ULP change does not show in 8 bits"
        );
        assert!(m.srgb8_max_diff >= 30, "{}", m.srgb8_max_diff);
        let h = heatmap(&a, &b, m.max_abs);
        let at = |x: usize, y: usize| &h[(y * 16 + x) * 3..][..3];
        assert_eq!(at(5, 3), &[255, 255, 255], "the largest error is white");
        assert!(
            at(0, 0).iter().any(|&v| v > 0),
            "a one-ULP pixel is not black"
        );
        assert_eq!(at(1, 0), &[0, 0, 0]);
    }

    #[test]
    fn ulp_distance_counts_representable_steps() {
        assert_eq!(ulp_distance(1.0, 1.0), 0);
        assert_eq!(ulp_distance(1.0, 1.0f32.next_up()), 1);
        assert_eq!(ulp_distance(0.0, -0.0), 0);
        assert_eq!(ulp_distance(f32::from_bits(1), -f32::from_bits(1)), 2);
        assert_eq!(ulp_distance(f32::NAN, 1.0), u32::MAX);
        assert_eq!(ulp_bucket(0), 0);
        assert_eq!(ulp_bucket(1), 1);
        assert_eq!(ulp_bucket(3), 2);
        assert_eq!(ulp_bucket(u32::MAX), ULP_BUCKETS - 1);
        assert!(compare(&image(2, 2, |_, _, _| 0.0), &image(2, 3, |_, _, _| 0.0)).is_err());
    }
}
