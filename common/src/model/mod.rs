//! The scene as the user wrote it: its types and limits, TOML parsing and validation, and the
//! spec enums the stages read (kernels, display mapping). Host code: f64 and libm allowed.

pub mod display;
pub mod kernel;
mod parse;
pub mod scene;
