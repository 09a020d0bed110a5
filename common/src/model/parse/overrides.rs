//! What the command line may change after a scene is read (camera values, then any value an
//! override touched), checked by the same rules as the file's own values.

use super::*;

impl Scene {
    /// Overrides camera values (command line): the direction is normalised and checked against
    /// `up` like the file's, the centre must be finite and the view width positive.
    pub fn override_camera(
        &mut self,
        direction: Option<[f64; 3]>,
        center: Option<[f64; 3]>,
        view_width: Option<f64>,
    ) -> Result<(), SceneError> {
        let v = Validator { file: &self.source };
        if self.camera.is_perspective() {
            let flag = [
                (direction.is_some(), "--camera-direction"),
                (center.is_some(), "--camera-center"),
                (view_width.is_some(), "--view-width"),
            ]
            .into_iter()
            .find_map(|(given, flag)| given.then_some(flag));
            if let Some(flag) = flag {
                return Err(v.err(
                    flag,
                    "an orthographic camera's flag; this scene's camera is perspective \
                     (camera.projection): use --eye, --look-at and --fov",
                ));
            }
        }
        if let Some(d) = direction {
            let d = v.unit_vector("--camera-direction", d)?;
            let u = self.camera.up;
            let cross = [
                d[1] * u[2] - d[2] * u[1],
                d[2] * u[0] - d[0] * u[2],
                d[0] * u[1] - d[1] * u[0],
            ];
            if (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt() < 1e-6 {
                return Err(v.err(
                    "--camera-direction",
                    "expected a direction not parallel to camera.up",
                ));
            }
            self.camera.direction = d;
            // A world-space light stays put: its tilt follows the camera.
            for i in 0..self.lights.len() {
                if let Some(world) = self.lights[i].world {
                    let after = " after --camera-direction";
                    v.place_light(i, &mut self.lights[i], world, &self.camera, after)?;
                }
            }
        }
        if let Some(c) = center {
            self.camera.center = v.bounded3("--camera-center", c, MAX_WORLD)?;
        }
        if let Some(w) = view_width {
            self.camera.view_width = v.length("--view-width", w)?;
        }
        Ok(())
    }

    /// Overrides a perspective camera's eye, `look_at` and vertical field of view (command
    /// line), checked as the file's are; world-space lights stay put. Refused on an orthographic
    /// camera.
    pub fn override_perspective(
        &mut self,
        eye: Option<[f64; 3]>,
        look_at: Option<[f64; 3]>,
        fov_deg: Option<f64>,
    ) -> Result<(), SceneError> {
        let v = Validator { file: &self.source };
        let Projection::Perspective {
            look_at: ref mut target,
            fov_deg: ref mut fov,
            ..
        } = self.camera.projection
        else {
            let flag = [
                (eye.is_some(), "--eye"),
                (look_at.is_some(), "--look-at"),
                (fov_deg.is_some(), "--fov"),
            ]
            .into_iter()
            .find_map(|(given, flag)| given.then_some(flag));
            return match flag {
                Some(flag) => Err(v.err(
                    flag,
                    "a perspective camera's flag; this scene's camera is orthographic \
                     (camera.projection): use --camera-direction, --camera-center and --view-width",
                )),
                None => Ok(()),
            };
        };
        if let Some(p) = look_at {
            *target = v.bounded3("--look-at", p, MAX_WORLD)?;
        }
        if let Some(f) = fov_deg {
            *fov = v.fov("--fov", f)?;
        }
        if let Some(e) = eye {
            self.camera.center = v.bounded3("--eye", e, MAX_WORLD)?;
        }
        if eye.is_none() && look_at.is_none() && fov_deg.is_none() {
            return Ok(());
        }
        let aspect = f64::from(self.image.width) / f64::from(self.image.height);
        let look_at_key = if look_at.is_some() {
            "--look-at"
        } else {
            "camera.look_at"
        };
        let eye_key = if eye.is_some() { "--eye" } else { "camera.eye" };
        v.aim(
            &mut self.camera,
            aspect,
            [look_at_key, "camera.up", eye_key],
        )?;
        // A world-space light stays put: its tilt follows the camera.
        for i in 0..self.lights.len() {
            if let Some(world) = self.lights[i].world {
                let after = " after --eye/--look-at";
                v.place_light(i, &mut self.lights[i], world, &self.camera, after)?;
            }
        }
        Ok(())
    }

    /// Re-checks the values that command-line overrides may have changed.
    pub fn revalidate(&self) -> Result<(), SceneError> {
        let v = Validator { file: &self.source };
        v.image_size(self.image.width, self.image.height)?;
        v.exposure(self.image.exposure)?;
        match self.sweep.slabs {
            SlabSpec::Count(n) => v.slab_count(n)?,
            SlabSpec::Distance(d) => {
                v.length("sweep.slab_distance", d)?;
            }
            SlabSpec::Auto => {}
        }
        if self.sweep.penumbra == Penumbra::Iterated && self.sweep.optimal_distance.is_none() {
            return Err(v.err(
                "sweep.optimal_distance",
                "missing: the iterated penumbra needs the distance d1 (world units) at which its \
                 shadows are right (or use the distance penumbra, which needs none)",
            ));
        }
        v.light_resolution(self.sweep.light_resolution)?;
        Ok(())
    }
}
