//! convshadow: iterative convolution shadows (Patel et al. 2013) for closed meshes filled with
//! volumetric detail. This facade re-exports the stages and runs them as one call.
//!
//! - [`common`]: scene model, kernels and their tables, hashing, noise, rasterizer set-up, I/O.
//! - [`cpu`]: the bit-exact CPU oracle (LDI, parity cursor, kernels, slab sweep).
//! - [`pipeline`]: scene → image ([`pipeline::render`]) and scene → LDI
//!   ([`pipeline::build_ldi`]) on the CPU or the GPU, with a typed error.
//! - [`report`]: the speed-against-error grid.
//! - [`console`]: stdout and stderr written without panicking (closed pipes, full devices).
//! - [`exit_code`]: the command line's exit codes and the one each error maps to.
//! - [`overrides`]: what the command line's scene flags (`--width`, `--slabs`, `--kernel`, …) do
//!   to a scene, shared by the binary and the Python module.
//! - [`stats`]: the numbers of a render as `--stats-json` writes them.
//! - [`diff`]: the numbers `convshadow diff` reports beyond `io::metrics` (FLIP, NaNs, JSON).
//!
//! The command line (its subcommands, their arguments and output) is private to the
//! `convshadow` binary (`src/cli/`); the Python module is `python/` (docs/python.md).

pub use convshadow_common as common;
pub use convshadow_cpu as cpu;
pub use convshadow_io as io;
pub use convshadow_reference as reference;

pub mod console;
pub mod diff;
pub mod exit_code;
pub mod overrides;
pub mod pipeline;
pub mod report;
pub mod stats;
