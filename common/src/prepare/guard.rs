//! The guard band: light buffer and LDI beyond each image edge, so that occluders just outside
//! the view cast their shadows into it.
//!
//! `sweep.guard_band = "auto"` (the default) sizes the band per side from the scene: the reach of
//! every light's shadow over the scene's depth, clipped to how far the meshes project beyond that
//! side of the view (see docs/how-it-works.md, "Guard band"). An integer sets the same band on
//! all four sides by hand; 0 turns it off. The band is host-side planning only: the rasterizer
//! set-up, the plan and every backend read the same [`GuardBand`].

use crate::model::scene::GuardBandSpec;
use std::fmt;

use glam::DVec3;

use crate::model::scene::{LightSpec, MAX_GUARD_BAND, Penumbra};
use crate::plan::kernel::KernelMoments;
use crate::prepare::camera::Camera;

/// Standard deviations of the accumulated kernel the automatic band adds to the mean shift.
///
/// Beyond the band the buffer reads as unoccluded light, and the iterated kernel carries that
/// boundary inward: an image pixel at `k` standard deviations from the band's outer edge loses
/// about `2·Φ(−k)` of an occluder's shadow (the probability that the kernel's random walk leaves
/// the band). `k = 3` leaves 0.27 % (two thirds of an 8-bit step) at the image edge; `k = 4`
/// leaves 6·10⁻⁵, below any 8-bit step, for 1.3·σ more band on each side a shadow can reach.
pub const AUTO_GUARD_SIGMAS: f64 = 4.0;

impl GuardBandSpec {
    /// The band known without building the geometry: the fixed band, or none for `Auto` (a lower
    /// bound of what `Auto` chooses, for refusing a render before anything is loaded).
    pub fn lower_bound(self) -> GuardBand {
        match self {
            GuardBandSpec::Auto => GuardBand::default(),
            GuardBandSpec::Pixels(g) => GuardBand::uniform(g),
        }
    }
}

/// The guard band of one render, in pixels beyond each image edge.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct GuardBand {
    /// Columns left of the image.
    pub left: u32,
    /// Columns right of the image.
    pub right: u32,
    /// Rows above the image.
    pub top: u32,
    /// Rows below the image.
    pub bottom: u32,
}

impl GuardBand {
    /// `g` pixels on every side.
    pub const fn uniform(g: u32) -> GuardBand {
        GuardBand {
            left: g,
            right: g,
            top: g,
            bottom: g,
        }
    }

    /// The grid (image plus band) of a `width × height` image: (grid width, grid height).
    pub fn grid(&self, width: u32, height: u32) -> (u32, u32) {
        (
            width + self.left + self.right,
            height + self.top + self.bottom,
        )
    }

    /// Grid pixels of a `width × height` image with this band, in u64 (for the memory budget).
    pub fn grid_pixels(&self, width: u32, height: u32) -> u64 {
        (u64::from(width) + u64::from(self.left) + u64::from(self.right))
            * (u64::from(height) + u64::from(self.top) + u64::from(self.bottom))
    }

    /// `[left, right, top, bottom]`.
    pub fn sides(&self) -> [u32; 4] {
        [self.left, self.right, self.top, self.bottom]
    }

    /// The band a scene asks for: the fixed band, or for `Auto` the one [`auto_guard_band`]
    /// computes from the rest of the arguments.
    pub fn resolve(spec: GuardBandSpec, scene: &AutoGuardInput<'_>) -> GuardBand {
        match spec {
            GuardBandSpec::Pixels(g) => GuardBand::uniform(g),
            GuardBandSpec::Auto => auto_guard_band(scene),
        }
    }
}

impl fmt::Display for GuardBand {
    /// `12 px` when every side is the same, else `left/right/top/bottom = 12/0/5/5 px`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [l, r, t, b] = self.sides();
        if l == r && r == t && t == b {
            write!(f, "{l} px")
        } else {
            write!(f, "left/right/top/bottom = {l}/{r}/{t}/{b} px")
        }
    }
}

/// What the automatic band is computed from.
pub struct AutoGuardInput<'a> {
    /// The camera (pixel size and image size).
    pub camera: &'a Camera,
    /// Every mesh as (world-space vertices, triangles).
    pub meshes: Vec<(&'a [DVec3], &'a [[u32; 3]])>,
    /// The lights.
    pub lights: &'a [LightSpec],
    /// Slab count of the sweep.
    pub slabs: u32,
    /// Slab thickness (world units).
    pub slab_distance: f64,
    /// The optimal shadow distance d1 (world units), for the iterated penumbra.
    pub optimal_distance: Option<f64>,
    /// How the kernel grows with depth.
    pub penumbra: Penumbra,
    /// Whether the kernels compensate the variance of bilinear reads.
    pub variance_compensation: bool,
}

/// The automatic guard band (see the module documentation and docs/how-it-works.md).
///
/// A triangle's part beyond an image edge can darken the image only through receivers deeper
/// than its nearest point, so over at most `D = z_far − z_near` of depth (`z_far`: the scene's
/// farthest vertex). Over `k = min(D/e + 1, n)` slabs a light's shadow reaches, towards the image
/// from one side, the mean shift `k·μκ` (0 where the shadows move away from that side) plus
/// [`AUTO_GUARD_SIGMAS`] standard deviations of the accumulated kernel (`k·Σκ`, plus the
/// bilinear reads' variance of at most ¼ px² per slab when it is not compensated) plus one pixel
/// for the bilinear corners. Per side, the band is the largest over triangles of the smaller of
/// that reach (the larger over lights) and how far the triangle extends beyond the side, rounded
/// up and capped at [`MAX_GUARD_BAND`]. So a scene whose meshes all lie inside the view gets no
/// band, and a backdrop wall reaching out of the view gets only the band its own thickness
/// allows (nothing lies behind it to shadow).
pub fn auto_guard_band(input: &AutoGuardInput<'_>) -> GuardBand {
    let cam = input.camera;
    let (w, h) = (f64::from(cam.width), f64::from(cam.height));
    let projected: Vec<Vec<DVec3>> = input
        .meshes
        .iter()
        .map(|(pos, _)| pos.iter().map(|p| cam.to_pixel(*p)).collect())
        .collect();
    let z_far = projected
        .iter()
        .flatten()
        .map(|q| q.z)
        .fold(f64::NEG_INFINITY, f64::max);
    let moments: Vec<_> = input
        .lights
        .iter()
        .map(|light| {
            KernelMoments::for_light(
                light.tilt_deg,
                light.variance,
                light.rotation_deg,
                input.slab_distance,
                // Distance penumbra: the covariance per e² of depth, scaled by k² below.
                match input.penumbra {
                    Penumbra::Iterated => input.optimal_distance.unwrap_or(input.slab_distance),
                    Penumbra::Distance => input.slab_distance,
                },
                cam.pixel_size,
            )
        })
        .collect();
    let bilinear = if input.variance_compensation {
        0.0
    } else {
        0.25
    };
    // Reach towards the image from [left, right, top, bottom] over `k` slabs, over all lights.
    let reach = |k: f64| -> [f64; 4] {
        let mut r = [0.0f64; 4];
        for m in &moments {
            // Iterated: k·Σκ after k slabs; distance: (k·e)²·Σl, at most, for an occluder k
            // slabs in front.
            let sd = |axis: usize| match input.penumbra {
                Penumbra::Iterated => (k * (m.cov[axis][axis].max(0.0) + bilinear)).sqrt(),
                Penumbra::Distance => (k * k * m.cov[axis][axis].max(0.0) + k * bilinear).sqrt(),
            };
            // μκ is where the impulse response moves per slab (the gather reads at −μκ): an
            // occluder at q darkens q + k·μκ, so occluders left of the image (x < 0) reach
            // into it when μκ.x > 0.
            let side = [
                k * m.mean[0].max(0.0) + AUTO_GUARD_SIGMAS * sd(0),
                k * (-m.mean[0]).max(0.0) + AUTO_GUARD_SIGMAS * sd(0),
                k * m.mean[1].max(0.0) + AUTO_GUARD_SIGMAS * sd(1),
                k * (-m.mean[1]).max(0.0) + AUTO_GUARD_SIGMAS * sd(1),
            ];
            for (r, s) in r.iter_mut().zip(side) {
                *r = r.max(s + 1.0);
            }
        }
        r
    };
    let n = f64::from(input.slabs);
    let mut band = [0.0f64; 4];
    for ((_, tris), q) in input.meshes.iter().zip(&projected) {
        for t in tris.iter() {
            let v = t.map(|i| q[i as usize]);
            // How far the triangle extends beyond each edge (pixels).
            let beyond = [
                -v.iter().map(|p| p.x).fold(f64::INFINITY, f64::min),
                v.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max) - w,
                -v.iter().map(|p| p.y).fold(f64::INFINITY, f64::min),
                v.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max) - h,
            ];
            if beyond.iter().all(|&b| b <= 0.0) {
                continue;
            }
            let z_near = v.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
            // One slab more than the depth spans: the occluder and its receiver may sit at
            // the far and near ends of their slabs.
            let k = ((z_far - z_near) / input.slab_distance + 1.0).min(n);
            let r = reach(k);
            for s in 0..4 {
                band[s] = band[s].max(beyond[s].min(r[s]));
            }
        }
    }
    let side = |px: f64| -> u32 {
        // NaN (never from validated scenes) and huge reaches end at the cap.
        let px = px.ceil();
        if px >= f64::from(MAX_GUARD_BAND) || px.is_nan() {
            MAX_GUARD_BAND
        } else {
            px.max(0.0) as u32
        }
    };
    GuardBand {
        left: side(band[0]),
        right: side(band[1]),
        top: side(band[2]),
        bottom: side(band[3]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::scene::{CameraSpec, ImageSpec};

    fn camera(width: u32, height: u32, view_width: f64) -> Camera {
        Camera::new(
            &CameraSpec {
                direction: [0.0, 0.0, 1.0],
                up: [0.0, 1.0, 0.0],
                center: [0.0, 0.0, 0.0],
                view_width,
                projection: Default::default(),
            },
            &ImageSpec {
                width,
                height,
                background: [0.0; 3],
                exposure: 0.0,
                tonemap: Default::default(),
            },
        )
    }

    fn light(tilt_deg: [f64; 2], variance: [f64; 2]) -> LightSpec {
        LightSpec {
            color: [1.0; 3],
            tilt_deg,
            world: None,
            variance,
            rotation_deg: 0.0,
            pattern: None,
            toward_viewer: false,
            point: None,
        }
    }

    #[test]
    fn spec_parses_auto_and_counts_and_refuses_the_rest() {
        assert_eq!("auto".parse(), Ok(GuardBandSpec::Auto));
        assert_eq!("0".parse(), Ok(GuardBandSpec::Pixels(0)));
        assert_eq!("4096".parse(), Ok(GuardBandSpec::Pixels(4096)));
        for bad in ["4097", "-1", "Auto", "", "1.5"] {
            let err = bad.parse::<GuardBandSpec>().unwrap_err();
            assert!(err.contains("\"auto\""), "{bad}: {err}");
        }
        assert_eq!(GuardBand::uniform(3).to_string(), "3 px");
        let b = GuardBand {
            left: 1,
            right: 2,
            top: 3,
            bottom: 4,
        };
        assert_eq!(b.to_string(), "left/right/top/bottom = 1/2/3/4 px");
        assert_eq!(b.grid(10, 20), (13, 27));
        assert_eq!(b.grid_pixels(10, 20), 13 * 27);
    }

    /// One triangle with these world-space vertices.
    fn tri(v: [[f64; 3]; 3]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        (v.iter().map(|p| DVec3::from(*p)).collect(), vec![[0, 1, 2]])
    }

    fn band_of(
        cam: &Camera,
        lights: &[LightSpec],
        meshes: &[(Vec<DVec3>, Vec<[u32; 3]>)],
    ) -> GuardBand {
        auto_guard_band(&AutoGuardInput {
            camera: cam,
            meshes: meshes
                .iter()
                .map(|(p, t)| (p.as_slice(), t.as_slice()))
                .collect(),
            lights,
            slabs: 10,
            slab_distance: 0.1,
            optimal_distance: Some(1.0),
            penumbra: Penumbra::Iterated,
            variance_compensation: true,
        })
    }

    #[test]
    fn auto_band_is_the_shadow_reach_clipped_to_the_meshes() {
        // 100 × 50 px over 10 world units: px = 0.1. The light tilts by atan 1.05 in x with
        // σx² = 0.0121 per unit depth, σy² = 0; 10 slabs of 0.1 (depth 1), d1 = 1. Per slab
        // the shadow moves 0.1·1.05 / px = 1.05 px and spreads by 1·0.1·0.0121 / px² =
        // 0.121 px²; over the whole depth 10.5 px and σ = 1.1 px.
        let cam = camera(100, 50, 10.0);
        let lights = [light([1.05f64.atan().to_degrees(), 0.0], [0.0121, 0.0])];
        // Camera x is world −x, camera y is world −y (looking along +z with +y up).
        let inside_far = tri([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]]);
        let inside_near = tri([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        // A triangle at the front reaching 100 px and more beyond every edge.
        let front = tri([[-15.0, -15.0, 0.0], [15.0, -15.0, 0.0], [0.0, 30.0, 0.0]]);
        // μl.x > 0: shadows move by −d·μl, towards −x (camera left), so occluders on the right
        // reach the image: ⌈10.5 + 4·1.1 + 1⌉ = 16 px; on the left only the spread,
        // ⌈4·1.1 + 1⌉ = 6 px. In y the light has no spread and no shift: the bilinear corner only.
        assert_eq!(
            band_of(&cam, &lights, &[front.clone(), inside_far.clone()]),
            GuardBand {
                left: 6,
                right: 16,
                top: 1,
                bottom: 1
            }
        );
        // The same triangle at the back (nothing behind it): one slab's reach,
        // ⌈1.05 + 4·√0.121 + 1⌉ = ⌈3.44⌉ = 4 px right, ⌈4·√0.121 + 1⌉ = ⌈2.39⌉ = 3 px left.
        let back = tri([[-15.0, -15.0, 1.0], [15.0, -15.0, 1.0], [0.0, 30.0, 1.0]]);
        assert_eq!(
            band_of(&cam, &lights, &[back, inside_near.clone()]),
            GuardBand {
                left: 3,
                right: 4,
                top: 1,
                bottom: 1
            }
        );
        // Meshes inside the view: no band at all, whatever the light.
        assert_eq!(
            band_of(&cam, &lights, &[inside_near.clone(), inside_far.clone()]),
            GuardBand::default()
        );
        // A triangle 0.35 world = 3.5 px beyond the left edge only: 4 px there (less than the
        // 6 px the light reaches from the left), none elsewhere.
        let left = tri([[5.35, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]);
        assert_eq!(
            band_of(&cam, &lights, &[left, inside_far]),
            GuardBand {
                left: 4,
                ..GuardBand::default()
            }
        );
    }

    #[test]
    fn auto_band_stops_at_the_cap() {
        let cam = camera(64, 64, 1.0);
        let lights = [light([0.0, 0.0], [1e8, 1e8])];
        let near = tri([[-1e6, -1e6, 0.0], [1e6, -1e6, 0.0], [0.0, 2e6, 0.0]]);
        let far = tri([[0.0, 0.0, 100.0], [0.1, 0.0, 100.0], [0.0, 0.1, 100.0]]);
        let meshes = [near, far];
        let band = auto_guard_band(&AutoGuardInput {
            camera: &cam,
            meshes: meshes
                .iter()
                .map(|(p, t)| (p.as_slice(), t.as_slice()))
                .collect(),
            lights: &lights,
            slabs: 100,
            slab_distance: 1.0,
            optimal_distance: Some(1.0),
            penumbra: Penumbra::Iterated,
            variance_compensation: false,
        });
        assert_eq!(band, GuardBand::uniform(MAX_GUARD_BAND));
    }
}
