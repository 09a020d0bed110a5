//! The contracts every change must keep (docs/ARCHITECTURE.md): the image and LDI bits
//! (golden hashes; the same bits for any thread count, path and quiet-chunk skipping; the early
//! finish), the LDI's parity on closed meshes, random scenes that render without NaN or are
//! refused naming the key, and the bit-exactness rules of the source.
//!
//! One test binary of several (docs/ARCHITECTURE.md, Tests): `cargo test --release --test
//! contract [NAME::]`.

#[path = "../support/mod.rs"]
mod support;

mod determinism;
mod early_finish;
mod extreme_numbers;
mod golden_hashes;
mod ldi_parity;
mod ldi_perspective;
mod mesh_props;
mod perspective_sweep;
mod rules;
mod scene_props;
mod simd_quiet;
