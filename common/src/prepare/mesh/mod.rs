//! Triangle meshes: procedural shapes and closure analysis (mesh files are read by
//! `convshadow_io::mesh`: OBJ, PLY, glTF 2.0 and STL).
//!
//! Host geometry is `f64`; the rasterizer snaps vertices to fixed point later. Closure is judged
//! by **position index** after welding vertices with bit-identical positions, because the parity
//! test of the LDI needs every edge shared by exactly two consistently wound
//! triangles.
//!
//! One file per topic: shape builders, closure analysis (topology), exact predicates,
//! and the errors of reading a mesh file; every item is re-exported here.

use glam::DVec3;

/// Indexed triangle mesh in f64 (host geometry is f64; the rasterizer snaps later).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions`; outward normal is `(b-a)×(c-a)`.
    pub triangles: Vec<[u32; 3]>,
}

mod error;
mod predicates;
mod shapes;
#[cfg(test)]
mod tests;
mod topology;

pub use error::*;
use predicates::*;
pub use topology::*;
