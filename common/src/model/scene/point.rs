//! Point and spot lights (`[[light]] kind = "point" | "spot"`): a light at a place, whose rays
//! diverge from it (issue 41). Rendered by the shadow-ray reference and by the sweep on a grid of
//! their own (docs/how-it-works.md, "Point and spot lights").

use glam::DVec3;

/// A point light, or a spot light (with [`PointLight::spot`]), as the scene gives it in world
/// space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// World position of the light's centre.
    pub position: [f64; 3],
    /// Standard deviation (world units) of the isotropic 3D Gaussian the light spreads over
    /// around `position`; 0 = a hard point light.
    pub radius: f64,
    /// The cone a spot light emits into; `None` for a point light (every direction).
    pub spot: Option<SpotCone>,
}

/// A spot light's cone: full intensity within `cone_deg` of its axis, fading smoothly to 0 over
/// the further `falloff_deg`, nothing beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotCone {
    /// The world direction of the axis (unit): where the spot points.
    pub direction: [f64; 3],
    /// The world direction the spot's own frame's "up" follows (unit, not parallel to the
    /// axis): its pattern's rows run down against it (`frame(direction, up)`, as a directional
    /// light's and the camera's).
    pub up: [f64; 3],
    /// Half-angle of full intensity, degrees (0–89).
    pub cone_deg: f64,
    /// The further half-angle over which the intensity fades to 0, degrees (0–90; 0 = a hard
    /// edge).
    pub falloff_deg: f64,
}

impl SpotCone {
    /// The cone's factor for light leaving the light's centre along `to_point` (any length, not
    /// zero): 1 within `cone_deg` of the axis, 0 beyond `cone_deg + falloff_deg`, between them
    /// the smoothstep `3s² − 2s³` of `s = (cos θ − cos_outer) / (cos_inner − cos_outer)` — in the
    /// cosine of the angle θ from the axis, as pbrt-v4's spot light, so no arc cosine is needed
    /// (the GPU port evaluates it in f32 with the same operations, [`SpotCone::cosines`]).
    pub fn factor(&self, to_point: DVec3) -> f64 {
        let cos = to_point.normalize().dot(DVec3::from(self.direction));
        let [inner, outer] = self.cosines();
        if cos >= inner {
            1.0
        } else if cos > outer {
            let s = (cos - outer) / (inner - outer);
            s * s * (3.0 - 2.0 * s)
        } else {
            0.0
        }
    }

    /// The cosines of the cone's half-angle and of its outer edge (`cone_deg + falloff_deg`,
    /// at most 90°).
    pub fn cosines(&self) -> [f64; 2] {
        let outer = (self.cone_deg + self.falloff_deg).min(90.0);
        [self.cone_deg.to_radians().cos(), outer.to_radians().cos()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_is_full_inside_its_cone_half_at_its_falloffs_middle_cosine_and_dark_beyond() {
        let spot = SpotCone {
            direction: [0.0, 0.0, 1.0],
            up: [0.0, 1.0, 0.0],
            cone_deg: 20.0,
            falloff_deg: 10.0,
        };
        let at = |deg: f64| {
            let a = deg.to_radians();
            spot.factor(DVec3::new(a.sin(), 0.0, a.cos()) * 3.0)
        };
        assert_eq!(at(0.0), 1.0);
        assert_eq!(at(19.9), 1.0);
        // Half-way through the falloff in the cosine the smoothstep is exactly 1/2.
        let half = ((20f64.to_radians().cos() + 30f64.to_radians().cos()) * 0.5).acos();
        let at_half = at(half.to_degrees());
        assert!((at_half - 0.5).abs() < 1e-9, "{at_half}");
        assert!(at(22.0) > at(24.0) && at(26.0) > at(28.0));
        assert_eq!(at(30.1), 0.0);
        assert_eq!(at(120.0), 0.0);
        let hard = SpotCone {
            falloff_deg: 0.0,
            ..spot
        };
        let dir = |deg: f64| {
            let a = f64::to_radians(deg);
            DVec3::new(0.0, a.sin(), a.cos())
        };
        assert_eq!(hard.factor(dir(19.99)), 1.0);
        assert_eq!(hard.factor(dir(20.01)), 0.0);
    }
}
