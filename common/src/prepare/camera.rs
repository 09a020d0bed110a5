//! The orthographic camera and the slab range.
//!
//! Camera space: x right, y down (image rows), z forward. Pixel (i, j) has its centre at
//! (i + 0.5, j + 0.5) in pixel coordinates; pixel coordinates are camera x/y divided by the pixel
//! size and offset so that the camera centre is the image centre. A guard band of `g` pixels
//! extends the pixel grid by `g` on every side: pixel coordinates then start at `-g`.

use glam::DVec3;

use crate::model::scene::{CameraSpec, ImageSpec};

/// An orthographic camera mapping world points to pixel coordinates and camera depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World direction of camera +x (image right).
    pub right: DVec3,
    /// World direction of camera +y (image down).
    pub down: DVec3,
    /// World direction of camera +z (view direction).
    pub forward: DVec3,
    /// World point at the image centre (depth 0).
    pub center: DVec3,
    /// Pixel size in world units.
    pub pixel_size: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// Builds the camera basis from a validated camera spec and image size.
    pub fn new(spec: &CameraSpec, image: &ImageSpec) -> Camera {
        let [right, down, forward] = spec.basis();
        Camera {
            right,
            down,
            forward,
            center: DVec3::from(spec.center),
            pixel_size: spec.view_width / f64::from(image.width),
            width: image.width,
            height: image.height,
        }
    }

    /// Camera-space coordinates (x right, y down, z forward) of a world point.
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.center;
        DVec3::new(d.dot(self.right), d.dot(self.down), d.dot(self.forward))
    }

    /// Pixel coordinates (x, y) and camera depth of a world point.
    pub fn to_pixel(&self, p: DVec3) -> DVec3 {
        let c = self.to_camera(p);
        DVec3::new(
            c.x / self.pixel_size + f64::from(self.width) * 0.5,
            c.y / self.pixel_size + f64::from(self.height) * 0.5,
            c.z,
        )
    }

    /// The world point at pixel coordinates (x, y) and camera depth z.
    pub fn pixel_to_world(&self, x: f64, y: f64, z: f64) -> DVec3 {
        let cx = (x - f64::from(self.width) * 0.5) * self.pixel_size;
        let cy = (y - f64::from(self.height) * 0.5) * self.pixel_size;
        self.center + self.right * cx + self.down * cy + self.forward * z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(direction: [f64; 3], up: [f64; 3]) -> Camera {
        Camera::new(
            &CameraSpec {
                direction,
                up,
                center: [1.0, 2.0, 3.0],
                view_width: 4.0,
            },
            &ImageSpec {
                width: 8,
                height: 4,
                background: [0.0; 3],
                exposure: 0.0,
                tonemap: Default::default(),
            },
        )
    }

    #[test]
    fn basis_is_right_handed_and_up_is_at_the_top() {
        let c = cam([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]);
        assert!((c.right.cross(c.down) - c.forward).length() < 1e-12);
        // A point above the centre lands in the upper half of the image (small row index).
        let p = c.to_pixel(DVec3::new(1.0, 3.0, 3.0));
        assert!(p.y < 2.0);
        assert_eq!(
            c.to_pixel(DVec3::new(1.0, 2.0, 3.0)),
            DVec3::new(4.0, 2.0, 0.0)
        );
        let c2 = cam([1.0, -1.0, 0.3], [0.0, 0.0, 1.0]);
        let w = DVec3::new(0.3, -7.0, 2.5);
        let p = c2.to_pixel(w);
        assert!((c2.pixel_to_world(p.x, p.y, p.z) - w).length() < 1e-12);
    }
}
