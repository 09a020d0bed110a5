//! Why a scene's geometry could not be built.

use crate::model::scene::MAX_SLABS;
use crate::prepare::mesh::MeshError;
use crate::prepare::raster::RasterError;

/// Why a scene's geometry could not be built.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// A mesh file could not be loaded.
    #[error("{scene}: mesh[{index}]: {source}")]
    Mesh {
        /// Scene file.
        scene: String,
        /// Mesh index in the scene.
        index: usize,
        /// The loader's error.
        source: MeshError,
    },
    /// Perspective: a mesh reaches the eye or `camera.near` (there is no clipping; an eye inside
    /// a closed mesh is refused so).
    #[error(
        "{scene}: mesh[{index}]: reaches view depth {depth:.6e}, {}",
        match near {
            Some(n) => format!(
                "in front of key `camera.near` = {n}: expected every mesh beyond it (lower \
                 camera.near or move camera.eye)"
            ),
            None => "at or behind key `camera.eye`: expected every mesh in front of the \
                     perspective camera's eye (an eye inside or beside a mesh is not supported; \
                     move camera.eye)"
                .to_string(),
        }
    )]
    BeforeNear {
        /// Scene file.
        scene: String,
        /// Mesh index.
        index: usize,
        /// The mesh's nearest view depth.
        depth: f64,
        /// `camera.near`, if given.
        near: Option<f64>,
    },
    /// A mesh has no triangle left after dropping degenerate ones.
    #[error("{scene}: mesh[{index}]: no non-degenerate triangle")]
    EmptyMesh {
        /// Scene file.
        scene: String,
        /// Mesh index.
        index: usize,
    },
    /// A triangle cannot be rasterized exactly.
    #[error("{scene}: {source}")]
    Raster {
        /// Scene file.
        scene: String,
        /// The rasterizer's error.
        source: RasterError,
    },
    /// The slab distance gives too many slabs for the scene's depth.
    #[error(
        "{scene}: key `sweep.slab_distance`: {distance} gives {count} slabs over the scene's depth of \
         {depth}, expected at most {MAX_SLABS}"
    )]
    TooManySlabs {
        /// Scene file.
        scene: String,
        /// Slab distance.
        distance: f64,
        /// Resulting count.
        count: f64,
        /// Scene depth.
        depth: f64,
    },
    /// `slabs = "auto"` needs more slabs than the limit.
    #[error(
        "{scene}: key `sweep.slabs`: \"auto\" needs {count} slabs (2 per {period:.4e} world \
         units along the view of `{limited_by}` over the scene's depth of {depth:.4e}, times \
         sweep.slab_factor = {factor}), expected at most {MAX_SLABS}; lower `sweep.slab_factor` \
         or give `sweep.slabs` a count"
    )]
    TooManyAutoSlabs {
        /// Scene file.
        scene: String,
        /// The count auto needs.
        count: f64,
        /// Scene depth.
        depth: f64,
        /// The finest period or thickness (world units along the view).
        period: f64,
        /// The key of the detail or the mesh (`mesh[i] thickness`) that sets it.
        limited_by: String,
        /// `sweep.slab_factor`.
        factor: f64,
    },
    /// A NIfTI texture's header could not be read (`slabs = "auto"` reads its dims).
    #[error("{scene}: material `{material}`: {source}")]
    Texture {
        /// Scene file.
        scene: String,
        /// Material name.
        material: String,
        /// The loader's error.
        source: crate::pixel::texture3d::TextureError,
    },
}
