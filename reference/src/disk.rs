//! The disk over a plane (paper fig. 14): an opaque, thin polygonal disk (a 64-sided cylinder)
//! in the first slab and a transparent receiver `m` slabs behind it. Its reference is the disk's
//! indicator convolved with the scaled Gaussian light, computed numerically in f64: the
//! probability that a Gaussian point lies in the convex polygon, integrated slice by slice
//! (Gauss–Legendre across, the normal CDF along each slice).

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene, SceneError};
use convshadow_common::plan::kernel::eigen2;
use convshadow_common::prepare::geometry::SceneGeometry;

use crate::edge::{CaseFrame, phi};
use crate::quadrature::gauss_legendre;

/// One disk set-up (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct DiskSetup {
    /// Convolutions between disk and receiver.
    pub slabs: u32,
    /// Slab thickness e (world units).
    pub slab_distance: f64,
    /// Optimal shadow distance d1.
    pub optimal_distance: f64,
    /// Pixel size (world units).
    pub pixel_size: f64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Disk radius (world units).
    pub radius: f64,
    /// Light tilt ωx (degrees).
    pub tilt_deg: f64,
    /// Light variances (σx², σy²).
    pub variance: [f64; 2],
    /// Rotation of the light's axes (degrees).
    pub rotation_deg: f64,
    /// Kernel name.
    pub kernel: String,
    /// `sweep.variance_compensation`.
    pub compensation: bool,
    /// How the kernels grow with depth.
    pub penumbra: Penumbra,
}

/// Sides of the disk polygon.
pub const DISK_SEGMENTS: u32 = 64;

impl DiskSetup {
    /// Distance d from disk to receiver.
    pub fn distance(&self) -> f64 {
        f64::from(self.slabs) * self.slab_distance
    }

    /// Shadow shift in pixels along x (the response moves by −d·tan ω / px).
    pub fn shift_px(&self) -> f64 {
        -self.distance() * self.tilt_deg.to_radians().tan() / self.pixel_size
    }

    /// The scene text (TOML). The disk sits right of the centre by half the shadow's shift, so
    /// disk and shadow straddle the image centre.
    pub fn toml(&self) -> String {
        let e = self.slab_distance;
        // Pixel +x is world −x for this camera (right = down × forward).
        let disk_x = 0.5 * self.shift_px() * self.pixel_size;
        CaseFrame {
            width: self.width,
            height: self.height,
            pixel_size: self.pixel_size,
            slab_distance: e,
            optimal_distance: self.optimal_distance,
            kernel: &self.kernel,
            compensation: self.compensation,
            slabs: self.slabs,
        }
        .toml(
            &format!("penumbra = \"{}\"\n", self.penumbra),
            &format!(
                "tilt_deg = [{:e}, 0.0]\nvariance = [{:e}, {:e}]\nrotation_deg = {:e}\n",
                self.tilt_deg, self.variance[0], self.variance[1], self.rotation_deg
            ),
            &format!(
                "shape = \"cylinder\"\nsize = [{:e}, {:e}, {DISK_SEGMENTS}]\n\
                 translate = [{disk_x:e}, 0.0, {:e}]\n",
                self.radius,
                0.2 * e,
                0.4 * e
            ),
        )
    }

    /// The parsed scene.
    pub fn scene(&self) -> Result<Scene, SceneError> {
        Scene::parse(&self.toml(), "<disk case>", Path::new("."))
    }

    /// The light's covariance on the receiver in px² for a distance factor `k` (d² for the
    /// correct shadow, d·d1 for the iterated model).
    pub fn covariance_px(&self, k: f64) -> [[f64; 2]; 2] {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        let (a, b) = (self.variance[0], self.variance[1]);
        let f = k / (self.pixel_size * self.pixel_size);
        [
            [f * (c * c * a + s * s * b), f * c * s * (a - b)],
            [f * c * s * (a - b), f * (s * s * a + c * c * b)],
        ]
    }

    /// The disk polygon in pixel coordinates (convex hull of the projected mesh vertices).
    pub fn polygon(&self, geometry: &SceneGeometry) -> Vec<[f64; 2]> {
        let cam = &geometry.camera;
        let pts: Vec<[f64; 2]> = geometry.meshes[0]
            .mesh
            .positions
            .iter()
            .map(|p| {
                let q = cam.to_pixel(*p);
                [q.x, q.y]
            })
            .collect();
        convex_hull(&pts)
    }

    /// The reference light at every pixel centre (row-major `width·height`): 1 − P(the shadow
    /// ray's Gaussian point lies in the disk), for covariance factor `k` (see
    /// [`DiskSetup::covariance_px`]).
    pub fn reference_light(&self, geometry: &SceneGeometry, k: f64) -> Vec<f64> {
        use rayon::prelude::*;
        let poly = self.polygon(geometry);
        let cov = self.covariance_px(k);
        let shift = self.shift_px();
        let (w, h) = (self.width as usize, self.height as usize);
        let mut out = vec![0.0; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, v) in row.iter_mut().enumerate() {
                // The receiver at pixel p sees the disk through p − shift.
                let m = [x as f64 + 0.5 - shift, y as f64 + 0.5];
                *v = 1.0 - gaussian_in_polygon(&poly, m, cov);
            }
        });
        out
    }
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, no repeated points.
pub fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// P(X ∈ polygon) for X ~ N(mean, cov) (px, px²) and a convex counter-clockwise polygon.
///
/// In the covariance's principal frame (u along the larger axis), P = ∫ φ(u) [Φ(v_hi(u)) −
/// Φ(v_lo(u))] du over the polygon's u-range, split at every vertex (the integrand is smooth
/// between them) and into pieces no wider than a quarter of the u standard deviation, each by
/// 16-point Gauss–Legendre. Zero variances reduce to indicator functions exactly.
pub fn gaussian_in_polygon(poly: &[[f64; 2]], mean: [f64; 2], cov: [[f64; 2]; 2]) -> f64 {
    let (l1, l2, e1) = eigen2(cov);
    let e2 = [-e1[1], e1[0]];
    // Polygon in the principal frame, relative to the mean.
    let q: Vec<[f64; 2]> = poly
        .iter()
        .map(|p| {
            let d = [p[0] - mean[0], p[1] - mean[1]];
            [d[0] * e1[0] + d[1] * e1[1], d[0] * e2[0] + d[1] * e2[1]]
        })
        .collect();
    let (s1, s2) = (l1.sqrt(), l2.sqrt());
    let umin = q.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let umax = q.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let edges: Vec<([f64; 2], [f64; 2])> = q
        .iter()
        .copied()
        .zip(q.iter().copied().cycle().skip(1))
        .collect();
    // The v-extent of the polygon at u over `edges` (convex: the min and max over edge
    // intersections).
    let slice = |edges: &[([f64; 2], [f64; 2])], u: f64| -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(a, b) in edges {
            let (ua, ub) = (a[0].min(b[0]), a[0].max(b[0]));
            if u < ua || u > ub {
                continue;
            }
            let v = if ub > ua {
                a[1] + (u - a[0]) / (b[0] - a[0]) * (b[1] - a[1])
            } else {
                lo = lo.min(a[1].min(b[1]));
                hi = hi.max(a[1].max(b[1]));
                continue;
            };
            lo = lo.min(v);
            hi = hi.max(v);
        }
        (lo, hi)
    };
    let inner = |edges: &[([f64; 2], [f64; 2])], u: f64| -> f64 {
        let (lo, hi) = slice(edges, u);
        if lo > hi {
            return 0.0;
        }
        if s2 > 0.0 {
            phi(hi / s2) - phi(lo / s2)
        } else if lo <= 0.0 && 0.0 <= hi {
            1.0
        } else {
            0.0
        }
    };
    if s1 == 0.0 {
        return if (umin..=umax).contains(&0.0) {
            inner(&edges, 0.0)
        } else {
            0.0
        };
    }
    // Only |u| < 9σ matters (the Gaussian's mass beyond is below 1e-18).
    let (a, b) = (umin.max(-9.0 * s1), umax.min(9.0 * s1));
    if a >= b {
        return 0.0;
    }
    let mut cuts: Vec<f64> = q
        .iter()
        .map(|p| p[0])
        .filter(|u| *u > a && *u < b)
        .collect();
    cuts.push(a);
    cuts.push(b);
    if s2 == 0.0 {
        // The slice indicator switches where an edge crosses v = 0.
        for (&p0, &p1) in q.iter().zip(q.iter().cycle().skip(1)) {
            if (p0[1] < 0.0) != (p1[1] < 0.0) {
                let u = p0[0] + (0.0 - p0[1]) / (p1[1] - p0[1]) * (p1[0] - p0[0]);
                if u > a && u < b {
                    cuts.push(u);
                }
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    let norm = 1.0 / (s1 * (2.0 * std::f64::consts::PI).sqrt());
    let gl = gauss_legendre(16);
    let mut total = 0.0;
    let mut crossing = Vec::with_capacity(edges.len());
    for w in cuts.windows(2) {
        let (c0, c1) = (w[0], w[1]);
        if c1 <= c0 {
            continue;
        }
        // No vertex lies between two cuts, so the edges that cross u are the same for every
        // u inside: found once, at the middle.
        let middle = 0.5 * (c0 + c1);
        crossing.clear();
        crossing.extend(
            edges
                .iter()
                .filter(|(a, b)| a[0].min(b[0]) <= middle && middle <= a[0].max(b[0])),
        );
        let pieces = ((c1 - c0) / (0.25 * s1)).ceil().max(1.0) as usize;
        let hw = 0.5 * (c1 - c0) / pieces as f64;
        for k in 0..pieces {
            let mid = c0 + (2 * k + 1) as f64 * hw;
            for (x, wt) in gl {
                let u = mid + hw * x;
                let g = norm * (-0.5 * (u / s1) * (u / s1)).exp();
                total += wt * hw * g * inner(&crossing, u);
            }
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(h: f64) -> Vec<[f64; 2]> {
        vec![[-h, -h], [h, -h], [h, h], [-h, h]]
    }

    #[test]
    fn gaussian_in_a_square_is_the_product_of_cdfs() {
        // Axis-aligned covariance: P = (Φ(h/σx) − Φ(−h/σx))·(Φ(h/σy) − Φ(−h/σy)).
        let (h, sx, sy) = (1.3, 0.7, 2.1);
        let want = (phi(h / sx) - phi(-h / sx)) * (phi(h / sy) - phi(-h / sy));
        let got = gaussian_in_polygon(&square(h), [0.0, 0.0], [[sx * sx, 0.0], [0.0, sy * sy]]);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // Shifted, with one zero variance: Φ-differences along x times the indicator along y.
        let got = gaussian_in_polygon(&square(h), [0.4, 0.5], [[sx * sx, 0.0], [0.0, 0.0]]);
        let want = phi((h - 0.4) / sx) - phi((-h - 0.4) / sx);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }

    #[test]
    fn rotated_isotropic_gaussian_in_a_regular_polygon_matches_the_disk_limit() {
        // P(|X| < r) for an isotropic Gaussian is 1 − exp(−r²/2σ²); a 4096-gon is a disk to 1e-6.
        let n = 4096;
        let r = 2.0;
        let poly: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = 2.0 * std::f64::consts::PI * i as f64 / n as f64;
                [r * t.cos(), r * t.sin()]
            })
            .collect();
        let s = 1.5f64;
        let got = gaussian_in_polygon(&poly, [0.0, 0.0], [[s * s, 0.0], [0.0, s * s]]);
        let want = 1.0 - (-(r * r) / (2.0 * s * s)).exp();
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }

    #[test]
    fn hull_of_a_square_with_inner_points() {
        let h = convex_hull(&[[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [1.0, 1.0], [0.0, 1.0]]);
        assert_eq!(h.len(), 4);
    }
}
