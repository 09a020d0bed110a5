//! convshadow: iterative convolution shadows (Patel et al. 2013) for closed meshes filled with
//! volumetric detail. This facade re-exports the stages and runs them as one call.
//!
//! - [`common`]: scene model, kernels and their tables, hashing, noise, rasterizer set-up, I/O.
//! - [`cpu`]: the bit-exact CPU oracle (LDI, parity cursor, kernels, slab sweep).
//! - [`pipeline`]: scene → image ([`pipeline::render`]) and scene → LDI
//!   ([`pipeline::build_ldi`]) on the CPU or the GPU, with a typed error.
//! - [`report`]: the speed-against-error grid.
//! - [`console`]: stdout and stderr written without panicking (closed pipes, full devices).
//!
//! The command line (its subcommands and exit codes) is private to the `convshadow` binary
//! (`src/cli/`).

pub use convshadow_common as common;
pub use convshadow_cpu as cpu;
pub use convshadow_io as io;
pub use convshadow_reference as reference;

pub mod console;
pub mod pipeline;
pub mod report;
