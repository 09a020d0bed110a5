//! Validation of what makes a light world-space (`[[light]] kind`, `direction`, `up`): the light
//! kinds this renderer sweeps, and a world-space light placed on the camera's slab plane.

use glam::DVec3;

use super::validate::Validator;
use crate::model::scene::{CameraSpec, LightSpec, SceneError, WorldLight};

impl Validator<'_> {
    /// `light[i].kind`: `"directional"` (the default). Point and spot lights (issue 41) are
    /// refused by name until the sweep has them.
    pub(super) fn light_kind(&self, i: usize, kind: Option<&str>) -> Result<(), SceneError> {
        match kind {
            None | Some("directional") => Ok(()),
            Some(k @ ("point" | "spot")) => Err(self.err(
                format!("light[{i}].kind"),
                format!("{k} lights are not supported yet: only \"directional\" lights are"),
            )),
            Some(k) => Err(self.err(
                format!("light[{i}].kind"),
                format!("expected \"directional\", \"point\" or \"spot\", got {k:?}"),
            )),
        }
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
