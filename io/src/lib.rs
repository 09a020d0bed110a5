//! The files of convshadow: what a scene names (the scene TOML, mesh files in OBJ, PLY, glTF 2.0
//! or STL, raw, NIfTI and OpenVDB volumes, pattern images) read into the core's types, and the images a render writes (PNG
//! through the display mapping, linear EXR) and compares (`metrics`). Host code only: every
//! reader is bounded (sizes checked before allocating) and names the file in its errors.
//!
//! [`read`] is the path a render takes: the scene, then [`read::read_geometry_files`] before
//! the geometry and [`read::read_plan_files`] before the plan (the core never opens a file).

pub mod gltf;
pub mod image;
pub mod input;
pub mod mesh;
pub mod metrics;
pub mod nifti;
pub mod obj;
pub mod pattern;
pub mod ply;
pub mod raw;
pub mod read;
pub mod stl;
pub mod vdb;
pub(crate) mod weld;

pub use read::{build_geometry, build_plan, build_plan_guarded, load_scene};
