//! `gaussian:K`: K×K discrete Gaussian weights in the principal frame.

use super::*;

/// Per-axis variance at or below which `gaussian:K` uses the 3-point pattern (v/2, 1 − v, v/2).
pub(crate) const GAUSSIAN_THREE_POINT: f64 = 0.5;

/// `gaussian:K`: a K×K grid of unit-spaced taps in the principal frame, centred on the mean,
/// weighted by the Gaussian of variances (λ1, λ2), normalised to the exact target variance.
///
/// An axis of variance v ≤ 1/2 uses the 3-point pattern (v/2, 1 − v, v/2) at −1, 0, 1 instead:
/// variance exactly v, and a non-negative spectrum 1 − v + v·cos ω (no checkerboard when
/// iterated). The sampled Gaussian's ±1 weights e^(−1/2v) vanish as v → 0, so rescaling its
/// positions to the exact variance would move its outer taps arbitrarily far (by √(v/got)).
pub(crate) fn gaussian_taps(k: u32, l1: f64, l2: f64, e1: [f64; 2]) -> Vec<([f64; 2], f64)> {
    let to_pixels = principal_to_pixels(e1);
    let h = (k / 2) as i32;
    // 1D weights per axis, then rescaled positions so each axis has exactly its variance.
    let axis = |var: f64| -> Vec<(f64, f64)> {
        if var <= 0.0 {
            return vec![(0.0, 1.0)];
        }
        if var <= GAUSSIAN_THREE_POINT {
            return vec![(-1.0, 0.5 * var), (0.0, 1.0 - var), (1.0, 0.5 * var)];
        }
        let ws: Vec<f64> = (-h..=h)
            .map(|i| (-0.5 * f64::from(i * i) / var).exp())
            .collect();
        let sum: f64 = ws.iter().sum();
        let got: f64 = (-h..=h)
            .zip(&ws)
            .map(|(i, w)| f64::from(i * i) * w / sum)
            .sum();
        // var > 1/2: the ±1 weights are ≥ e^-1 of the centre's, so `got` > 0.
        let stretch = (var / got).sqrt();
        (-h..=h)
            .zip(ws)
            .map(|(i, w)| (f64::from(i) * stretch, w / sum))
            .collect()
    };
    let (ax, ay) = (axis(l1), axis(l2));
    let mut taps = Vec::new();
    for (v, wv) in &ay {
        for (u, wu) in &ax {
            let w = wu * wv;
            if w > 1e-12 {
                taps.push((to_pixels(*u, *v), w));
            }
        }
    }
    taps
}
