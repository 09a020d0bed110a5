//! Rasterizer set-up shared by the CPU and GPU LDI builders.
//!
//! Every triangle is projected to pixel space on the host in f64, its vertices snapped to fixed
//! point with [`SUBPIXEL_BITS`] fractional bits, and oriented to positive area. Coverage of pixel
//! centres is then decided by exact integer edge functions with the top-left rule, so a pixel
//! centre on an edge shared by two triangles is covered by exactly one of them. The depth of a
//! fragment is the triangle's plane evaluated at the pixel centre in f32 in a fixed order
//! ([`TriangleSetup::depth_at`]), relative to a reference pixel inside the triangle's box. In
//! perspective the plane is the inverse depth `1/z` (affine in pixel coordinates, as depth is
//! not) and a fragment's depth is `1 / plane − origin` ([`RasterSetup::fragment_depth`]).

use glam::DVec3;

use crate::prepare::camera::Camera;
use crate::prepare::guard::GuardBand;

/// Fractional bits of the fixed-point vertex coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
/// One pixel in fixed point.
pub const FIXED_ONE: i64 = 1 << SUBPIXEL_BITS;
/// Vertices must project within this many pixels of the grid origin: keeps every edge-function
/// product below 2^61, so i64 arithmetic is exact.
pub const COORD_LIMIT_PX: f64 = (1u64 << 21) as f64;

/// One triangle, ready to rasterize.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleSetup {
    /// Fixed-point grid coordinates of the vertices, ordered so that the area is positive.
    pub v: [[i32; 2]; 3],
    /// Grid pixel range that may be covered: x0, y0, x1, y1 inclusive (clipped to the grid).
    pub bbox: [i32; 4],
    /// Plane depth at the centre of pixel (bbox x0, bbox y0), relative to the slab origin.
    pub depth_ref: f32,
    /// Plane depth change per pixel in x.
    pub depth_dx: f32,
    /// Plane depth change per pixel in y.
    pub depth_dy: f32,
    /// Mesh index (scene order).
    pub mesh: u32,
    /// Whether the outward normal faces the camera.
    pub front_facing: bool,
    /// Outward unit normal in camera space.
    pub normal: [f32; 3],
}

/// Whether an edge with direction (dx, dy) (fixed point, positive-area orientation, y down)
/// is a top or left edge: those own the pixel centres that lie exactly on them.
#[inline(always)]
pub fn is_top_left(dx: i64, dy: i64) -> bool {
    dy < 0 || (dy == 0 && dx > 0)
}

impl TriangleSetup {
    /// The edge function of edge k (from vertex k to k+1) at a fixed-point point, and its bias
    /// (0 for top-left edges, −1 otherwise) so that "covered" is `e + bias >= 0`, i.e. `e > 0`
    /// or (`e == 0` and top-left).
    #[inline(always)]
    pub fn edge(&self, k: usize, px: i64, py: i64) -> i64 {
        let a = self.v[k];
        let b = self.v[(k + 1) % 3];
        let (dx, dy) = (i64::from(b[0] - a[0]), i64::from(b[1] - a[1]));
        dx * (py - i64::from(a[1])) - dy * (px - i64::from(a[0]))
    }

    /// The tie-breaking bias of edge k (see [`TriangleSetup::edge`]).
    #[inline(always)]
    pub fn edge_bias(&self, k: usize) -> i64 {
        let a = self.v[k];
        let b = self.v[(k + 1) % 3];
        if is_top_left(i64::from(b[0] - a[0]), i64::from(b[1] - a[1])) {
            0
        } else {
            -1
        }
    }

    /// Whether the centre of grid pixel (i, j) is covered.
    pub fn covers(&self, i: i32, j: i32) -> bool {
        let px = i64::from(i) * FIXED_ONE + FIXED_ONE / 2;
        let py = i64::from(j) * FIXED_ONE + FIXED_ONE / 2;
        (0..3).all(|k| self.edge(k, px, py) + self.edge_bias(k) >= 0)
    }

    /// The fragment depth at grid pixel (i, j): `(depth_ref + depth_dx·Δi) + depth_dy·Δj` in f32.
    #[inline(always)]
    pub fn depth_at(&self, i: i32, j: i32) -> f32 {
        let di = (i - self.bbox[0]) as f32;
        let dj = (j - self.bbox[1]) as f32;
        let a = self.depth_dx * di;
        let b = self.depth_dy * dj;
        (self.depth_ref + a) + b
    }
}

/// Why a triangle cannot be rasterized.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RasterError {
    /// Perspective: a vertex lies at or behind the eye (view depth ≤ 0), where it has no pixel.
    #[error(
        "mesh {mesh} triangle {triangle}: a vertex at view depth {depth:.6e}, at or behind the \
         perspective camera's eye; move camera.eye so that every mesh lies in front of it"
    )]
    BehindEye {
        /// Mesh index.
        mesh: usize,
        /// Triangle index within the mesh.
        triangle: usize,
        /// The vertex's view depth.
        depth: f64,
    },
    /// A vertex projects too far from the image for exact 64-bit edge functions.
    #[error(
        "mesh {mesh} triangle {triangle}: a vertex projects to pixel ({x:.0}, {y:.0}), beyond the \
         rasterizer's ±{limit} px range; widen camera.view_width or move the mesh closer to the view"
    )]
    OutOfRange {
        /// Mesh index.
        mesh: usize,
        /// Triangle index within the mesh.
        triangle: usize,
        /// Projected x.
        x: f64,
        /// Projected y.
        y: f64,
        /// The limit in pixels.
        limit: f64,
    },
}

/// All triangles of a scene, set up for a pixel grid of the image plus a guard band.
#[derive(Clone, Debug, PartialEq)]
pub struct RasterSetup {
    /// Grid width (image width + left and right guard band).
    pub width: u32,
    /// Grid height (image height + top and bottom guard band).
    pub height: u32,
    /// Guard band in pixels, per side: image pixel (x, y) is grid pixel (x + left, y + top).
    pub guard: GuardBand,
    /// Triangles that may cover a pixel centre, in scene order; the index is the sort tie-breaker.
    pub triangles: Vec<TriangleSetup>,
    /// Triangles whose snapped area is zero (they cover nothing).
    pub zero_area: usize,
    /// The meshes that take part in the parity test (bit i: mesh i): the closed ones. A clear
    /// bit is an open mesh, rendered as a thin shell: its fragments are surface crossings that
    /// toggle no inside bit (docs/scene-format.md, "Open meshes"). All set by [`RasterSetup::new`];
    /// the scene's geometry clears the open meshes' bits.
    pub parity_meshes: u32,
    /// Perspective: every triangle's plane is the inverse view depth, and a fragment's depth
    /// is `1 / plane − origin` with this origin (the sweep's first depth, in f32); `None` for an
    /// orthographic camera, whose planes are the depth relative to the origin.
    pub perspective_origin: Option<f32>,
}

impl RasterSetup {
    /// The depth of `tri`'s fragment at grid pixel (i, j), relative to the sweep's origin:
    /// [`TriangleSetup::depth_at`], or in perspective `1 / depth_at − origin` (in f32, the GPU's
    /// order).
    #[inline(always)]
    pub fn fragment_depth(&self, tri: &TriangleSetup, i: i32, j: i32) -> f32 {
        let plane = tri.depth_at(i, j);
        match self.perspective_origin {
            None => plane,
            Some(origin) => 1.0 / plane - origin,
        }
    }
}

impl RasterSetup {
    /// Sets up every triangle of every mesh; depths are relative to `z_origin` (camera depth;
    /// perspective: [`RasterSetup::fragment_depth`]).
    pub fn new(
        camera: &Camera,
        guard: GuardBand,
        meshes: &[(&[DVec3], &[[u32; 3]])],
        z_origin: f64,
    ) -> Result<RasterSetup, RasterError> {
        let (width, height) = guard.grid(camera.width, camera.height);
        let (gx, gy) = (f64::from(guard.left), f64::from(guard.top));
        let perspective = camera.focal_px.is_some();
        let mut triangles = Vec::new();
        let mut zero_area = 0;
        for (mesh, (positions, tris)) in meshes.iter().enumerate() {
            let projected: Vec<DVec3> = positions.iter().map(|p| camera.to_pixel(*p)).collect();
            for (t, tri) in tris.iter().enumerate() {
                if perspective
                    && let Some(z) = tri
                        .iter()
                        .map(|&v| projected[v as usize].z)
                        .find(|z| *z <= 0.0)
                {
                    return Err(RasterError::BehindEye {
                        mesh,
                        triangle: t,
                        depth: z,
                    });
                }
                let mut fixed = [[0i64; 2]; 3];
                let mut depth = [0f64; 3];
                for k in 0..3 {
                    let p = projected[tri[k] as usize];
                    let (x, y) = (p.x + gx, p.y + gy);
                    if !(x.abs() < COORD_LIMIT_PX && y.abs() < COORD_LIMIT_PX) {
                        return Err(RasterError::OutOfRange {
                            mesh,
                            triangle: t,
                            x: p.x,
                            y: p.y,
                            limit: COORD_LIMIT_PX,
                        });
                    }
                    fixed[k] = [
                        (x * FIXED_ONE as f64).round() as i64,
                        (y * FIXED_ONE as f64).round() as i64,
                    ];
                    // Perspective: the inverse depth, whose plane is affine in pixels.
                    depth[k] = if perspective {
                        1.0 / p.z
                    } else {
                        p.z - z_origin
                    };
                }
                let area = (fixed[1][0] - fixed[0][0]) * (fixed[2][1] - fixed[0][1])
                    - (fixed[1][1] - fixed[0][1]) * (fixed[2][0] - fixed[0][0]);
                if area == 0 {
                    zero_area += 1;
                    continue;
                }
                // Positive area in (x right, y down) means the outward normal points away.
                let front_facing = area < 0;
                if front_facing {
                    fixed.swap(1, 2);
                    depth.swap(1, 2);
                }
                let lo = |k: usize| fixed.iter().map(|v| v[k]).min().unwrap_or(0);
                let hi = |k: usize| fixed.iter().map(|v| v[k]).max().unwrap_or(0);
                // Pixel i's centre is at i·ONE + ONE/2: the first centre ≥ lo and last ≤ hi.
                let first = |v: i64| (v - FIXED_ONE / 2 + FIXED_ONE - 1).div_euclid(FIXED_ONE);
                let last = |v: i64| (v - FIXED_ONE / 2).div_euclid(FIXED_ONE);
                let x0 = first(lo(0)).max(0);
                let y0 = first(lo(1)).max(0);
                let x1 = last(hi(0)).min(i64::from(width) - 1);
                let y1 = last(hi(1)).min(i64::from(height) - 1);
                if x0 > x1 || y0 > y1 {
                    continue;
                }
                let (depth_ref, depth_dx, depth_dy) = plane(&fixed, &depth, x0, y0);
                let w = |i: usize| positions[tri[i] as usize];
                let n = (w(1) - w(0)).cross(w(2) - w(0));
                let n = DVec3::new(
                    n.dot(camera.right),
                    n.dot(camera.down),
                    n.dot(camera.forward),
                );
                let n = n.normalize_or_zero();
                triangles.push(TriangleSetup {
                    v: fixed.map(|v| [v[0] as i32, v[1] as i32]),
                    bbox: [x0 as i32, y0 as i32, x1 as i32, y1 as i32],
                    depth_ref,
                    depth_dx,
                    depth_dy,
                    mesh: mesh as u32,
                    front_facing,
                    normal: [n.x as f32, n.y as f32, n.z as f32],
                });
            }
        }
        Ok(RasterSetup {
            width,
            height,
            guard,
            triangles,
            zero_area,
            parity_meshes: u32::MAX,
            perspective_origin: perspective.then_some(z_origin as f32),
        })
    }
}

/// The plane through the snapped vertices: depth at the centre of pixel (x0, y0) and slopes.
fn plane(fixed: &[[i64; 2]; 3], depth: &[f64; 3], x0: i64, y0: i64) -> (f32, f32, f32) {
    let s = 1.0 / FIXED_ONE as f64;
    let x: Vec<f64> = fixed.iter().map(|v| v[0] as f64 * s).collect();
    let y: Vec<f64> = fixed.iter().map(|v| v[1] as f64 * s).collect();
    let d = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
    let (dz1, dz2) = (depth[1] - depth[0], depth[2] - depth[0]);
    let p = (dz1 * (y[2] - y[0]) - dz2 * (y[1] - y[0])) / d;
    let q = (dz2 * (x[1] - x[0]) - dz1 * (x[2] - x[0])) / d;
    let cx = x0 as f64 + 0.5;
    let cy = y0 as f64 + 0.5;
    let z = depth[0] + p * (cx - x[0]) + q * (cy - y[0]);
    (z as f32, p as f32, q as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(v: [[i32; 2]; 3]) -> TriangleSetup {
        TriangleSetup {
            v,
            bbox: [0, 0, 8, 8],
            depth_ref: 0.0,
            depth_dx: 0.0,
            depth_dy: 0.0,
            mesh: 0,
            front_facing: true,
            normal: [0.0, 0.0, -1.0],
        }
    }

    #[test]
    fn shared_edges_through_pixel_centres_are_covered_exactly_once() {
        // A square split along its diagonal, with vertices on pixel centres: every centre on the
        // diagonal must be covered by exactly one of the two triangles.
        let c = |i: i32| i * 256 + 128;
        let a = tri([[c(0), c(0)], [c(4), c(0)], [c(4), c(4)]]);
        let b = tri([[c(0), c(0)], [c(4), c(4)], [c(0), c(4)]]);
        for j in 0..5 {
            for i in 0..5 {
                let n = a.covers(i, j) as u32 + b.covers(i, j) as u32;
                // Top and left edges own their centres; right and bottom ones do not.
                let expect = if i == 4 || j == 4 { 0 } else { 1 };
                assert_eq!(n, expect, "pixel {i},{j}");
            }
        }
    }
}
