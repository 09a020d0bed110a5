//! The x86-64-v3 build and the processors around it: the lane tests in a build for baseline
//! x86-64 (a cargo build of its own), and the binary's processor check on emulated processors
//! (qemu-user). Kept apart from the other binaries: the nested build takes the machine's cores.
//!
//! One test binary of several (docs/ARCHITECTURE.md, Tests): `cargo test --release --test
//! platform [NAME::]`.

#[path = "../support/mod.rs"]
mod support;

mod baseline_lanes;
mod cpu_check;
