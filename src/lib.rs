//! convshadow: iterative convolution shadows (Patel et al. 2013) for closed meshes filled with
//! volumetric detail. This facade re-exports the stages and holds the command-line commands.
//!
//! - [`common`]: scene model, kernels and their tables, hashing, noise, rasterizer set-up, I/O.
//! - [`cpu`]: the bit-exact CPU oracle (LDI, parity cursor, kernels, slab sweep).

pub use convshadow_common as common;
pub use convshadow_cpu as cpu;
pub use convshadow_io as io;
pub use convshadow_reference as reference;

pub mod commands;
pub mod exit;
pub mod pipeline;
pub mod report;
