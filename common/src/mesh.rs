//! Triangle meshes: procedural shapes, OBJ loading (via `tobj`) and closure analysis.
//!
//! Host geometry is `f64`; the rasterizer snaps vertices to fixed point later. Closure is judged
//! by **position index** after welding vertices with bit-identical positions, because the parity
//! test of the LDI (DESIGN.md §2) needs every edge shared by exactly two consistently wound
//! triangles.

use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::f64::consts::PI;
use std::fmt;
use std::ops::Div;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use glam::{DMat3, DVec3};

/// Indexed triangle mesh in f64 (host geometry is f64; the rasterizer snaps later).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions`; outward normal is `(b-a)×(c-a)`.
    pub triangles: Vec<[u32; 3]>,
}

/// Closure / quality report of a mesh after cleaning.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshReport {
    /// Triangles kept after dropping degenerate ones.
    pub triangles: usize,
    /// Triangles dropped: repeated index, zero area (exactly collinear in f64), or an index out of range.
    pub degenerate_triangles: usize,
    /// Undirected edges used by exactly 1 triangle.
    pub boundary_edges: usize,
    /// Undirected edges used by 3 or more triangles.
    pub nonmanifold_edges: usize,
    /// Manifold edges whose two triangles traverse them in the same direction (inconsistent winding).
    pub flipped_edges: usize,
}

impl MeshReport {
    /// True when there are no boundary, non-manifold or flipped edges.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0 && self.nonmanifold_edges == 0 && self.flipped_edges == 0
    }
}

impl fmt::Display for MeshReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} triangles ({} degenerate dropped), {} boundary edges, {} non-manifold edges, {} flipped edges",
            self.triangles,
            self.degenerate_triangles,
            self.boundary_edges,
            self.nonmanifold_edges,
            self.flipped_edges
        )
    }
}

/// Errors of [`load_obj`]; every message names the file, the line where known, and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{}: cannot read OBJ file (expected a readable Wavefront OBJ file): {source}", .path.display())]
    Io {
        /// File path.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// A line does not follow the OBJ syntax.
    #[error("{}:{line}: expected {expected} in \"{text}\"", .path.display())]
    Syntax {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What was expected there.
        expected: String,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A face line with fewer than 3 vertices.
    #[error("{}:{line}: face has {count} vertex indices, expected at least 3, in \"{text}\"", .path.display())]
    FaceTooShort {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Number of vertex references on the line.
        count: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A face refers to an element (vertex, texture coordinate, normal) that is not defined.
    #[error(
        "{}:{line}: {element} index {index} is out of range (expected {expected}) in \"{text}\"",
        .path.display(),
        expected = index_range_hint(.defined)
    )]
    BadIndex {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// "vertex", "texture coordinate" or "normal".
        element: &'static str,
        /// The index as written in the file (0, too large, or too negative).
        index: i64,
        /// How many such elements were defined before this line.
        defined: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// A vertex with a NaN or infinite coordinate.
    #[error(
        "{}:{line}: vertex {vertex} has a non-finite coordinate (expected finite numbers) in \"{text}\"",
        .path.display()
    )]
    NonFinite {
        /// File path.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// 1-based vertex index, as faces in the file refer to it.
        vertex: usize,
        /// The offending line (trimmed, shortened).
        text: String,
    },
    /// tobj rejected the file and the line could not be located.
    #[error("{}: line unknown: tobj could not parse the file ({source}); expected a valid Wavefront OBJ file", .path.display())]
    Obj {
        /// File path.
        path: PathBuf,
        /// tobj's error.
        source: tobj::LoadError,
    },
    /// The file has no faces.
    #[error("{}: no triangles (expected at least one face line \"f a b c\")", .path.display())]
    NoTriangles {
        /// File path.
        path: PathBuf,
    },
    /// A whole-file inconsistency that has no single line (e.g. too many vertices for u32 indices).
    #[error("{}: {message}", .path.display())]
    Invalid {
        /// File path.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
}

/// Text for the accepted index range when `defined` elements exist.
fn index_range_hint(defined: &usize) -> String {
    let defined = *defined;
    if defined == 0 {
        "an element defined on an earlier line; none is defined yet".to_string()
    } else {
        format!(
            "1..={defined} or -{defined}..=-1, as {defined} are defined before this line; OBJ indices start at 1"
        )
    }
}

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

    /// Drops degenerate triangles (counted), then counts boundary / non-manifold / flipped edges by position index.
    ///
    /// Degenerate: a repeated index, an index out of range, or three exactly collinear
    /// positions (exact predicate on the f64 coordinates). Positions are kept unchanged.
    pub fn analyze(&self) -> (TriMesh, MeshReport) {
        let mut kept = Vec::with_capacity(self.triangles.len());
        let mut degenerate = 0usize;
        for &t in &self.triangles {
            if self.is_degenerate(t) {
                degenerate += 1;
            } else {
                kept.push(t);
            }
        }
        let mut edges = directed_edges(&kept);
        edges.sort_unstable();
        let mut report = MeshReport {
            triangles: kept.len(),
            degenerate_triangles: degenerate,
            ..MeshReport::default()
        };
        for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
            match run.len() {
                1 => report.boundary_edges += 1,
                2 => {
                    if run[0].2 == run[1].2 {
                        report.flipped_edges += 1;
                    }
                }
                _ => report.nonmanifold_edges += 1,
            }
        }
        (
            TriMesh {
                positions: self.positions.clone(),
                triangles: kept,
            },
            report,
        )
    }

    /// Signed volume (positive for a closed outward mesh), summed relative to the bounding-box centre.
    ///
    /// Triangles with an index out of range are skipped. For a closed mesh the result does not
    /// depend on the reference point; using the box centre keeps it accurate far from the origin.
    pub fn signed_volume(&self) -> f64 {
        let (lo, hi) = self.bounds();
        let o = (lo + hi) * 0.5;
        let mut sum = 0.0;
        for t in &self.triangles {
            if let Some([a, b, c]) = self.corners(*t) {
                sum += (a - o).dot((b - o).cross(c - o));
            }
        }
        sum / 6.0
    }

    /// Axis-aligned bounds `(min, max)` of all positions; `(ZERO, ZERO)` for a mesh without positions.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let Some(&first) = self.positions.first() else {
            return (DVec3::ZERO, DVec3::ZERO);
        };
        self.positions
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)))
    }

    /// Euler characteristic V − E + F over referenced vertices, distinct undirected edges and all triangles.
    pub fn euler_characteristic(&self) -> i64 {
        let mut verts: Vec<u32> = self.triangles.iter().flatten().copied().collect();
        verts.sort_unstable();
        verts.dedup();
        let mut edges: Vec<(u32, u32)> = directed_edges(&self.triangles)
            .into_iter()
            .map(|(a, b, _)| (a, b))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        verts.len() as i64 - edges.len() as i64 + self.triangles.len() as i64
    }

    /// The three corner positions of a triangle, or `None` if an index is out of range.
    fn corners(&self, [a, b, c]: [u32; 3]) -> Option<[DVec3; 3]> {
        let p = |i: u32| self.positions.get(i as usize).copied();
        Some([p(a)?, p(b)?, p(c)?])
    }

    /// Repeated index, index out of range, or exactly collinear corners.
    fn is_degenerate(&self, t: [u32; 3]) -> bool {
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            return true;
        }
        match self.corners(t) {
            None => true,
            Some([a, b, c]) => {
                orient2d_is_zero([a.x, a.y], [b.x, b.y], [c.x, c.y])
                    && orient2d_is_zero([a.y, a.z], [b.y, b.z], [c.y, c.z])
                    && orient2d_is_zero([a.z, a.x], [b.z, b.x], [c.z, c.x])
            }
        }
    }
}

/// Undirected edge keys `(min, max, forward)` of every triangle, `forward` = traversed min→max.
fn directed_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32, bool)> {
    let mut edges = Vec::with_capacity(triangles.len() * 3);
    for &[a, b, c] in triangles {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            edges.push((u.min(v), u.max(v), u < v));
        }
    }
    edges
}

// ---------------------------------------------------------------------------------------------
// Exact collinearity (Shewchuk-style expansion arithmetic, no error from rounding).

/// `a + b` as an exact pair `(sum, error)`.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let err = (a - (s - bb)) + (b - bb);
    (s, err)
}

/// Veltkamp's split of `a` into two 26-bit halves whose products are exact.
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `a * b` as an exact pair `(product, error)` by Dekker's algorithm: plain multiplications
/// only (the project uses no fused multiply-add anywhere); exact unless it under/overflows.
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = al * bl - (((p - ah * bh) - al * bh) - ah * bl);
    (p, err)
}

/// True iff the 2D orientation determinant of `a, b, c` is exactly zero.
fn orient2d_is_zero(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    let (l1, l2) = (b[0] - a[0], c[1] - a[1]);
    let (r1, r2) = (b[1] - a[1], c[0] - a[0]);
    let (l, r) = (l1 * l2, r1 * r2);
    let det = l - r;
    // Shewchuk's ccwerrboundA: beyond it, the floating-point sign is certain.
    let eps = f64::EPSILON * 0.5;
    let bound = (3.0 + 16.0 * eps) * eps * (l.abs() + r.abs());
    if det.abs() > bound {
        return false;
    }
    // Exact: each difference is an exact two-term expansion, products of terms are exact pairs.
    let d = |p: f64, q: f64| two_sum(p, -q);
    let (bx, bxe) = d(b[0], a[0]);
    let (cy, cye) = d(c[1], a[1]);
    let (by, bye) = d(b[1], a[1]);
    let (cx, cxe) = d(c[0], a[0]);
    let mut expansion: Vec<f64> = Vec::with_capacity(32);
    let mut add = |x: f64| {
        // Grow a nonoverlapping expansion (increasing magnitude), dropping zeros.
        let mut q = x;
        let mut out = Vec::with_capacity(expansion.len() + 1);
        for &e in &expansion {
            let (s, err) = two_sum(q, e);
            if err != 0.0 {
                out.push(err);
            }
            q = s;
        }
        if q != 0.0 {
            out.push(q);
        }
        expansion = out;
    };
    for (p, q, sign) in [
        (bx, cy, 1.0),
        (bx, cye, 1.0),
        (bxe, cy, 1.0),
        (bxe, cye, 1.0),
        (by, cx, -1.0),
        (by, cxe, -1.0),
        (bye, cx, -1.0),
        (bye, cxe, -1.0),
    ] {
        let (h, e) = two_product(p, q);
        add(sign * h);
        add(sign * e);
    }
    expansion.is_empty()
}

// ---------------------------------------------------------------------------------------------
// OBJ loading.

/// Longest line excerpt quoted in an error message.
const MAX_QUOTE: usize = 120;

/// The line trimmed and shortened for quoting in a message.
fn quote(line: &str) -> String {
    let t = line.trim();
    if t.chars().count() <= MAX_QUOTE {
        t.to_string()
    } else {
        let mut s: String = t.chars().take(MAX_QUOTE).collect();
        s.push('…');
        s
    }
}

/// What the validating scan learned about a file that tobj needs to be told.
struct ScanSummary {
    /// Number of face lines.
    faces: usize,
    /// Whether the file has `l` (polyline) elements, which tobj would turn into triangles.
    has_polylines: bool,
}

/// The float type tobj parses into (f32, or f64 with tobj's `use_f64` feature), as used by the scan.
trait ObjFloat: FromStr + Copy + Into<f64> + Div<Output = Self> {}
impl<T: FromStr + Copy + Into<f64> + Div<Output = T>> ObjFloat for T {}

/// Line-by-line validation with tobj's acceptance rules plus ours; errors carry the line number.
///
/// `_like` only fixes `T` to tobj's float type, so finiteness is judged on the values tobj keeps.
fn scan_obj<T: ObjFloat>(path: &Path, bytes: &[u8], _like: &[T]) -> Result<ScanSummary, MeshError> {
    let mut n_v = 0usize;
    let mut n_vt = 0usize;
    let mut n_vn = 0usize;
    let mut summary = ScanSummary {
        faces: 0,
        has_polylines: false,
    };
    let mut lines = bytes.split(|&b| b == b'\n').enumerate().peekable();
    while let Some((i, raw)) = lines.next() {
        let line_no = i + 1;
        if raw.is_empty() && lines.peek().is_none() {
            break; // trailing newline
        }
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let syntax = |expected: String, text: &str| MeshError::Syntax {
            path: path.to_path_buf(),
            line: line_no,
            expected,
            text: quote(text),
        };
        let line = match std::str::from_utf8(raw) {
            Ok(s) => s,
            Err(_) => {
                return Err(syntax(
                    "UTF-8 text".to_string(),
                    &String::from_utf8_lossy(raw),
                ));
            }
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut xyz = [None::<T>; 3];
                for (k, slot) in xyz.iter_mut().enumerate() {
                    let axis = ["x", "y", "z"][k];
                    match words.next() {
                        None => {
                            return Err(syntax(
                                format!("3 coordinates \"v x y z\" in a vertex line, found {k}"),
                                line,
                            ));
                        }
                        Some(w) => match w.parse::<T>() {
                            Ok(x) => *slot = Some(x),
                            Err(_) => {
                                return Err(syntax(
                                    format!(
                                        "a number for the {axis} coordinate of a vertex, found \"{w}\","
                                    ),
                                    line,
                                ));
                            }
                        },
                    }
                }
                let rest: Vec<&str> = words.collect();
                let mut coords: Vec<f64> = Vec::with_capacity(3);
                match rest.len() {
                    0 | 3 => coords.extend(xyz.iter().flatten().map(|&x| x.into())),
                    1 => {
                        let w = rest[0].parse::<T>().map_err(|_| {
                            syntax(
                                format!(
                                    "a number for the w coordinate of a vertex, found \"{}\",",
                                    rest[0]
                                ),
                                line,
                            )
                        })?;
                        if w.into() == 0.0 {
                            return Err(syntax("a nonzero w coordinate".to_string(), line));
                        }
                        coords.extend(xyz.iter().flatten().map(|&x| (x / w).into()));
                    }
                    k => {
                        return Err(syntax(
                            format!(
                                "\"v x y z\", \"v x y z w\" or \"v x y z r g b\", found {} numbers",
                                3 + k
                            ),
                            line,
                        ));
                    }
                }
                n_v += 1;
                if coords.iter().any(|c| !c.is_finite()) {
                    return Err(MeshError::NonFinite {
                        path: path.to_path_buf(),
                        line: line_no,
                        vertex: n_v,
                        text: quote(line),
                    });
                }
            }
            Some(kw @ ("vt" | "vn")) => {
                let (need, what) = if kw == "vt" {
                    (2, "texture coordinate \"vt u v\"")
                } else {
                    (3, "normal \"vn x y z\"")
                };
                for k in 0..need {
                    match words.next() {
                        None => {
                            return Err(syntax(
                                format!("{need} numbers in a {what}, found {k}"),
                                line,
                            ));
                        }
                        Some(w) if w.parse::<T>().is_err() => {
                            return Err(syntax(
                                format!("a number in a {what}, found \"{w}\","),
                                line,
                            ));
                        }
                        Some(_) => {}
                    }
                }
                if kw == "vt" {
                    n_vt += 1;
                } else {
                    n_vn += 1;
                }
            }
            Some("f") => {
                let mut count = 0usize;
                for token in words {
                    count += 1;
                    let parts: Vec<&str> = token.split('/').collect();
                    if parts.len() > 3 {
                        return Err(syntax(
                            format!(
                                "a face vertex \"v\", \"v/vt\", \"v//vn\" or \"v/vt/vn\", found \"{token}\","
                            ),
                            line,
                        ));
                    }
                    if parts[0].is_empty() {
                        return Err(syntax(format!("a vertex index, found \"{token}\","), line));
                    }
                    let defined = [n_v, n_vt, n_vn];
                    let names = ["vertex", "texture coordinate", "normal"];
                    for (k, part) in parts.iter().enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let Ok(index) = part.parse::<i64>() else {
                            return Err(syntax(
                                format!("an integer {} index, found \"{part}\",", names[k]),
                                line,
                            ));
                        };
                        let n = defined[k] as i64;
                        let ok = (index > 0 && index <= n) || (index < 0 && index >= -n);
                        if !ok {
                            return Err(MeshError::BadIndex {
                                path: path.to_path_buf(),
                                line: line_no,
                                element: names[k],
                                index,
                                defined: defined[k],
                                text: quote(line),
                            });
                        }
                    }
                }
                if count < 3 {
                    return Err(MeshError::FaceTooShort {
                        path: path.to_path_buf(),
                        line: line_no,
                        count,
                        text: quote(line),
                    });
                }
                summary.faces += 1;
            }
            Some("l") => summary.has_polylines = true,
            Some("usemtl") => {
                // tobj takes the name after the first space and rejects an empty one.
                let name = line.split_once(' ').map(|(_, n)| n.trim()).unwrap_or("");
                if name.is_empty() {
                    return Err(syntax("a material name after \"usemtl\"".to_string(), line));
                }
            }
            _ => {}
        }
    }
    Ok(summary)
}

/// `bytes` with every `l` (polyline) line blanked, keeping line numbers.
fn without_polylines(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        if i > 0 {
            out.push(b'\n');
        }
        let is_polyline = std::str::from_utf8(raw)
            .map(|s| s.split_whitespace().next() == Some("l"))
            .unwrap_or(false);
        if !is_polyline {
            out.extend_from_slice(raw);
        }
    }
    out
}

/// Load an OBJ with tobj (single_index = false, triangulate = true; all models/objects in the file merged into one TriMesh).
///
/// Vertices are welded by exact position (−0.0 = 0.0) so closure is judged by position.
/// Each line is validated first so that errors name the line: syntax tobj would reject,
/// non-finite vertices, faces with fewer than 3 vertices, and indices that are 0 or refer to an
/// element not defined before the line (negative indices are relative, as in the OBJ format).
/// Polylines (`l`) are ignored; materials are not read. Degenerate triangles are kept here and
/// dropped by [`TriMesh::analyze`]. Polygons are triangulated by tobj as fans.
pub fn load_obj(path: &Path) -> Result<TriMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    // The empty Vec only tells the scan which float type tobj parses into.
    let summary = scan_obj(path, &bytes, &tobj::Mesh::default().positions)?;
    if summary.faces == 0 {
        return Err(MeshError::NoTriangles {
            path: path.to_path_buf(),
        });
    }
    let filtered;
    let input: &[u8] = if summary.has_polylines {
        filtered = without_polylines(&bytes);
        &filtered
    } else {
        &bytes
    };
    // `..Default::default()` keeps this compiling when tobj's `merging`/`reordering` features add fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(input), &options, |_| {
            Err(tobj::LoadError::GenericFailure)
        })
        .map_err(|source| MeshError::Obj {
            path: path.to_path_buf(),
            source,
        })?;

    let invalid = |message: String| MeshError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let mut mesh = TriMesh::default();
    let mut weld: HashMap<[u64; 3], u32> = HashMap::new();
    let mut local: Vec<u32> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        local.clear();
        for p in m.positions.chunks_exact(3) {
            let q: [f64; 3] = [p[0].into(), p[1].into(), p[2].into()];
            if q.iter().any(|c| !c.is_finite()) {
                return Err(invalid(format!(
                    "a vertex of object \"{}\" has a non-finite coordinate {q:?} (expected finite numbers)",
                    model.name
                )));
            }
            // +0.0 normalises -0.0 to 0.0.
            let key = q.map(|c| (c + 0.0).to_bits());
            let id = match weld.entry(key) {
                Entry::Occupied(e) => *e.get(),
                Entry::Vacant(e) => {
                    let Ok(next) = u32::try_from(mesh.positions.len()) else {
                        return Err(invalid(format!(
                            "more than {} distinct vertex positions (expected a mesh addressable with u32 indices)",
                            u32::MAX
                        )));
                    };
                    mesh.positions.push(DVec3::from_array(q));
                    *e.insert(next)
                }
            };
            local.push(id);
        }
        for t in m.indices.chunks_exact(3) {
            let map = |i: u32| local.get(i as usize).copied();
            match (map(t[0]), map(t[1]), map(t[2])) {
                (Some(a), Some(b), Some(c)) => mesh.triangles.push([a, b, c]),
                _ => {
                    return Err(invalid(format!(
                        "tobj produced a vertex index out of range in object \"{}\" (expected valid face indices)",
                        model.name
                    )));
                }
            }
        }
    }
    if mesh.triangles.is_empty() {
        return Err(MeshError::NoTriangles {
            path: path.to_path_buf(),
        });
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_is_closed_outward_with_the_prism_volume() {
        let c = TriMesh::cylinder(0.5, 0.2, 32);
        let (_, r) = c.analyze();
        assert!(r.is_closed(), "{r:?}");
        assert_eq!(c.triangles.len(), 4 * 32);
        // A regular 32-gon prism: area n/2·r²·sin(2π/n) times the height.
        let v = 16.0 * 0.25 * (2.0 * PI / 32.0).sin() * 0.2;
        assert!(
            (c.signed_volume() - v).abs() < 1e-12,
            "{}",
            c.signed_volume()
        );
        assert_eq!(c.euler_characteristic(), 2);
    }

    fn all_meshes() -> Vec<(&'static str, TriMesh)> {
        let mut v = vec![("box", TriMesh::unit_box(DVec3::new(1.0, 2.0, 3.0)))];
        for s in 0..=4 {
            v.push(("icosphere", TriMesh::icosphere(1.5, s)));
        }
        v.push(("torus", TriMesh::torus(2.0, 0.5, 24)));
        v
    }

    #[test]
    fn procedural_meshes_are_closed() {
        for (name, m) in all_meshes() {
            let (clean, report) = m.analyze();
            assert_eq!(
                report,
                MeshReport {
                    triangles: m.triangles.len(),
                    ..MeshReport::default()
                },
                "{name}"
            );
            assert!(report.is_closed(), "{name}");
            assert_eq!(clean, m, "{name}: nothing to drop");
        }
    }

    #[test]
    fn box_counts_volume_and_normals() {
        let size = DVec3::new(1.0, 2.0, 3.0);
        let m = TriMesh::unit_box(size);
        assert_eq!(m.positions.len(), 8);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.euler_characteristic(), 2);
        // 1·2·3 exactly: every term is a product of halves of small integers.
        assert_eq!(m.signed_volume(), 6.0);
        assert_eq!(m.bounds(), (-size * 0.5, size * 0.5));
        // Each triangle's normal is along an axis and points away from the centre.
        for &t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            assert!(n.dot(centroid) > 0.0, "{t:?} points inward");
            assert_eq!(
                [n.x != 0.0, n.y != 0.0, n.z != 0.0]
                    .iter()
                    .filter(|&&x| x)
                    .count(),
                1
            );
        }
    }

    #[test]
    fn icosphere_counts_and_orientation() {
        for s in 0..=4u32 {
            let m = TriMesh::icosphere(2.0, s);
            let p4 = 4usize.pow(s);
            assert_eq!(m.triangles.len(), 20 * p4, "s={s}");
            assert_eq!(m.positions.len(), 10 * p4 + 2, "s={s}");
            assert_eq!(m.euler_characteristic(), 2, "s={s}");
            for p in &m.positions {
                assert!((p.length() - 2.0).abs() < 1e-12);
            }
            for &t in &m.triangles {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                assert!(
                    (b - a).cross(c - a).dot(a + b + c) > 0.0,
                    "s={s} {t:?} inward"
                );
            }
        }
    }

    #[test]
    fn icosahedron_volume_is_exact() {
        // Circumradius r = a/4·sqrt(10 + 2√5); V = 5/12·(3 + √5)·a³.
        let r = 1.7;
        let s5 = 5.0_f64.sqrt();
        let a = 4.0 * r / (10.0 + 2.0 * s5).sqrt();
        let expected = 5.0 / 12.0 * (3.0 + s5) * a.powi(3);
        let v = TriMesh::icosphere(r, 0).signed_volume();
        assert!((v - expected).abs() < 1e-12 * expected, "{v} vs {expected}");
    }

    #[test]
    fn icosphere_volume_within_inscribed_bounds() {
        // Every triangle lies inside the ball (its corners are on the sphere), so V < 4/3·π·r³.
        // The cone from the origin over each face contains the spherical sector of radius h_f
        // (the face plane's distance); the faces tile the sphere under central projection, so
        // V ≥ 4/3·π·h_min³.
        let r: f64 = 1.25;
        let ball = 4.0 / 3.0 * PI * r.powi(3);
        let mut previous_error = f64::INFINITY;
        for s in 0..=4 {
            let m = TriMesh::icosphere(r, s);
            let v = m.signed_volume();
            let h_min = m
                .triangles
                .iter()
                .map(|&t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize]);
                    (b - a).cross(c - a).normalize().dot(a)
                })
                .fold(f64::INFINITY, f64::min);
            assert!(v < ball, "s={s}");
            assert!(v >= 4.0 / 3.0 * PI * h_min.powi(3) * (1.0 - 1e-12), "s={s}");
            let error = ball - v;
            assert!(error < previous_error, "error must shrink with subdivision");
            previous_error = error;
        }
        // Level 4: edges ≈ 1.05·r/16, so the deepest face sits ~r·(1 - 0.0015) deep at most.
        assert!(previous_error < 0.01 * ball);
    }

    #[test]
    fn torus_counts_and_volume() {
        for &(big_r, small_r, seg) in &[(2.0, 0.5, 24u32), (3.0, 1.0, 7), (1.0, 0.25, 64)] {
            let m = TriMesh::torus(big_r, small_r, seg);
            let n = seg as usize;
            let tube = (seg as usize / 2).max(3);
            assert_eq!(m.positions.len(), n * tube);
            assert_eq!(m.triangles.len(), 2 * n * tube);
            assert_eq!(m.euler_characteristic(), 0);
            assert!(m.analyze().1.is_closed());
            // Each sector between two meridians is a prism-like wedge over the inscribed
            // tube polygon P (its quads are planar trapezoids): V = n·sin(2π/n)·A_P·R with
            // A_P = tube/2·r²·sin(2π/tube). Equivalently V = 2π²Rr²·sinc(2π/n)·sinc(2π/tube).
            let exact = 2.0 * PI * PI * big_r * small_r * small_r;
            let xn = 2.0 * PI / n as f64;
            let xm = 2.0 * PI / tube as f64;
            let poly = exact * (xn.sin() / xn) * (xm.sin() / xm);
            let v = m.signed_volume();
            assert!((v - poly).abs() < 1e-9 * poly, "{v} vs {poly}");
            // sinc(x) ∈ [1 − x²/6, 1]
            assert!(v < exact);
            assert!(v > exact * (1.0 - xn * xn / 6.0) * (1.0 - xm * xm / 6.0));
        }
    }

    #[test]
    fn torus_normals_point_away_from_core_circle() {
        let (big_r, m) = (2.0, TriMesh::torus(2.0, 0.5, 16));
        for &t in &m.triangles {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let centroid = (a + b + c) / 3.0;
            let radial = DVec3::new(centroid.x, centroid.y, 0.0).normalize() * big_r;
            assert!((b - a).cross(c - a).dot(centroid - radial) > 0.0, "{t:?}");
        }
    }

    #[test]
    fn torus_clamps_small_segment_counts() {
        let m = TriMesh::torus(2.0, 0.5, 1);
        assert_eq!(m.positions.len(), 9);
        assert!(m.analyze().1.is_closed());
        assert!(m.signed_volume() > 0.0);
    }

    #[test]
    fn transformed_keeps_closure_and_scales_volume() {
        for (name, m) in all_meshes() {
            let v = m.signed_volume();
            for &s in &[0.5, 3.0, -2.0] {
                let t = m.transformed(
                    s,
                    DVec3::new(10.0, -35.0, 120.0),
                    DVec3::new(1e3, -7.0, 0.25),
                );
                assert!(t.analyze().1.is_closed(), "{name} s={s}");
                let expected = v * s.abs().powi(3);
                assert!(
                    (t.signed_volume() - expected).abs() < 1e-9 * expected,
                    "{name} s={s}: {} vs {expected}",
                    t.signed_volume()
                );
            }
        }
    }

    #[test]
    fn transformed_rotates_x_then_y_then_z() {
        let m = TriMesh {
            positions: vec![DVec3::Y, DVec3::X],
            triangles: vec![],
        };
        // Rx(90°) takes +y to +z, then Ry(90°) takes +z to +x. (Rx·Ry order would give +z.)
        let t = m.transformed(2.0, DVec3::new(90.0, 90.0, 0.0), DVec3::new(0.0, 0.0, 5.0));
        assert!((t.positions[0] - DVec3::new(2.0, 0.0, 5.0)).length() < 1e-12);
        // Rz(90°) takes +x to +y.
        let t = m.transformed(1.0, DVec3::new(0.0, 0.0, 90.0), DVec3::ZERO);
        assert!((t.positions[1] - DVec3::Y).length() < 1e-12);
    }

    #[test]
    fn reversed_triangle_gives_three_flipped_edges() {
        let mut m = TriMesh::unit_box(DVec3::ONE);
        m.triangles[5].swap(0, 1);
        let (_, r) = m.analyze();
        assert_eq!(r.flipped_edges, 3);
        assert_eq!((r.boundary_edges, r.nonmanifold_edges), (0, 0));
        assert!(!r.is_closed());
    }

    #[test]
    fn removed_triangle_gives_three_boundary_edges() {
        let mut m = TriMesh::icosphere(1.0, 1);
        m.triangles.remove(17);
        let (_, r) = m.analyze();
        assert_eq!(r.boundary_edges, 3);
        assert_eq!((r.flipped_edges, r.nonmanifold_edges), (0, 0));
        assert!(!r.is_closed());
        assert_eq!(m.euler_characteristic(), 1);
    }

    #[test]
    fn fin_triangle_gives_nonmanifold_edge() {
        let mut m = TriMesh::unit_box(DVec3::ONE);
        m.positions.push(DVec3::new(0.0, 0.0, 5.0));
        // Edge 0-4 belongs to the box; the fin adds a third user and two boundary edges.
        m.triangles.push([0, 4, 8]);
        let (_, r) = m.analyze();
        assert_eq!(r.nonmanifold_edges, 1);
        assert_eq!(r.boundary_edges, 2);
        assert_eq!(r.flipped_edges, 0);
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let mut m = TriMesh::unit_box(DVec3::ONE);
        let base = m.clone();
        let d = DVec3::new(0.1, 0.7, 0.3);
        let n = m.positions.len() as u32;
        // d, 2d and 8d are exactly collinear in f64 (power-of-two scaling is exact), although
        // c − a = 7d rounds; the exact predicate must still see zero area.
        m.positions
            .extend([d, d * 2.0, d * 8.0, DVec3::new(0.5, 0.5, 0.5)]);
        m.triangles.push([0, 0, 1]); // repeated index
        m.triangles.push([n, n + 1, n + 2]); // collinear
        m.triangles.push([7, n + 3, 6]); // n+3 duplicates vertex 7's position: zero area
        m.triangles.push([0, 1, 99]); // out of range
        m.triangles.insert(0, [n, n + 2, n + 1]);
        let (clean, r) = m.analyze();
        assert_eq!(r.degenerate_triangles, 5);
        assert_eq!(r.triangles, 12);
        assert!(r.is_closed());
        assert_eq!(clean.triangles, base.triangles);
        assert_eq!(clean.positions, m.positions);
        // A nearly collinear (but not exactly) triangle is kept.
        let sliver = TriMesh {
            positions: vec![
                DVec3::ZERO,
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(2.0, 2.0, 2.0 + 1e-15),
            ],
            triangles: vec![[0, 1, 2]],
        };
        assert_eq!(sliver.analyze().1.degenerate_triangles, 0);
    }

    #[test]
    fn exact_orientation_predicate() {
        assert!(orient2d_is_zero([0.0, 0.0], [1.0, 1.0], [3.0, 3.0]));
        assert!(!orient2d_is_zero(
            [0.0, 0.0],
            [1.0, 1.0],
            [3.0, 3.0 + 4.0 * f64::EPSILON]
        ));
        // Points on y = x + 0.1 offset by tiny steps: exact arithmetic, not the rounded determinant.
        let a = [0.1, 0.2];
        let b = [0.1 + 2f64.powi(-40), 0.2 + 2f64.powi(-40)];
        let c = [0.1 + 2f64.powi(-30), 0.2 + 2f64.powi(-30)];
        assert!(orient2d_is_zero(a, b, c));
        let c2 = [c[0], f64::from_bits(c[1].to_bits() + 1)];
        assert!(!orient2d_is_zero(a, b, c2));
    }

    #[test]
    fn bounds_and_volume_of_empty_mesh() {
        let m = TriMesh::default();
        assert_eq!(m.bounds(), (DVec3::ZERO, DVec3::ZERO));
        assert_eq!(m.signed_volume(), 0.0);
        assert_eq!(m.analyze().1, MeshReport::default());
    }

    #[test]
    fn volume_is_accurate_far_from_origin() {
        let m =
            TriMesh::unit_box(DVec3::splat(1e-3)).transformed(1.0, DVec3::ZERO, DVec3::splat(1e6));
        let v = m.signed_volume();
        assert!((v - 1e-9).abs() < 1e-6 * 1e-9, "{v}");
    }

    #[test]
    fn load_obj_welds_seams_and_resolves_relative_indices() {
        let dir = std::env::temp_dir().join(format!("convshadow-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let path = dir.join("seam.obj");
        // A tetrahedron whose vertex 1 is duplicated (as -0.0) and whose faces use v/vt/vn,
        // v//vn, negative indices, and a polyline that must be ignored (tobj would make it a triangle).
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv -0.0 0 -0\nvt 0 0\nvn 0 0 1\n\
                    f 1/1/1 3/1/1 2/1/1\nf 5//1 2//1 4//1\nf -5 -2 -3\nf 2 3 4\nl 1 2 3\n";
        std::fs::write(&path, text).expect("write");
        let m = load_obj(&path).expect("loads");
        let (_, r) = m.analyze();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(r.triangles, 4);
        assert!(r.is_closed(), "{r}");
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-15);

        let cases: [(&str, &str, &str); 9] = [
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 0\n",
                "seam.obj:3:",
                "vertex index 0",
            ),
            (
                "v 0 0 0\nv 1 0 0\nf 1 2 -3\n",
                "seam.obj:3:",
                "vertex index -3",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3 4\n",
                "seam.obj:4:",
                "vertex index 4",
            ),
            ("v 0 0 0\nv 1 0\n", "seam.obj:2:", "3 coordinates"),
            ("v 0 0 0\nv 1 inf 0\n", "seam.obj:2:", "vertex 2"),
            ("v 0 0 0\n\nv 1 0 0\nf 1 2\n", "seam.obj:4:", "at least 3"),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1/2 2 3\n",
                "seam.obj:4:",
                "texture coordinate index 2",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3/x\n",
                "seam.obj:4:",
                "\"x\"",
            ),
            ("v 0 0 0\nv 1 0 0\n", "seam.obj", "no triangles"),
        ];
        for (text, location, what) in cases {
            std::fs::write(&path, text).expect("write");
            let msg = load_obj(&path).expect_err(text).to_string();
            assert!(
                msg.contains(location) && msg.contains(what),
                "{text:?} -> {msg}"
            );
        }
        let missing = load_obj(&dir.join("missing.obj"))
            .expect_err("missing")
            .to_string();
        assert!(missing.contains("missing.obj"), "{missing}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    proptest::proptest! {
        #[test]
        fn any_rigid_transform_keeps_closure_and_volume(
            s in 0.01f64..100.0,
            neg in proptest::bool::ANY,
            rx in -360.0f64..360.0, ry in -360.0f64..360.0, rz in -360.0f64..360.0,
            tx in -1e4f64..1e4, ty in -1e4f64..1e4, tz in -1e4f64..1e4,
        ) {
            let m = TriMesh::icosphere(1.0, 1);
            let scale = if neg { -s } else { s };
            let t = m.transformed(scale, DVec3::new(rx, ry, rz), DVec3::new(tx, ty, tz));
            proptest::prop_assert!(t.analyze().1.is_closed());
            let expected = m.signed_volume() * s.powi(3);
            proptest::prop_assert!((t.signed_volume() - expected).abs() < 1e-9 * expected);
        }
    }
}
