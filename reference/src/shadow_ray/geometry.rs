//! The tracer's geometry: triangles in slab-grid space, where a shadow ray starts, the
//! Möller–Trumbore intersection and the small vector helpers it uses (f64 throughout).

/// One triangle in grid space: x, y in grid pixels, z in world depth relative to the first slab.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tri {
    pub(super) v0: [f64; 3],
    pub(super) e1: [f64; 3],
    pub(super) e2: [f64; 3],
    pub(super) mesh: u32,
}

/// Where a shadow ray starts, and what it does not count as crossed there.
///
/// The renderer's model at a surface crossing reads the light *arriving at* the surface point:
/// the surface itself does not occlude it (its inside does, where a ray heads into it). So a
/// crossing's rays start on the exact f64 surface under the pixel centre (not at the LDI's f32
/// depth, which is off the surface by its rounding and the vertices' fixed-point snapping, up to
/// ~1e-4 of depth on a surface at 60° to the view) and skip the triangle they start on; a ray
/// heading into the mesh then crosses its far side and is attenuated by the inside, a ray
/// heading out crosses nothing of it. Crossings closer than `tol` are the start met again
/// through f64 rounding (a neighbouring triangle at a shared edge or vertex, a coincident face
/// of a touching mesh) and are ignored too.
#[derive(Clone, Copy, Debug)]
pub(super) struct Start {
    /// Index of the triangle the ray starts on (`u32::MAX`: none).
    pub(super) skip: u32,
    /// Crossings at ray parameters (depth) up to this are not counted.
    pub(super) tol: f64,
}

impl Start {
    /// f64 rounding of a crossing at the start: 2^-30 relative to the depth.
    pub(super) fn rounding(p: [f64; 3]) -> f64 {
        (1.0 + p[2].abs()) * (1.0 / 1_073_741_824.0)
    }

    /// A point off any surface (inside a medium or given exactly).
    pub(super) fn free(p: [f64; 3]) -> Start {
        Start {
            skip: u32::MAX,
            tol: Start::rounding(p),
        }
    }

    /// A point on triangle `tri`, exactly.
    pub(super) fn on(p: [f64; 3], tri: u32) -> Start {
        Start {
            skip: tri,
            tol: Start::rounding(p),
        }
    }

    /// A crossing whose triangle was not found (never seen in the tests; kept for safety): the
    /// LDI's depth, with crossings within 2^-16 (relative) taken for its own surface.
    pub(super) fn near(p: [f64; 3]) -> Start {
        Start {
            skip: u32::MAX,
            tol: (1.0 + p[2].abs()) / 65_536.0,
        }
    }
}

pub(super) fn to_detail_f64(m: &[f32; 12], q: [f64; 3]) -> [f32; 3] {
    let row = |r: usize| {
        f64::from(m[4 * r]) * q[0]
            + f64::from(m[4 * r + 1]) * q[1]
            + f64::from(m[4 * r + 2]) * q[2]
            + f64::from(m[4 * r + 3])
    };
    [row(0) as f32, row(1) as f32, row(2) as f32]
}

pub(super) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Möller–Trumbore: the ray parameter where `o + u·d` meets triangle `t`, if it does.
pub(super) fn intersect(o: [f64; 3], d: [f64; 3], t: &Tri) -> Option<f64> {
    let pv = cross(d, t.e2);
    let det = dot(t.e1, pv);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = sub(o, t.v0);
    let a = dot(tv, pv) * inv;
    if !(0.0..=1.0).contains(&a) {
        return None;
    }
    let qv = cross(tv, t.e1);
    let b = dot(d, qv) * inv;
    if b < 0.0 || a + b > 1.0 {
        return None;
    }
    Some(dot(t.e2, qv) * inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_meets_a_triangle_where_expected() {
        let t = Tri {
            v0: [0.0, 0.0, 2.0],
            e1: [4.0, 0.0, 0.0],
            e2: [0.0, 4.0, 0.0],
            mesh: 0,
        };
        // From (1, 1, 5) towards depth 0 with slope (0.1, 0): meets depth 2 at u = 3.
        let u = intersect([1.0, 1.0, 5.0], [0.1, 0.0, -1.0], &t).unwrap();
        assert!((u - 3.0).abs() < 1e-12);
        assert!(intersect([5.0, 5.0, 5.0], [0.0, 0.0, -1.0], &t).is_none());
    }
}
