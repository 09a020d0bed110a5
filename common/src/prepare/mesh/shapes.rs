//! Procedural shapes (box, icosphere, torus, cylinder) and rigid transforms.

use std::collections::HashMap;
use std::f64::consts::PI;

use glam::{DMat3, DVec3};

use super::*;

impl TriMesh {
    /// Axis-aligned box centred at the origin with full extents `size`: 8 vertices, 12 outward triangles.
    pub fn unit_box(size: DVec3) -> TriMesh {
        let h = size * 0.5;
        // Vertex index = x | y << 1 | z << 2, bit set = positive side.
        let positions = (0..8u32)
            .map(|i| {
                DVec3::new(
                    if i & 1 != 0 { h.x } else { -h.x },
                    if i & 2 != 0 { h.y } else { -h.y },
                    if i & 4 != 0 { h.z } else { -h.z },
                )
            })
            .collect();
        // Quads counter-clockwise seen from outside.
        const QUADS: [[u32; 4]; 6] = [
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
        ];
        let triangles = QUADS
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        TriMesh {
            positions,
            triangles,
        }
    }

    /// Icosphere of `radius` centred at the origin: closed, outward, 20·4^s triangles, 10·4^s+2 vertices.
    pub fn icosphere(radius: f64, subdivisions: u32) -> TriMesh {
        let phi = (1.0 + 5.0_f64.sqrt()) * 0.5;
        let mut unit: Vec<DVec3> = [
            (-1.0, phi, 0.0),
            (1.0, phi, 0.0),
            (-1.0, -phi, 0.0),
            (1.0, -phi, 0.0),
            (0.0, -1.0, phi),
            (0.0, 1.0, phi),
            (0.0, -1.0, -phi),
            (0.0, 1.0, -phi),
            (phi, 0.0, -1.0),
            (phi, 0.0, 1.0),
            (-phi, 0.0, -1.0),
            (-phi, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
        .collect();
        let mut tris: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        // Orient every face outward (the solid is convex and contains the origin).
        for t in &mut tris {
            let [a, b, c] = t.map(|i| unit[i as usize]);
            if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
                t.swap(1, 2);
            }
        }
        for _ in 0..subdivisions {
            let mut midpoints: HashMap<(u32, u32), u32> =
                HashMap::with_capacity(tris.len() * 3 / 2);
            let mut next = Vec::with_capacity(tris.len() * 4);
            let mut mid = |a: u32, b: u32| -> u32 {
                let key = (a.min(b), a.max(b));
                *midpoints.entry(key).or_insert_with(|| {
                    let p = ((unit[a as usize] + unit[b as usize]) * 0.5).normalize();
                    unit.push(p);
                    (unit.len() - 1) as u32
                })
            };
            for &[a, b, c] in &tris {
                let ab = mid(a, b);
                let bc = mid(b, c);
                let ca = mid(c, a);
                next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            tris = next;
        }
        TriMesh {
            positions: unit.into_iter().map(|p| p * radius).collect(),
            triangles: tris,
        }
    }

    /// Torus around the z axis: `segments` around the major circle (at least 3), max(3, segments/2) around the tube; closed genus 1, outward.
    pub fn torus(major: f64, minor: f64, segments: u32) -> TriMesh {
        let n = segments.max(3);
        let m = (segments / 2).max(3);
        let mut positions = Vec::with_capacity(n as usize * m as usize);
        for i in 0..n {
            let theta = 2.0 * PI * f64::from(i) / f64::from(n);
            let (st, ct) = theta.sin_cos();
            for j in 0..m {
                let phi = 2.0 * PI * f64::from(j) / f64::from(m);
                let (sp, cp) = phi.sin_cos();
                let rho = major + minor * cp;
                positions.push(DVec3::new(rho * ct, rho * st, minor * sp));
            }
        }
        let idx = |i: u32, j: u32| (i % n) * m + (j % m);
        let mut triangles = Vec::with_capacity(2 * n as usize * m as usize);
        for i in 0..n {
            for j in 0..m {
                // d(theta) x d(phi) points away from the tube's core circle.
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        TriMesh {
            positions,
            triangles,
        }
    }

    /// A closed cylinder around the z axis, centred at the origin: `radius`, full `height`,
    /// `segments` around (at least 3); caps are fans around a centre vertex; outward winding.
    pub fn cylinder(radius: f64, height: f64, segments: u32) -> TriMesh {
        let n = segments.max(3);
        let h = 0.5 * height;
        let mut positions = Vec::with_capacity(2 * n as usize + 2);
        for z in [-h, h] {
            for i in 0..n {
                let (s, c) = (2.0 * PI * f64::from(i) / f64::from(n)).sin_cos();
                positions.push(DVec3::new(radius * c, radius * s, z));
            }
        }
        let (bottom, top) = (2 * n, 2 * n + 1);
        positions.push(DVec3::new(0.0, 0.0, -h));
        positions.push(DVec3::new(0.0, 0.0, h));
        let mut triangles = Vec::with_capacity(4 * n as usize);
        for i in 0..n {
            let j = (i + 1) % n;
            // Side quad: counter-clockwise seen from outside.
            triangles.push([i, j, n + j]);
            triangles.push([i, n + j, n + i]);
            // Caps: the bottom faces −z, the top +z.
            triangles.push([bottom, j, i]);
            triangles.push([top, n + i, n + j]);
        }
        TriMesh {
            positions,
            triangles,
        }
    }

    /// Returns `p' = R·(scale·p) + t` with `R = Rz·Ry·Rx` (degrees, x applied first); winding is flipped when `scale < 0`.
    pub fn transformed(&self, scale: f64, rotate_deg: DVec3, translate: DVec3) -> TriMesh {
        let r = DMat3::from_rotation_z(rotate_deg.z.to_radians())
            * DMat3::from_rotation_y(rotate_deg.y.to_radians())
            * DMat3::from_rotation_x(rotate_deg.x.to_radians());
        let positions = self
            .positions
            .iter()
            .map(|&p| r * (p * scale) + translate)
            .collect();
        let triangles = if scale < 0.0 {
            self.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect()
        } else {
            self.triangles.clone()
        };
        TriMesh {
            positions,
            triangles,
        }
    }
}
