//! Validation of `[camera]`: the orthographic keys (`direction`, `center`, `view_width`) or the
//! perspective ones (`eye`, `look_at`, `fov_deg`, `near`), `up` for both, each refused beside the
//! other projection's keys so that a scene says one thing.

use super::RawCamera;
use super::validate::Validator;
use crate::model::scene::{
    CameraSpec, MAX_FOV_DEG, MAX_WORLD, MIN_FOV_DEG, Projection, SceneError,
};

/// The keys only an orthographic camera takes.
const ORTHOGRAPHIC_KEYS: [&str; 3] = ["direction", "center", "view_width"];
/// The keys only a perspective camera takes.
const PERSPECTIVE_KEYS: [&str; 4] = ["eye", "look_at", "fov_deg", "near"];

impl Validator<'_> {
    /// `[camera]` as the model takes it; `aspect` is the image's width over its height.
    pub(super) fn camera(&self, raw: &RawCamera, aspect: f64) -> Result<CameraSpec, SceneError> {
        let perspective = match raw.projection.as_deref() {
            None | Some("orthographic") => false,
            Some("perspective") => true,
            Some(p) => {
                return Err(self.err(
                    "camera.projection",
                    format!("expected \"orthographic\" or \"perspective\", got {p:?}"),
                ));
            }
        };
        let given = |key: &str| match key {
            "direction" => raw.direction.is_some(),
            "center" => raw.center.is_some(),
            "view_width" => raw.view_width.is_some(),
            "eye" => raw.eye.is_some(),
            "look_at" => raw.look_at.is_some(),
            "fov_deg" => raw.fov_deg.is_some(),
            _ => raw.near.is_some(),
        };
        let (foreign, kind) = if perspective {
            (
                &ORTHOGRAPHIC_KEYS[..],
                "a perspective camera (eye, look_at, fov_deg, near)",
            )
        } else {
            (
                &PERSPECTIVE_KEYS[..],
                "an orthographic camera (direction, center, view_width)",
            )
        };
        if let Some(key) = foreign.iter().find(|k| given(k)) {
            let other = if perspective {
                "an orthographic camera's key; set camera.projection = \"orthographic\" or use"
            } else {
                "a perspective camera's key; set camera.projection = \"perspective\", or use"
            };
            return Err(self.err(format!("camera.{key}"), format!("{other} {kind}")));
        }
        let up = self.unit_vector("camera.up", raw.up.unwrap_or([0.0, 1.0, 0.0]))?;
        if !perspective {
            let direction =
                self.unit_vector("camera.direction", raw.direction.unwrap_or([0.0, 0.0, 1.0]))?;
            self.not_parallel("camera.up", up, direction, "camera.direction")?;
            let Some(view_width) = raw.view_width else {
                return Err(self.err(
                    "camera.view_width",
                    "missing: an orthographic camera needs the world width the image spans",
                ));
            };
            return Ok(CameraSpec {
                direction,
                up,
                center: self.bounded3(
                    "camera.center",
                    raw.center.unwrap_or([0.0; 3]),
                    MAX_WORLD,
                )?,
                view_width: self.length("camera.view_width", view_width)?,
                projection: Projection::Orthographic,
            });
        }
        let missing =
            |key: &str, what: &str| self.err(format!("camera.{key}"), format!("missing: {what}"));
        let eye = raw
            .eye
            .ok_or_else(|| missing("eye", "a perspective camera needs the eye's position"))?;
        let look_at = raw.look_at.ok_or_else(|| {
            missing(
                "look_at",
                "a perspective camera needs the point it looks at",
            )
        })?;
        let fov_deg = raw.fov_deg.ok_or_else(|| {
            missing(
                "fov_deg",
                "a perspective camera needs its vertical field of view in degrees",
            )
        })?;
        let mut camera = CameraSpec {
            direction: [0.0, 0.0, 1.0],
            up,
            center: self.bounded3("camera.eye", eye, MAX_WORLD)?,
            view_width: 1.0,
            projection: Projection::Perspective {
                look_at: self.bounded3("camera.look_at", look_at, MAX_WORLD)?,
                fov_deg: self.fov("camera.fov_deg", fov_deg)?,
                near: raw
                    .near
                    .map(|n| self.length("camera.near", n))
                    .transpose()?,
            },
        };
        self.aim(
            &mut camera,
            aspect,
            ["camera.look_at", "camera.up", "camera.eye"],
        )?;
        Ok(camera)
    }

    /// A vertical field of view in [`MIN_FOV_DEG`, `MAX_FOV_DEG`] degrees.
    pub(super) fn fov(&self, key: &str, v: f64) -> Result<f64, SceneError> {
        self.finite(key, v)?;
        if (MIN_FOV_DEG..=MAX_FOV_DEG).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                key,
                format!("expected a vertical field of view in [{MIN_FOV_DEG}, {MAX_FOV_DEG}] degrees, got {v}"),
            ))
        }
    }

    /// Refuses `v` (under `key`) parallel to `other` (under `other_key`).
    pub(super) fn not_parallel(
        &self,
        key: &str,
        v: [f64; 3],
        other: [f64; 3],
        other_key: &str,
    ) -> Result<(), SceneError> {
        let cross = [
            other[1] * v[2] - other[2] * v[1],
            other[2] * v[0] - other[0] * v[2],
            other[0] * v[1] - other[1] * v[0],
        ];
        if (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt() < 1e-6 {
            return Err(self.err(
                key,
                format!("expected a direction not parallel to {other_key}"),
            ));
        }
        Ok(())
    }

    /// A perspective camera's direction (eye towards `look_at`) and `view_width` (the image's
    /// width at the `look_at` distance, for an image `aspect` = width / height) from its eye,
    /// `look_at`, `up` and field of view; `[look_at, up, eye]` name what a failure blames (the
    /// file's keys, or the command line's flags).
    pub(super) fn aim(
        &self,
        camera: &mut CameraSpec,
        aspect: f64,
        [look_at_key, up_key, eye_key]: [&str; 3],
    ) -> Result<(), SceneError> {
        let Projection::Perspective {
            look_at, fov_deg, ..
        } = camera.projection
        else {
            return Ok(());
        };
        let eye = camera.center;
        let d = [
            look_at[0] - eye[0],
            look_at[1] - eye[1],
            look_at[2] - eye[2],
        ];
        let distance = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if distance == 0.0 {
            return Err(self.err(
                look_at_key,
                format!(
                    "expected a point other than {eye_key} ({eye:?}): the view has no direction"
                ),
            ));
        }
        let direction = d.map(|c| c / distance);
        self.not_parallel(
            up_key,
            camera.up,
            direction,
            "the view (eye towards look_at)",
        )?;
        camera.direction = direction;
        camera.view_width = 2.0 * distance * (0.5 * fov_deg).to_radians().tan() * aspect;
        Ok(())
    }
}
