//! From the model to geometry: the camera, meshes placed in the world, the slab count, the guard
//! band and the rasterizer set-up. Host code: f64 and libm allowed.

pub mod auto_slabs;
pub mod camera;
pub mod error;
pub mod geometry;
pub mod guard;
pub mod mesh;
pub mod placement;
pub mod raster;
