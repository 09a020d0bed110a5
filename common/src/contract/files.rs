//! The files a scene names, read by the host (the `convshadow-io` crate) and handed to the
//! stages, so that `prepare` and `plan` never open a file. Each list is indexed like the scene's
//! own list (meshes, materials, lights); a scene without files needs only the `Default` values.

use std::sync::Arc;

use crate::pixel::volume::Volume;
use crate::plan::pattern::Pattern;
use crate::prepare::mesh::TriMesh;

/// The voxel grid of a NIfTI volume (from its header) or of an OpenVDB grid (its active box and
/// voxel size): what `slabs = "auto"` needs of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Voxels along x, y, z.
    pub dims: [u32; 3],
    /// Voxel spacing along x, y, z in the file's units.
    pub spacing: [f64; 3],
}

/// What the geometry stage needs read: the meshes of mesh files and the grids of NIfTI volumes.
#[derive(Clone, Debug, Default)]
pub struct GeometryFiles {
    /// Per scene mesh: the object-space mesh read from its file (`None`: a built-in shape).
    pub meshes: Vec<Option<TriMesh>>,
    /// Per material: its NIfTI or OpenVDB texture's grid (`None`: no texture, or a raw one).
    pub volume_grids: Vec<Option<VolumeGrid>>,
}

/// A material's 3D texture, read.
#[derive(Clone, Debug)]
pub struct TextureFile {
    /// The voxels, dense or bricked.
    pub texture: Arc<Volume>,
    /// A NIfTI volume's or OpenVDB grid's extent (dims × spacing, or × voxel size), fitted into
    /// the mesh's box by the plan; `None` for a raw texture, which fills the box.
    pub extent: Option<[f64; 3]>,
}

/// What the plan needs read: 3D textures and light patterns.
#[derive(Clone, Debug, Default)]
pub struct PlanFiles {
    /// Per material: its 3D texture (`None`: no texture).
    pub textures: Vec<Option<TextureFile>>,
    /// Per light: its pattern image (`None`: no pattern).
    pub patterns: Vec<Option<Pattern>>,
}
