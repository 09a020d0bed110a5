//! Fuzz target: the glTF path (`gltf::load_gltf` on a `.glb`, or JSON glTF: the gltf crate's parser, then bounds-checked accessors and node transforms). The bytes are written to a temporary `.glb` file, loaded
//! through `mesh::load_mesh` (chosen by the extension), and the mesh is analysed for closure.
//! Any panic is a bug: a bad file must come back as a `MeshError`.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

use convshadow_io::mesh::load_mesh;
use libfuzzer_sys::fuzz_target;

/// One temporary file per fuzzing process (libFuzzer runs inputs one after another).
fn temp_file() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        std::env::temp_dir().join(format!("convshadow-fuzz-{}.glb", std::process::id()))
    })
}

fuzz_target!(|data: &[u8]| {
    let path = temp_file();
    if std::fs::write(path, data).is_err() {
        return;
    }
    let Ok(mesh) = load_mesh(path) else {
        return;
    };
    // A loaded mesh has triangles with valid indices and finite positions.
    assert!(!mesh.triangles.is_empty());
    let n = mesh.positions.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let (clean, report) = mesh.analyze();
    assert_eq!(
        report.triangles + report.degenerate_triangles,
        mesh.triangles.len()
    );
    let _ = clean.signed_volume();
});
