//! Shared core of convshadow: the scene model, parameters, tables, hashing, noise, rasterizer
//! set-up and image I/O. Everything here is used by both the CPU oracle and the GPU port.

pub mod auto_slabs;
pub mod camera;
pub mod geometry;
pub mod guard;
pub mod hash;
pub mod image_io;
pub mod input;
pub mod kernel;
pub mod lane;
pub mod ldi;
pub mod levels;
pub mod mesh;
pub mod metrics;
pub mod nifti;
pub mod noise;
pub mod pattern;
pub mod plan;
pub mod raster;
pub mod scene;
pub mod sweep_io;
pub mod texture3d;
pub mod tonemap;
