//! The horizon (`sweep.horizon`): at an opaque surface, the part of an area light below the
//! surface's tangent plane is blocked by the body itself (a ray leaving a closed opaque mesh's
//! surface into it must cross that surface again), and the surface hold passes exactly that part
//! on so that a surface oblique to the slabs does not shadow itself in bands. The shading puts it
//! back in closed form: with `f` the facing normal and `d(s)` the direction towards the light for
//! a light sample `s`, the visible part is `P(f·d > 0) = Φ(μ/σ)`, μ = f·d̄ the mean's dot product
//! and σ² its variance over the light's samples (docs/how-it-works.md, "The horizon").
//!
//! Φ comes from a table computed once here (f64, stored in f32) and read by linear interpolation
//! with the same operations on the CPU (`cpu/src/shading.rs` `horizon`) and the GPU
//! (`shading.wgsl` `horizon`).

use glam::DVec3;

use crate::plan::kernel::rotated_covariance;

/// |μ/σ| at and beyond which the visible part is taken as exactly 1 (μ > 0) or 0: Φ(8) is
/// 1 − 6·10⁻¹⁶, 1 in f32.
pub const HORIZON_REACH: f32 = 8.0;

/// Intervals of the table over [−[`HORIZON_REACH`], [`HORIZON_REACH`]]: the linear
/// interpolation's error is at most h²/8 · max|Φ''| = 1.9·10⁻⁶ (h = 1/128).
pub const HORIZON_STEPS: u32 = 2048;

/// Table knots per unit of μ/σ, `HORIZON_STEPS / (2 · HORIZON_REACH)`: a power of two, so the
/// knots are exact in f32.
pub const HORIZON_PER_UNIT: f32 = 128.0;

/// Φ(t) at t = −[`HORIZON_REACH`] + i / [`HORIZON_PER_UNIT`], i = 0 … [`HORIZON_STEPS`]: the
/// standard normal distribution function, from `libm`'s erfc in f64.
pub fn horizon_table() -> Vec<f32> {
    (0..=HORIZON_STEPS)
        .map(|i| {
            let t = -f64::from(HORIZON_REACH) + f64::from(i) / f64::from(HORIZON_PER_UNIT);
            (0.5 * libm::erfc(-t / std::f64::consts::SQRT_2)) as f32
        })
        .collect()
}

/// A directional light's spread as the shading's horizon reads it: σ² = a·fx² + b·fx·fy +
/// c·fy² + iso for a unit facing normal f, the variance of f·d over the light's slopes s ~ N(s̄,
/// Σ) with d = (s, −1)/‖(s̄, −1)‖ (so that μ = f·`to_light`). Returns [a, b, c, iso] =
/// [Σxx, 2Σxy, Σyy, 0] / ‖(s̄, −1)‖²; Σ = R(α)·diag(σx², σy²)·R(α)ᵀ, the light's slope
/// covariance on the slab plane (`variance`, `rotation_deg`).
pub fn directional_spread(tilt_deg: [f64; 2], variance: [f64; 2], rotation_deg: f64) -> [f32; 4] {
    let mu = tilt_deg.map(|t| t.to_radians().tan());
    let norm2 = DVec3::new(mu[0], mu[1], -1.0).length_squared();
    let [[xx, xy], [_, yy]] = rotated_covariance(variance, rotation_deg);
    [xx / norm2, 2.0 * xy / norm2, yy / norm2, 0.0].map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_knots_span_the_reach() {
        assert_eq!(HORIZON_PER_UNIT * 2.0 * HORIZON_REACH, HORIZON_STEPS as f32);
    }

    #[test]
    fn the_table_is_the_normal_distribution_at_its_knots() {
        let table = horizon_table();
        assert_eq!(table.len(), HORIZON_STEPS as usize + 1);
        // Φ(0) = ½, Φ(±1) = ½(1 ± erf(1/√2)) with erf(1/√2) = 0.682689492137086 (tabulated).
        let at = |t: f32| table[((t + HORIZON_REACH) * HORIZON_PER_UNIT) as usize];
        assert_eq!(at(0.0), 0.5);
        assert!((f64::from(at(1.0)) - 0.841_344_746_068_543).abs() < 1e-7);
        assert!((f64::from(at(-1.0)) - 0.158_655_253_931_457).abs() < 1e-7);
        // The ends round to the values beyond them.
        assert_eq!(table[HORIZON_STEPS as usize], 1.0);
        assert!(table[0] < 1e-8);
        assert!(table.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn a_directional_lights_spread_is_its_covariance_over_its_mean_directions_length() {
        // Untilted, axis-aligned: ‖d̄‖ = 1, the variances themselves.
        assert_eq!(
            directional_spread([0.0, 0.0], [0.04, 0.01], 0.0),
            [0.04, 0.0, 0.01, 0.0]
        );
        // Turned 90°: the axes swap (within rounding of cos 90°).
        let s = directional_spread([0.0, 0.0], [0.04, 0.01], 90.0);
        assert!((s[0] - 0.01).abs() < 1e-9 && (s[2] - 0.04).abs() < 1e-9 && s[1].abs() < 1e-9);
        // Tilted 45° along x: ‖(1, 0, −1)‖² = 2.
        let s = directional_spread([45.0, 0.0], [0.04, 0.04], 0.0);
        assert!((s[0] - 0.02).abs() < 1e-8 && (s[2] - 0.02).abs() < 1e-8);
    }
}
