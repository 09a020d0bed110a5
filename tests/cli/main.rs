//! The `convshadow` binary from the outside: `render`, `ldi`, `diff` and `report --quick`, their
//! outputs, display mapping and volumes, and its reliability (every bad input refused with a
//! documented exit code, memory limits, signals).
//!
//! One test binary of several (docs/ARCHITECTURE.md, Tests): `cargo test --release --test cli
//! [NAME::]`.

#[path = "../support/mod.rs"]
mod support;

mod budget_props;
mod closed_output;
mod diff_selftest;
mod display_volumes;
mod exr_layers;
mod hardening;
mod ldi;
mod mesh_formats;
mod reliability;
mod render;
mod report_quick;
mod vdb;
