//! A perspective eye's view samples for a light travelling towards it (docs/how-it-works.md, "A
//! perspective camera"): the tracer works in the coordinates of the turned-round slab grid (its
//! camera looking back at the eye from the far end, x mirrored, depth `−z`), where such a light
//! comes from behind, and the view samples follow the eye's rays into that grid, as the sweep's
//! eye pass reads it.

use convshadow_common::prepare::raster::RasterSetup;

/// The eye's rays in the turned-round grid's coordinates.
#[derive(Clone, Copy)]
pub struct TurnedEye<'a> {
    /// Image width and height (eye pixels).
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Where the view axis meets the grid, in grid pixel coordinates.
    pub axis: [f64; 2],
    /// Grid pixels per image pixel of offset from the image centre, per unit of view depth.
    pub zoom: f64,
    /// A grid relative depth `z` is the view depth `z_origin − z`.
    pub z_origin: f64,
    /// The crossed triangles' normals, as the turned camera sees them (the view LDI's
    /// triangle indices).
    pub raster: &'a RasterSetup,
}

impl TurnedEye<'_> {
    /// Where the ray through image position (x, y) (pixels, centres at +0.5) is at grid relative
    /// depth `z`: mirrored in x about the axis, scaled by the view depth.
    pub(super) fn point(&self, x: f64, y: f64, z: f64) -> [f64; 3] {
        let depth = self.z_origin - z;
        let (cx, cy) = (f64::from(self.width) * 0.5, f64::from(self.height) * 0.5);
        [
            self.axis[0] + (cx - x) * depth * self.zoom,
            self.axis[1] + (y - cy) * depth * self.zoom,
            z,
        ]
    }

    /// The ray through (x, y) as a line of the grid: its point at relative depth 0 and its
    /// direction per unit of relative depth.
    pub(super) fn line(&self, x: f64, y: f64) -> ([f64; 3], [f64; 3]) {
        let origin = self.point(x, y, 0.0);
        let at_one = self.point(x, y, 1.0);
        (origin, [at_one[0] - origin[0], at_one[1] - origin[1], 1.0])
    }
}
