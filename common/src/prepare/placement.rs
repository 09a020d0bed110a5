//! Where a mesh sits in the world: its placed triangles, the map back to object space, and the
//! box its 3D texture fills.

use glam::{DAffine3, DMat3, DVec3};

use crate::model::scene::MeshSpec;
use crate::prepare::mesh::{MeshReport, TriMesh};

/// A mesh placed in the world, with its defects and the way back to object space.
#[derive(Clone, Debug)]
pub struct WorldMesh {
    /// World-space triangles (degenerate ones dropped).
    pub mesh: TriMesh,
    /// Closure report (boundary, non-manifold and flipped edges, degenerate triangles).
    pub report: MeshReport,
    /// Maps world points to the mesh's object space (where detail functions are evaluated).
    pub world_to_object: DAffine3,
    /// Object-space bounding box (3D textures are mapped onto it).
    pub object_bounds: (DVec3, DVec3),
}

/// The object-to-world transform of a mesh spec: p' = R·(s·p) + t, R = Rz·Ry·Rx.
pub fn object_to_world(spec: &MeshSpec) -> DAffine3 {
    let [rx, ry, rz] = spec.rotate_deg.map(f64::to_radians);
    let r = DMat3::from_rotation_z(rz) * DMat3::from_rotation_y(ry) * DMat3::from_rotation_x(rx);
    DAffine3::from_mat3_translation(r * spec.scale, DVec3::from(spec.translate))
}

/// The largest box with the aspect of `extent`, centred in the bounds `lo..hi`: a NIfTI volume's
/// voxels keep their spacing's proportions (outside the box, sampling clamps to the edge voxels).
pub fn fit_extent(lo: DVec3, hi: DVec3, extent: DVec3) -> (DVec3, DVec3) {
    let size = hi - lo;
    let extent = extent.max(DVec3::splat(1e-30));
    let scale = (size / extent).min_element();
    let fitted = extent * scale;
    let centre = (lo + hi) * 0.5;
    (centre - fitted * 0.5, centre + fitted * 0.5)
}
