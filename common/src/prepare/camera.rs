//! The camera: world points to pixel coordinates and view depth, orthographic or perspective.
//!
//! Camera space: x right, y down (image rows), z forward. Pixel (i, j) has its centre at
//! (i + 0.5, j + 0.5) in pixel coordinates; pixel coordinates are camera x/y divided by the pixel
//! size (perspective: x/z and y/z times the focal length in pixels) and offset so that the view
//! axis passes through the image centre. A guard band of `g` pixels extends the pixel grid by `g`
//! on every side: pixel coordinates then start at `-g`.

use glam::DVec3;

use crate::model::scene::{CameraSpec, ImageSpec, Projection};

/// A camera mapping world points to pixel coordinates and camera depth (view depth: the
/// distance along the view direction, from the view's centre or, in perspective, the eye).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World direction of camera +x (image right).
    pub right: DVec3,
    /// World direction of camera +y (image down).
    pub down: DVec3,
    /// World direction of camera +z (view direction).
    pub forward: DVec3,
    /// World point at the image centre (depth 0); perspective: the eye.
    pub center: DVec3,
    /// Pixel size in world units; perspective: a pixel's footprint at the `look_at` distance.
    pub pixel_size: f64,
    /// Perspective: the focal length in pixels, `(height / 2) / tan(fov / 2)`; `None` for an
    /// orthographic camera.
    pub focal_px: Option<f64>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// Builds the camera basis from a validated camera spec and image size.
    pub fn new(spec: &CameraSpec, image: &ImageSpec) -> Camera {
        let [right, down, forward] = spec.basis();
        let center = DVec3::from(spec.center);
        let (pixel_size, focal_px) = match spec.projection {
            Projection::Orthographic => (spec.view_width / f64::from(image.width), None),
            Projection::Perspective {
                look_at, fov_deg, ..
            } => {
                let focal = 0.5 * f64::from(image.height) / (0.5 * fov_deg).to_radians().tan();
                let distance = (DVec3::from(look_at) - center).length();
                (distance / focal, Some(focal))
            }
        };
        Camera {
            right,
            down,
            forward,
            center,
            pixel_size,
            focal_px,
            width: image.width,
            height: image.height,
        }
    }

    /// An orthographic camera's pixel size, or a perspective camera's pixel footprint at view
    /// depth `z` (`z / focal_px`).
    pub fn pixel_size_at(&self, z: f64) -> f64 {
        self.focal_px.map_or(self.pixel_size, |f| z / f)
    }

    /// Camera-space coordinates (x right, y down, z forward) of a world point.
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        let d = p - self.center;
        DVec3::new(d.dot(self.right), d.dot(self.down), d.dot(self.forward))
    }

    /// Pixel coordinates (x, y) and camera depth of a world point (perspective: a point at depth
    /// `z > 0`; nearer points have no pixel).
    pub fn to_pixel(&self, p: DVec3) -> DVec3 {
        let c = self.to_camera(p);
        let s = self.pixel_size_at(c.z);
        DVec3::new(
            c.x / s + f64::from(self.width) * 0.5,
            c.y / s + f64::from(self.height) * 0.5,
            c.z,
        )
    }

    /// The world point at pixel coordinates (x, y) and camera depth z.
    pub fn pixel_to_world(&self, x: f64, y: f64, z: f64) -> DVec3 {
        let s = self.pixel_size_at(z);
        let cx = (x - f64::from(self.width) * 0.5) * s;
        let cy = (y - f64::from(self.height) * 0.5) * s;
        self.center + self.right * cx + self.down * cy + self.forward * z
    }

    /// Slab-grid coordinates (x, y) and camera depth of a world point: camera x and y over
    /// `pixel_size`, offset to the image centre, at every depth. The slab planes' one frame in
    /// which a directional light travels in straight lines of one slope: an orthographic
    /// camera's pixels; in perspective, its pixels at the `look_at` distance.
    pub fn to_grid(&self, p: DVec3) -> DVec3 {
        let c = self.to_camera(p);
        DVec3::new(
            c.x / self.pixel_size + f64::from(self.width) * 0.5,
            c.y / self.pixel_size + f64::from(self.height) * 0.5,
            c.z,
        )
    }

    /// The world point at slab-grid coordinates (x, y) and camera depth z ([`Camera::to_grid`]).
    pub fn grid_to_world(&self, x: f64, y: f64, z: f64) -> DVec3 {
        let cx = (x - f64::from(self.width) * 0.5) * self.pixel_size;
        let cy = (y - f64::from(self.height) * 0.5) * self.pixel_size;
        self.center + self.right * cx + self.down * cy + self.forward * z
    }

    /// Where the view ray through pixel coordinates (x, y) is at camera depth z, in slab-grid
    /// coordinates ([`Camera::to_grid`]): (x, y) itself for an orthographic camera; in
    /// perspective the pixel's offset from the centre scaled by `z / (focal_px · pixel_size)`.
    pub fn pixel_to_grid(&self, x: f64, y: f64, z: f64) -> (f64, f64) {
        let Some(f) = self.focal_px else {
            return (x, y);
        };
        let (cx, cy) = (f64::from(self.width) * 0.5, f64::from(self.height) * 0.5);
        let zoom = z / (f * self.pixel_size);
        (cx + (x - cx) * zoom, cy + (y - cy) * zoom)
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
                projection: Default::default(),
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
