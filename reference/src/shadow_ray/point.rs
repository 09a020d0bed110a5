//! Point and spot lights in the shadow-ray reference (`[[light]] kind = "point" | "spot"`): the
//! light's Gaussian sampled in 3D, shadow rays of finite length to each sample, the inverse-square
//! falloff and the spot's cone taken from the light's centre, and the shading's light vector per
//! shading point.
//!
//! The model (docs/how-it-works.md, "Point and spot lights"): the light arriving at a point X is
//! `color · cone(X − P) / |X − P|² · V(X)`, V the mean transmittance over the light's Gaussian
//! of points `P + δ`, `δ ~ N(0, r²·I)` (world units): the falloff and the cone belong to the
//! light's centre P, the shadow to the whole light (a visibility convolved with the light's
//! shape, as the sweep's kernels convolve it). The media attenuate per unit depth along every
//! shadow ray, as for directional lights (the model's opacities are per slab).

use convshadow_common::plan::point_light::PointSource;
use convshadow_common::prepare::geometry::SceneGeometry;

use super::geometry::{Start, Tri, intersect, sub};
use super::{Reference, Scratch};
use crate::light_samples::{gaussian_pair, inverse_normal_cdf, permute};
use convshadow_common::pixel::hash::mix32;

impl Reference<'_> {
    /// [`Reference::light_at_with`] for a point or spot light: the mean transmittance to `k²`
    /// points of its Gaussian (multi-jittered across the view, each with a depth offset from a
    /// hashed permutation of the `k²` strata of its own axis: a Latin hypercube), times the
    /// falloff and cone of its centre ([`PointSource::falloff`]).
    pub(super) fn point_light_at(
        &self,
        light: &PointSource,
        p: [f64; 3],
        start: Start,
        (k, base): (u32, u32),
        scratch: &mut Scratch,
    ) -> [f64; 3] {
        let m = k * k;
        let inv_m = 1.0 / f64::from(m);
        let depth_perm = mix32(base ^ 0x0de9_7a11);
        let mut acc = [0.0f64; 3];
        for a in 0..k {
            for b in 0..k {
                let ([z1, z2], h) = gaussian_pair(base, k, a, b);
                let j3 = (f64::from(mix32(h ^ 0x5bd1_e995) >> 8) + 0.5) / 16_777_216.0;
                let fz = permute(a * k + b, m, depth_perm);
                let z = [z1, z2, inverse_normal_cdf((f64::from(fz) + j3) * inv_m)];
                let target: [f64; 3] =
                    std::array::from_fn(|i| light.center[i] + light.sigma[i] * z[i]);
                // The ray's parameter runs 0 → 1 from p to the light's point: the start's
                // tolerance (in depth, or across, whichever the ray moves along more) in it.
                let d = sub(target, p);
                let reach = d[2]
                    .abs()
                    .max(d[0].abs().max(d[1].abs()) * light.pixel_size());
                let start = Start {
                    tol: if reach > 0.0 {
                        start.tol / reach
                    } else {
                        start.tol
                    },
                    ..start
                };
                let t = self.transmittance(p, d, 1.0, start, scratch);
                for (a, v) in acc.iter_mut().zip(t) {
                    *a += v;
                }
            }
        }
        let falloff = light.falloff(p);
        std::array::from_fn(|c| acc[c] / f64::from(m) * falloff[c])
    }
}

/// The first closed mesh of `geometry` that holds world point `point`, if any: the crossings of a
/// ray from it (a fixed direction off every axis) counted even-odd per mesh, in f64. A point
/// light inside a closed mesh would be lit from within: its shadow rays' parity, counted from
/// the light's end, would be wrong, so the reference refuses it.
pub fn closed_mesh_holding(geometry: &SceneGeometry, point: [f64; 3]) -> Option<usize> {
    let dir = [
        0.301_511_344_577_763_6,
        0.904_534_033_733_290_9,
        -0.301_511_344_577_763_6,
    ];
    geometry.meshes.iter().enumerate().find_map(|(m, wm)| {
        if geometry.raster.parity_meshes & (1 << m) == 0 {
            return None; // an open mesh has no inside
        }
        let p = &wm.mesh.positions;
        let v = |i: u32| p[i as usize].to_array();
        let crossings = wm
            .mesh
            .triangles
            .iter()
            .filter(|t| {
                let a = v(t[0]);
                let tri = Tri {
                    v0: a,
                    e1: sub(v(t[1]), a),
                    e2: sub(v(t[2]), a),
                    mesh: m as u32,
                };
                intersect(point, dir, &tri).is_some_and(|u| u > 0.0)
            })
            .count();
        (crossings % 2 == 1).then_some(m)
    })
}
