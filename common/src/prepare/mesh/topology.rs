//! Closure analysis: degenerate triangles, boundary, non-manifold and flipped edges by position.

use std::fmt;

use glam::DVec3;

use super::*;

/// Closure / quality report of a mesh after cleaning.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshReport {
    /// Triangles kept after dropping degenerate ones.
    pub triangles: usize,
    /// Triangles dropped: repeated index, zero area (exactly collinear in f64), or an index out of range.
    pub degenerate_triangles: usize,
    /// Undirected edges used by exactly 1 triangle.
    pub boundary_edges: usize,
    /// Undirected edges used by 3 or more triangles, not as often in each direction (odd
    /// incidence, or inconsistent winding): the inside/outside parity breaks there.
    pub nonmanifold_edges: usize,
    /// Undirected edges used by 4 or more triangles, as often in each direction (a closed
    /// 2-cycle, such as two cubes sharing an edge): closed for the parity test, so accepted, but
    /// counted for a warning.
    pub paired_nonmanifold_edges: usize,
    /// Manifold edges whose two triangles traverse them in the same direction (inconsistent winding).
    pub flipped_edges: usize,
}

impl MeshReport {
    /// True when there are no boundary, flipped or unpaired non-manifold edges (paired ones, used
    /// as often in each direction, keep the mesh closed).
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
        )?;
        if self.paired_nonmanifold_edges > 0 {
            write!(
                f,
                ", {} closed non-manifold edges (used as often in each direction)",
                self.paired_nonmanifold_edges
            )?;
        }
        Ok(())
    }
}

impl TriMesh {
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
                n => {
                    let forward = run.iter().filter(|e| e.2).count();
                    if 2 * forward == n {
                        report.paired_nonmanifold_edges += 1;
                    } else {
                        report.nonmanifold_edges += 1;
                    }
                }
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
pub(crate) fn directed_edges(triangles: &[[u32; 3]]) -> Vec<(u32, u32, bool)> {
    let mut edges = Vec::with_capacity(triangles.len() * 3);
    for &[a, b, c] in triangles {
        for (u, v) in [(a, b), (b, c), (c, a)] {
            edges.push((u.min(v), u.max(v), u < v));
        }
    }
    edges
}
