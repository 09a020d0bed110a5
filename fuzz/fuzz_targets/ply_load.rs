//! Fuzz target: the PLY path (`ply::load_ply`: header checks, ply-rs-bw, face and vertex checks, welding).
//! The bytes are loaded as a `.ply` file and the mesh checked (`shared/mesh_file.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "shared/mesh_file.rs"]
mod mesh_file;

fuzz_target!(|data: &[u8]| mesh_file::fuzz_mesh_file(data, "ply"));
