//! Fuzz target: the glTF path (`gltf::load_gltf` on a `.glb`, or JSON glTF: the gltf crate's parser, then bounds-checked accessors and node transforms).
//! The bytes are loaded as a `.glb` file and the mesh checked (`shared/mesh_file.rs`).
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "shared/mesh_file.rs"]
mod mesh_file;

fuzz_target!(|data: &[u8]| mesh_file::fuzz_mesh_file(data, "glb"));
