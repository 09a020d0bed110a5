//! Fuzz target: the STL path (`stl::load_stl`: size-based binary/ASCII choice, stl_io, welding).
//! The bytes are loaded as a `.stl` file and the mesh checked (`shared/mesh_file.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "shared/mesh_file.rs"]
mod mesh_file;

fuzz_target!(|data: &[u8]| mesh_file::fuzz_mesh_file(data, "stl"));
