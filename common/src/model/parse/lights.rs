//! Validation of what makes a light world-space (`[[light]] kind`, `direction`, `up`, and a
//! point or spot light's `position`, `radius`, `cone_deg`, `falloff_deg`): the light kinds, and a
//! world-space light placed on the camera's slab plane.

use glam::DVec3;

use super::RawLight;
use super::validate::Validator;
use crate::model::scene::{
    CameraSpec, LightSpec, MAX_WORLD, PointLight, SceneError, SpotCone, WorldLight,
};

/// What `[[light]] kind` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LightKind {
    /// A distant Gaussian light (the default).
    Directional,
    /// A light at a place, shining every way.
    Point,
    /// A point light shining into a cone.
    Spot,
}

impl Validator<'_> {
    /// `light[i].kind`: `"directional"` (the default), `"point"` or `"spot"`.
    pub(super) fn light_kind(&self, i: usize, kind: Option<&str>) -> Result<LightKind, SceneError> {
        match kind {
            None | Some("directional") => Ok(LightKind::Directional),
            Some("point") => Ok(LightKind::Point),
            Some("spot") => Ok(LightKind::Spot),
            Some(k) => Err(self.err(
                format!("light[{i}].kind"),
                format!("expected \"directional\", \"point\" or \"spot\", got {k:?}"),
            )),
        }
    }

    /// Light i's place, size and cone, for a point or spot light: `position` (required),
    /// `radius` (default 0, at most 1e9), and for a spot `direction` (required, its axis),
    /// `cone_deg` (required, 0–89) and `falloff_deg` (default 0, 0–90). A directional light's
    /// keys are refused by name on these kinds, and these kinds' keys on a directional light.
    pub(super) fn point_light(
        &self,
        i: usize,
        kind: LightKind,
        raw: &RawLight,
    ) -> Result<Option<PointLight>, SceneError> {
        let key = |k: &str| format!("light[{i}].{k}");
        if kind == LightKind::Directional {
            let theirs = [
                ("position", raw.position.is_some()),
                ("radius", raw.radius.is_some()),
                ("cone_deg", raw.cone_deg.is_some()),
                ("falloff_deg", raw.falloff_deg.is_some()),
            ];
            if let Some((k, _)) = theirs.iter().find(|(_, given)| *given) {
                return Err(self.err(
                    key(k),
                    "only applies to point and spot lights (`kind = \"point\"` or \"spot\"`)",
                ));
            }
            return Ok(None);
        }
        let name = if kind == LightKind::Spot {
            "spot"
        } else {
            "point"
        };
        let directional = [
            ("tilt_deg", raw.tilt_deg.is_some()),
            ("variance", raw.variance.is_some()),
            ("rotation_deg", raw.rotation_deg.is_some()),
            ("up", raw.up.is_some() && kind == LightKind::Point),
            (
                "direction",
                raw.direction.is_some() && kind == LightKind::Point,
            ),
        ];
        if let Some((k, _)) = directional.iter().find(|(_, given)| *given) {
            return Err(self.err(
                key(k),
                format!(
                    "only applies to directional lights: a {name} light's place is `position`, \
                     its size `radius`{}",
                    if kind == LightKind::Spot {
                        ", its axis `direction`"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if raw.pattern.is_some() && kind == LightKind::Point {
            return Err(self.err(
                key("pattern"),
                "only applies to directional and spot lights: a point light shines every way",
            ));
        }
        let position = raw.position.ok_or_else(|| {
            self.err(
                key("position"),
                format!("expected `position = [x, y, z]`: where the {name} light is (world units)"),
            )
        })?;
        let position = self.bounded3(&key("position"), position, MAX_WORLD)?;
        let radius = self.finite(&key("radius"), raw.radius.unwrap_or(0.0))?;
        if !(0.0..=MAX_WORLD).contains(&radius) {
            return Err(self.err(
                key("radius"),
                format!("expected a radius from 0 to {MAX_WORLD:e} (world units), got {radius}"),
            ));
        }
        let spot = match kind {
            LightKind::Spot => {
                let direction = raw.direction.ok_or_else(|| {
                    self.err(
                        key("direction"),
                        "expected `direction = [x, y, z]`: the world direction the spot points",
                    )
                })?;
                let direction = self.unit_vector(&key("direction"), direction)?;
                // The spot's own frame, chosen as a directional light's (`world_light`).
                let up = self.world_light(i, direction, raw.up, [0.0; 2], 0.0)?.up;
                let cone_deg = raw.cone_deg.ok_or_else(|| {
                    self.err(
                        key("cone_deg"),
                        "expected `cone_deg`: the half-angle of full intensity, 0 to 89 degrees",
                    )
                })?;
                let cone_deg = self.finite(&key("cone_deg"), cone_deg)?;
                if !(0.0..=89.0).contains(&cone_deg) {
                    return Err(self.err(
                        key("cone_deg"),
                        format!("expected a half-angle from 0 to 89 degrees, got {cone_deg}"),
                    ));
                }
                let falloff_deg =
                    self.finite(&key("falloff_deg"), raw.falloff_deg.unwrap_or(0.0))?;
                if !(0.0..=90.0).contains(&falloff_deg) {
                    return Err(self.err(
                        key("falloff_deg"),
                        format!("expected a half-angle from 0 to 90 degrees, got {falloff_deg}"),
                    ));
                }
                Some(SpotCone {
                    direction,
                    up,
                    cone_deg,
                    falloff_deg,
                })
            }
            _ => {
                for (k, given) in [
                    ("cone_deg", raw.cone_deg.is_some()),
                    ("falloff_deg", raw.falloff_deg.is_some()),
                ] {
                    if given {
                        return Err(
                            self.err(key(k), "only applies to spot lights (`kind = \"spot\"`)")
                        );
                    }
                }
                None
            }
        };
        Ok(Some(PointLight {
            position,
            radius,
            spot,
        }))
    }

    /// Light i's `tilt_deg` (default [0, 0]), each |ω| < 90; refused beside a `direction`.
    pub(super) fn light_tilt(
        &self,
        i: usize,
        tilt: Option<[f64; 2]>,
        has_direction: bool,
    ) -> Result<[f64; 2], SceneError> {
        if has_direction && tilt.is_some() {
            return Err(self.err(
                format!("light[{i}]"),
                "expected `tilt_deg` (camera space) or `direction` (world space), not both",
            ));
        }
        let tilt = tilt.unwrap_or([0.0; 2]);
        for (j, t) in tilt.iter().enumerate() {
            let k = format!("light[{i}].tilt_deg[{j}]");
            self.finite(&k, *t)?;
            if t.abs() >= 90.0 {
                return Err(self.err(k, format!("expected |angle| < 90 degrees, got {t}")));
            }
        }
        Ok(tilt)
    }

    /// Light i's world-space spec from its `direction`, `up` (default world +y, or +z where
    /// the direction is within 10⁻⁶ of parallel to +y: a light straight down or up) and its
    /// validated `variance` and `rotation_deg`.
    pub(super) fn world_light(
        &self,
        i: usize,
        direction: [f64; 3],
        up: Option<[f64; 3]>,
        variance: [f64; 2],
        rotation_deg: f64,
    ) -> Result<WorldLight, SceneError> {
        let direction = self.unit_vector(&format!("light[{i}].direction"), direction)?;
        let across = |u: [f64; 3]| DVec3::from(direction).cross(DVec3::from(u)).length() >= 1e-6;
        let up = match up {
            Some(u) => {
                let key = format!("light[{i}].up");
                let u = self.unit_vector(&key, u)?;
                if !across(u) {
                    return Err(self.err(key, "expected a direction not parallel to `direction`"));
                }
                u
            }
            None if across([0.0, 1.0, 0.0]) => [0.0, 1.0, 0.0],
            None => [0.0, 0.0, 1.0],
        };
        Ok(WorldLight {
            direction,
            up,
            variance,
            rotation_deg,
        })
    }

    /// Sets light i's tilt and slab-plane spread from its world-space spec seen by `camera`
    /// ([`CameraSpec::light_on_slabs`]); `after` names what changed the camera, for the message.
    pub(crate) fn place_light(
        &self,
        i: usize,
        light: &mut LightSpec,
        world: WorldLight,
        camera: &CameraSpec,
        after: &str,
    ) -> Result<(), SceneError> {
        let on_slabs = camera.light_on_slabs(&world).map_err(|angle| {
            self.err(
                format!("light[{i}].direction"),
                format!(
                    "the light travels at {angle:.1}° to the view direction{after}, along the \
                     slab planes: a light beside the viewer (exactly 90°) has no sweep order; \
                     any other angle is supported"
                ),
            )
        })?;
        light.toward_viewer = on_slabs.toward_viewer;
        light.tilt_deg = on_slabs.tilt_deg;
        light.variance = on_slabs.variance;
        light.rotation_deg = on_slabs.rotation_deg;
        light.world = Some(world);
        Ok(())
    }
}
