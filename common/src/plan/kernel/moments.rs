//! A light's per-slab moments (μκ, Σκ) and their principal frame.

/// A light's per-slab kernel moments in pixel units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelMoments {
    /// μκ: where the impulse response moves per slab (pixels).
    pub mean: [f64; 2],
    /// Σκ: how much it spreads per slab (pixels², symmetric 2×2, row-major).
    pub cov: [[f64; 2]; 2],
}

/// Largest per-slab mean shift and standard deviation of a kernel (pixels): 2^26. The grid is at
/// most 16384 + 2·4096 px a side, so a kernel that moves or spreads further in one slab reads
/// (all but a part in 10^4 of) its light from beyond the grid, where the light is unoccluded,
/// whatever its exact size; clamped there (the variances scaled together, keeping the shape),
/// its taps' offsets, slab shifts and reaches stay within `i32` (in-range scenes with slabs a
/// billion units thick and grazing lights asked for 10^11 px).
pub const MAX_KERNEL_PX: f64 = 67_108_864.0;

impl KernelMoments {
    /// μκ = −e·μl, Σκ = d1·e·R(α)·diag(σx², σy²)·R(α)ᵀ, divided by px and px², each clamped to
    /// [`MAX_KERNEL_PX`] (the mean per axis, the covariance by its larger principal variance).
    pub fn for_light(
        tilt_deg: [f64; 2],
        variance: [f64; 2],
        rotation_deg: f64,
        slab_distance: f64,
        optimal_distance: f64,
        pixel_size: f64,
    ) -> KernelMoments {
        let mu_l = [
            tilt_deg[0].to_radians().tan(),
            tilt_deg[1].to_radians().tan(),
        ];
        let mean = [
            -slab_distance * mu_l[0] / pixel_size,
            -slab_distance * mu_l[1] / pixel_size,
        ];
        let mean = mean.map(|m| m.clamp(-MAX_KERNEL_PX, MAX_KERNEL_PX));
        let k = optimal_distance * slab_distance / (pixel_size * pixel_size);
        let (mut vx, mut vy) = (variance[0] * k, variance[1] * k);
        let widest = vx.max(vy);
        if widest > MAX_KERNEL_PX * MAX_KERNEL_PX {
            let shrink = MAX_KERNEL_PX * MAX_KERNEL_PX / widest;
            (vx, vy) = (vx * shrink, vy * shrink);
        }
        let cov = rotated_covariance([vx, vy], rotation_deg);
        KernelMoments { mean, cov }
    }
}

/// R(α)·diag(vx, vy)·R(α)ᵀ: the covariance of principal variances `v` whose axes are turned by
/// `rotation_deg` (α) from x towards y (symmetric 2×2, row-major).
pub fn rotated_covariance(v: [f64; 2], rotation_deg: f64) -> [[f64; 2]; 2] {
    let (s, c) = rotation_deg.to_radians().sin_cos();
    let (vx, vy) = (v[0], v[1]);
    [
        [c * c * vx + s * s * vy, c * s * (vx - vy)],
        [c * s * (vx - vy), s * s * vx + c * c * vy],
    ]
}

/// Eigen-decomposition of a symmetric 2×2 matrix: (λ1 ≥ λ2, unit eigenvector of λ1).
pub fn eigen2(cov: [[f64; 2]; 2]) -> (f64, f64, [f64; 2]) {
    let (a, b, d) = (cov[0][0], cov[0][1], cov[1][1]);
    let half_trace = 0.5 * (a + d);
    let disc = (0.25 * (a - d) * (a - d) + b * b).sqrt();
    let l1 = half_trace + disc;
    let l2 = (half_trace - disc).max(0.0);
    let angle = 0.5 * (2.0 * b).atan2(a - d);
    (l1.max(0.0), l2, [angle.cos(), angle.sin()])
}

/// Maps principal-frame coordinates (along e1, along e2 = e1 rotated 90°) to pixel offsets.
pub(crate) fn principal_to_pixels(e1: [f64; 2]) -> impl Fn(f64, f64) -> [f64; 2] {
    let e2 = [-e1[1], e1[0]];
    move |u, v| [u * e1[0] + v * e2[0], u * e1[1] + v * e2[1]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kernel_beyond_any_grid_is_clamped_keeping_its_shape() {
        // Slabs 6e8 thick, a grazing light, 0.04-unit pixels: 1.2e11 px per slab unclamped.
        let m = KernelMoments::for_light([83.0, -60.0], [6000.0, 60.0], 0.0, 6e8, 6e8, 0.04);
        assert_eq!(m.mean, [-MAX_KERNEL_PX, MAX_KERNEL_PX]);
        let max_var = MAX_KERNEL_PX * MAX_KERNEL_PX;
        assert!((m.cov[0][0] - max_var).abs() <= 1e-9 * max_var, "{m:?}");
        assert!((m.cov[1][1] / m.cov[0][0] - 0.01).abs() < 1e-12, "{m:?}");
        // Within the limits nothing changes.
        let n = KernelMoments::for_light([30.0, 0.0], [0.02, 0.01], 10.0, 0.01, 0.5, 0.01);
        assert!((n.mean[0] + 0.01 * 30f64.to_radians().tan() / 0.01).abs() < 1e-12);
        assert!((n.cov[0][0] + n.cov[1][1] - 0.03 * 0.5 * 0.01 / 1e-4).abs() < 1e-9);
    }
}
