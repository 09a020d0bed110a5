//! Fuzz target: the OBJ path (line validation, then tobj, welding).
//! The bytes are loaded as a `.obj` file and the mesh checked (`shared/mesh_file.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "shared/mesh_file.rs"]
mod mesh_file;

fuzz_target!(|data: &[u8]| mesh_file::fuzz_mesh_file(data, "obj"));
