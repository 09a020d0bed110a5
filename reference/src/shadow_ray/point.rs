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

use std::sync::Arc;

use convshadow_common::model::scene::{PatternSpec, PointLight, SpotCone, frame};
use convshadow_common::plan::pattern::Pattern;
use convshadow_common::plan::{fresnel_terms, henyey_greenstein};
use convshadow_common::prepare::camera::Camera;
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_cpu::shading::LightTerms;
use glam::DVec3;

use super::geometry::{Start, Tri, intersect, sub};
use super::{Reference, Scratch};
use crate::light_samples::{gaussian_pair, inverse_normal_cdf, permute};
use convshadow_common::pixel::hash::mix32;

/// A point or spot light where the tracer works (slab-grid coordinates: x, y in grid pixels,
/// z in world depth relative to the first slab plane).
#[derive(Clone, Debug)]
pub(super) struct PointSource {
    /// The light's centre, grid coordinates.
    pub(super) center: [f64; 3],
    /// The light's standard deviation per grid axis: `radius / pixel_size` across, `radius` in
    /// depth.
    pub(super) sigma: [f64; 3],
    /// World units per grid pixel across the view.
    pixel_size: f64,
    /// The spot's cone with its axis in camera space (x right, y down, z along the view).
    spot: Option<SpotCone>,
    /// A spot's pattern and where it lies on the plane at unit distance along the axis.
    pattern: Option<SpotPattern>,
}

/// A spot light's pattern (gobo): the image on the plane at unit distance along the spot's axis,
/// in the spot's own frame, `size` and `center` in units of that plane (tangents of the angle
/// from the axis).
#[derive(Clone, Debug)]
struct SpotPattern {
    /// The spot's own right and down axes, camera space.
    right: DVec3,
    /// See `right`.
    down: DVec3,
    /// The image's extent on the unit plane.
    size: [f64; 2],
    /// The image's centre on the unit plane, along right and down.
    center: [f64; 2],
    /// The image.
    image: Arc<Pattern>,
}

impl PointSource {
    /// `light` (with its pattern's placement `spec` and image, a spot's) seen by `camera`,
    /// with grid depths relative to `z_origin`.
    pub(super) fn new(
        light: &PointLight,
        pattern: Option<(&PatternSpec, &Arc<Pattern>)>,
        camera: &Camera,
        z_origin: f64,
    ) -> PointSource {
        let c = camera.to_grid(DVec3::from(light.position));
        let px = camera.pixel_size;
        let to_camera = |d: DVec3| {
            DVec3::new(
                d.dot(camera.right),
                d.dot(camera.down),
                d.dot(camera.forward),
            )
        };
        let spot = light.spot.map(|s| SpotCone {
            direction: to_camera(DVec3::from(s.direction)).to_array(),
            ..s
        });
        let pattern = light.spot.zip(pattern).map(|(s, (spec, image))| {
            let [right, down, _] = frame(DVec3::from(s.direction), DVec3::from(s.up));
            SpotPattern {
                right: to_camera(right),
                down: to_camera(down),
                size: spec.size,
                center: spec.center,
                image: Arc::clone(image),
            }
        });
        PointSource {
            center: [c.x, c.y, c.z - z_origin],
            sigma: [light.radius / px, light.radius / px, light.radius],
            pixel_size: px,
            spot,
            pattern,
        }
    }

    /// World units per grid pixel across the view.
    pub(super) fn pixel_size(&self) -> f64 {
        self.pixel_size
    }

    /// The camera-space world vector from grid point `p` to the light's centre.
    fn toward_center(&self, p: [f64; 3]) -> DVec3 {
        let d = sub(self.center, p);
        DVec3::new(d[0] * self.pixel_size, d[1] * self.pixel_size, d[2])
    }

    /// The factor the light's centre gives the light arriving at `p`, per channel: the cone
    /// (1 for a point light) times a spot's pattern over the squared distance,
    /// `cone(X − P)·pattern(X − P) / |X − P|²` (0 at the centre itself).
    pub(super) fn falloff(&self, p: [f64; 3]) -> [f64; 3] {
        let d = self.toward_center(p);
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return [0.0; 3];
        }
        let cone = self.spot.map_or(1.0, |s| s.factor(-d)) / d2;
        let Some(pattern) = &self.pattern else {
            return [cone; 3];
        };
        // Where the ray from the centre through X meets the unit plane along the axis: none at
        // 90° or more from the axis.
        let out = -d;
        let along = out.dot(DVec3::from(
            self.spot.map_or([0.0, 0.0, 1.0], |s| s.direction),
        ));
        if along <= 0.0 {
            return [0.0; 3];
        }
        let (a, b) = (
            out.dot(pattern.right) / along,
            out.dot(pattern.down) / along,
        );
        let img = &pattern.image;
        let tx = ((a - pattern.center[0]) / pattern.size[0] + 0.5) * f64::from(img.width);
        let ty = ((b - pattern.center[1]) / pattern.size[1] + 0.5) * f64::from(img.height);
        std::array::from_fn(|c| cone * img.sample(tx, ty, c))
    }

    /// The shading's terms of this light at grid point `p` (a front-to-back pass: the viewer
    /// along −z): the direction to the centre, its half vector with the view, the Fresnel
    /// constants, and the colour times the phase function `g` for the angle between the light's
    /// travel and the view (the bare colour where g = 0, as the plan's).
    pub(super) fn terms(&self, p: [f64; 3], color: [f32; 3], g: f64) -> LightTerms {
        let d = self.toward_center(p);
        let to_light = if d.length_squared() > 0.0 {
            d.normalize()
        } else {
            DVec3::NEG_Z
        };
        let h = (to_light + DVec3::NEG_Z).normalize_or(DVec3::NEG_Z);
        let f32x3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        // cos θ between the travel (−to_light) and the direction to the viewer (−z).
        let phase = henyey_greenstein(g, to_light.z);
        let light_color = if g == 0.0 {
            color
        } else {
            color.map(|c| (f64::from(c) * phase) as f32)
        };
        LightTerms {
            light_color,
            color,
            to_light: f32x3(to_light),
            half_vector: f32x3(h),
            fresnel: fresnel_terms(h, to_light),
        }
    }
}

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
