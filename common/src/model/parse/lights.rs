//! Validation of what makes a light world-space (`[[light]] kind` and `direction`): the light
//! kinds this renderer sweeps, and the camera-space tilt of a world direction.

use super::validate::Validator;
use crate::model::scene::{CameraSpec, SceneError};

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

    /// The camera-space tilt of light i travelling along the world unit vector `direction`
    /// ([`CameraSpec::tilt_of`]); `after` names what changed the camera, for the message.
    pub(crate) fn light_tilt(
        &self,
        i: usize,
        direction: [f64; 3],
        camera: &CameraSpec,
        after: &str,
    ) -> Result<[f64; 2], SceneError> {
        camera.tilt_of(direction).map_err(|angle| {
            self.err(
                format!("light[{i}].direction"),
                format!(
                    "the light travels at {angle:.1}° to the view direction{after}; only lights \
                     from behind the viewer (less than 90°) are supported yet, not lights from \
                     beside or in front of it"
                ),
            )
        })
    }
}
