//! The wgpu port against the CPU oracle: the same LDI and, on lavapipe, the same image bits
//! (required under CI, a loud skip without an adapter elsewhere).
//!
//! One test binary of several (docs/ARCHITECTURE.md, Tests): `cargo test --release --test gpu
//! [NAME::]`.

#[path = "../support/mod.rs"]
mod support;

mod ldi;
mod perspective;
mod point;
mod render;
