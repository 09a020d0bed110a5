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
        Ok(())
    }
}
