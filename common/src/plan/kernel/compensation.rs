//! Compensation: shaping a pattern so that, read bilinearly, its response has the target Σκ.

use wide::f64x4;

use super::*;

/// Whether the light is narrow enough that its mean is carried in whole pixels: when Σκ is
/// below what a bilinear read of the mean's fraction would add on some axis.
pub(crate) fn carry_mean(m: &KernelMoments) -> bool {
    let bilinear = |v: f64| {
        let f = v - v.floor();
        f * (1.0 - f)
    };
    m.cov[0][0] < bilinear(m.mean[0]) || m.cov[1][1] < bilinear(m.mean[1])
}

/// Outer iterations of [`compensated_pattern`] (each builds one pattern).
pub(crate) const MAX_SHAPE_ITERATIONS: usize = 12;

/// A pattern whose taps, read bilinearly around `mean`, give the response covariance `target`:
/// pattern covariance plus the variance f(1−f) per axis that the reads add.
///
/// A bilinear read spreads a tap along the two pixel axes independently, so the response's x
/// variance depends only on the taps' x offsets. The pattern built for a shape covariance C (with
/// C's diagonal = Σκ's) is therefore scaled along x by s_x and along y by s_y, each found by
/// bisection on [0, 1]. Along one axis the response variance is T(s) = Σ w·L(r) − m² with
/// r = m + s·o the read positions and L the piecewise-linear interpolant of r² at the integers
/// (a read at r puts weights 1 − f and f on ⌊r⌋ and ⌊r⌋ + 1: second moment r² + f(1 − f)). L is
/// convex, so T is convex in s, and its slope at s = 0 is ≥ 0 because the union of a pattern's
/// phases is zero-mean: T is non-decreasing on [0, 1], from T(0) = f(1 − f) of the mean's
/// fraction (≤ Σκ, else `build_table` carries the mean and m = 0, T(0) = 0) to
/// T(1) = C + bilinear ≥ Σκ. Bisection converges for every Σκ (the damped fixed point this
/// replaces diverged below Σκ ≈ 0.05 px² per slab).
///
/// Scaling multiplies the correlation by s_x·s_y, so C's off-diagonal is set to Σκ_xy/(s_x·s_y)
/// and the pattern rebuilt; the scales depend only weakly on C's correlation and this settles in a
/// few rounds. Bilinear reads add no correlation: where the compensated pattern is too narrow to
/// carry Σκ_xy (C would stop being positive semi-definite; only when Σκ's smaller eigenvalue is
/// below 1/4 px²), C is capped at correlation ±1 and the response keeps less than Σκ_xy.
pub(crate) fn compensated_pattern(
    make: &dyn Fn([[f64; 2]; 2]) -> Pattern,
    mean: [f64; 2],
    target: [[f64; 2]; 2],
) -> Pattern {
    let scales = |pattern: &Pattern| {
        [
            axis_scale(pattern, mean[0], 0, target[0][0]),
            axis_scale(pattern, mean[1], 1, target[1][1]),
        ]
    };
    let mut shape = target;
    let mut pattern = make(shape);
    let mut scale = scales(&pattern);
    for _ in 1..MAX_SHAPE_ITERATIONS {
        let both = scale[0] * scale[1];
        if target[0][1] == 0.0 || both <= 0.0 {
            break;
        }
        let limit = (shape[0][0] * shape[1][1]).sqrt();
        let want = target[0][1] / both;
        // Total for any input: a non-finite shape or ratio keeps the last pattern (no clamp panic).
        if !(limit.is_finite() && want.is_finite()) {
            break;
        }
        let want = want.clamp(-limit, limit);
        if (want - shape[0][1]).abs() <= 1e-12 * limit {
            break;
        }
        shape[0][1] = want;
        shape[1][0] = want;
        pattern = make(shape);
        scale = scales(&pattern);
    }
    pattern
        .into_iter()
        .map(|phase| {
            phase
                .into_iter()
                .map(|(o, w)| ([o[0] * scale[0], o[1] * scale[1]], w))
                .collect()
        })
        .collect()
}

/// The scale s ∈ [0, 1] of the pattern's offsets along `axis` at which the response variance
/// along that axis equals `target` (see [`compensated_pattern`]: non-decreasing in s), by
/// bisection; 0 or 1 where `target` is out of reach.
pub(crate) fn axis_scale(pattern: &Pattern, mean: f64, axis: usize, target: f64) -> f64 {
    let taps = AxisTaps::of(pattern, axis);
    let variance = |s: f64| taps.response_variance(mean, s);
    if variance(1.0) <= target {
        return 1.0;
    }
    if variance(0.0) >= target {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    // 60 halvings: an interval of 2^-60, below f64's resolution of s near 1.
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if variance(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A pattern's taps along one axis for the bisection of [`axis_scale`], which reads them some 60
/// times: offsets and weights in the pattern's order (phase by phase), four to a lane vector.
struct AxisTaps {
    offsets: Vec<f64x4>,
    weights: Vec<f64x4>,
    /// Taps (the last vector's lanes past it are padding).
    count: usize,
    /// The weights' sum, one tap at a time in order (the same for every scale).
    total: f64,
}

impl AxisTaps {
    /// The taps of `pattern` along `axis`.
    fn of(pattern: &Pattern, axis: usize) -> AxisTaps {
        let (offsets, weights): (Vec<f64>, Vec<f64>) =
            pattern.iter().flatten().map(|(o, w)| (o[axis], *w)).unzip();
        AxisTaps {
            offsets: lanes_of_four(&offsets),
            weights: lanes_of_four(&weights),
            count: weights.len(),
            total: weights.iter().fold(0.0, |total, w| total + w),
        }
    }

    /// The variance along the axis of the response of these taps (offsets scaled by `s`) read
    /// bilinearly around `mean` (see `response_variance`): four taps' terms at once, each in its
    /// expression's order, added one tap at a time in the pattern's order (the same bits;
    /// `response_variance_by_lanes_is_the_bits_of_one_tap_at_a_time`).
    fn response_variance(&self, mean: f64, s: f64) -> f64 {
        let (mean, s4, one) = (f64x4::splat(mean), f64x4::splat(s), f64x4::splat(1.0));
        let (mut first, mut second) = (0.0, 0.0);
        for (i, (&o, &w)) in self.offsets.iter().zip(&self.weights).enumerate() {
            let r = -(mean + s4 * o);
            let f = r - r.floor();
            let (by_r, by_second) = ((w * r).to_array(), (w * (r * r + f * (one - f))).to_array());
            for k in 0..(self.count - 4 * i).min(4) {
                first += by_r[k];
                second += by_second[k];
            }
        }
        let m = first / self.total;
        second / self.total - m * m
    }
}

/// Variance along `axis` of the response of a pattern (offsets scaled by `s`) read bilinearly
/// around `mean`: a read at r = −(mean + s·o) has second moment r² + f(1 − f), f = r − ⌊r⌋. One
/// tap at a time: the plain loop [`AxisTaps::response_variance`] must reproduce.
#[cfg(test)]
pub(crate) fn response_variance(pattern: &Pattern, mean: f64, axis: usize, s: f64) -> f64 {
    let (mut total, mut first, mut second) = (0.0, 0.0, 0.0);
    for phase in pattern {
        for (o, w) in phase {
            let r = -(mean + s * o[axis]);
            let f = r - r.floor();
            total += w;
            first += w * r;
            second += w * (r * r + f * (1.0 - f));
        }
    }
    let m = first / total;
    second / total - m * m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn response_variance_by_lanes_is_the_bits_of_one_tap_at_a_time() {
        // Patterns of 1 to 9 taps (every padding of the last lane vector), offsets on both sides
        // of whole pixels, means and scales that put reads on integers and between them.
        let mut h = 0x9e37_79b9u32;
        let mut next = || {
            h = crate::pixel::hash::mix32(h.wrapping_add(0x6d2b_79f5));
            f64::from(h) / f64::from(u32::MAX)
        };
        for count in 1..=9 {
            let pattern: Pattern = (0..3)
                .map(|_| {
                    (0..count)
                        .map(|_| ([next() * 6.0 - 3.0, next() * 4.0 - 2.0], next()))
                        .collect()
                })
                .collect();
            for axis in 0..2 {
                let taps = AxisTaps::of(&pattern, axis);
                for (mean, s) in [(0.0, 0.0), (0.3, 1.0), (-1.25, 0.5), (next(), next())] {
                    let lanes = taps.response_variance(mean, s);
                    let plain = response_variance(&pattern, mean, axis, s);
                    assert_eq!(
                        lanes.to_bits(),
                        plain.to_bits(),
                        "{count} taps, axis {axis}"
                    );
                }
            }
        }
    }
}
