//! What every mesh-file fuzz target does with its bytes: write them to a temporary file with the
//! format's extension, load it (`mesh::load_mesh`, which picks the loader by extension), and hold
//! a loaded mesh to the loaders' contract. Any panic is a bug: a bad file must come back as a
//! `MeshError`.

use std::path::PathBuf;
use std::sync::OnceLock;

use convshadow_io::mesh::load_mesh;

/// Loads `data` as a mesh file ending in `.{extension}` (one temporary file per fuzzing
/// process: libFuzzer runs inputs one after another) and checks what a loader returns.
pub fn fuzz_mesh_file(data: &[u8], extension: &str) {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    let path = PATH.get_or_init(|| {
        std::env::temp_dir().join(format!(
            "convshadow-fuzz-{}.{extension}",
            std::process::id()
        ))
    });
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
    // Every triangle is either kept or counted as degenerate.
    assert_eq!(clean.triangles.len(), report.triangles);
    assert_eq!(
        report.triangles + report.degenerate_triangles,
        mesh.triangles.len()
    );
    let _ = clean.signed_volume();
    let _ = clean.bounds();
    let _ = clean.euler_characteristic();
}
