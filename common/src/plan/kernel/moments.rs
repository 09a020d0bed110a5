//! A light's per-slab moments (μκ, Σκ) and their principal frame.

/// A light's per-slab kernel moments in pixel units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelMoments {
    /// μκ: where the impulse response moves per slab (pixels).
    pub mean: [f64; 2],
    /// Σκ: how much it spreads per slab (pixels², symmetric 2×2, row-major).
    pub cov: [[f64; 2]; 2],
}

impl KernelMoments {
    /// μκ = −e·μl, Σκ = d1·e·R(α)·diag(σx², σy²)·R(α)ᵀ, divided by px and px².
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
        let (s, c) = rotation_deg.to_radians().sin_cos();
        let k = optimal_distance * slab_distance / (pixel_size * pixel_size);
        let (vx, vy) = (variance[0] * k, variance[1] * k);
        let cov = [
            [c * c * vx + s * s * vy, c * s * (vx - vy)],
            [c * s * (vx - vy), s * s * vx + c * c * vy],
        ];
        KernelMoments { mean, cov }
    }
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
