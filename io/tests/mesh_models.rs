//! Loads the real models in `../shared/models` (next to the repository) and checks closure,
//! triangle counts and the error handling of the deliberately broken files in `bad/`.

use std::path::{Path, PathBuf};

use convshadow_common::prepare::mesh::{MeshError, MeshReport, TriMesh};
use convshadow_io::obj::load_obj;

/// The models folder beside the repository (see `convshadow_testkit::models_dir`).
fn models_dir() -> Option<PathBuf> {
    convshadow_testkit::models_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
}

/// Loads `name` from the models folder and analyses it; panics with the loader's message.
fn load(dir: &Path, name: &str) -> (TriMesh, MeshReport) {
    let mesh = load_obj(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    mesh.analyze()
}

#[test]
fn mesh_closed_models_are_closed_with_readme_counts() {
    let Some(dir) = models_dir() else { return };
    // (file, vertices, triangles, genus) from models/README.md.
    let closed: [(&str, usize, usize, i64); 9] = [
        ("bunny.obj", 3301, 6598, 0),
        ("bunny_hr.obj", 29834, 59664, 0),
        ("spot.obj", 2930, 5856, 0),
        ("spot_remeshed_lowres.obj", 829, 1654, 0),
        ("armadillo.obj", 14587, 29170, 0),
        ("armadillo_100k.obj", 49999, 99994, 0),
        ("torus.obj", 2304, 4608, 1),
        ("sphere.obj", 642, 1280, 0),
        ("cube.obj", 26, 48, 0),
    ];
    for (name, vertices, triangles, genus) in closed {
        let (mesh, report) = load(&dir, name);
        assert_eq!(
            report,
            MeshReport {
                triangles,
                ..MeshReport::default()
            },
            "{name}: {report}"
        );
        assert!(report.is_closed(), "{name}");
        // Welded by position, so seams in uv/normal indices (bunny, spot, cube) do not split vertices.
        assert_eq!(mesh.positions.len(), vertices, "{name}");
        assert_eq!(mesh.euler_characteristic(), 2 - 2 * genus, "{name}");
        assert!(
            mesh.signed_volume() > 0.0,
            "{name}: outward winding expected"
        );
    }
}

#[test]
fn mesh_open_models_are_reported_open() {
    let Some(dir) = models_dir() else { return };
    let (mesh, r) = load(&dir, "cube_no_bottom.obj");
    assert_eq!((mesh.positions.len(), r.triangles), (25, 40));
    assert_eq!(r.boundary_edges, 8, "{r}");
    assert_eq!((r.nonmanifold_edges, r.flipped_edges), (0, 0), "{r}");
    assert!(!r.is_closed());
    // A disc: V − E + F = 1.
    assert_eq!(mesh.euler_characteristic(), 1);

    let (_, r) = load(&dir, "stanford_bunny_original.obj");
    assert_eq!(r.triangles, 69451, "{r}");
    assert_eq!(r.boundary_edges, 223, "{r}");
    assert!(!r.is_closed());

    // README: 1036 boundary edges, counted over the file's vertex indices. The teapot repeats
    // vertices along its patch seams (3644 `v` lines, 3241 distinct positions); welded by
    // position, 160 boundary edges remain (the rim, spout, handle and lid openings). Counted
    // independently with a short Python script over the f32-rounded positions: 1036 unwelded, 160 welded.
    let (mesh, r) = load(&dir, "teapot.obj");
    assert_eq!((mesh.positions.len(), r.triangles), (3241, 6320), "{r}");
    assert_eq!(r.boundary_edges, 160, "{r}");
    assert_eq!((r.nonmanifold_edges, r.degenerate_triangles), (0, 0), "{r}");
    assert!(!r.is_closed());
}

#[test]
fn mesh_cornell_box_loads() {
    let Some(dir) = models_dir() else { return };
    // 18 quads in several objects, negative (relative) indices, materials that are not read.
    let (mesh, r) = load(&dir, "cornell_box.obj");
    assert_eq!(r.triangles, 36, "{r}");
    assert_eq!(r.degenerate_triangles, 0, "{r}");
    assert!(!r.is_closed(), "the box has no front wall: {r}");
    let (lo, hi) = mesh.bounds();
    assert_eq!(lo.to_array(), [0.0, 0.0, 0.0]);
    // Coordinates are read as f32 by tobj, then widened.
    assert_eq!(
        hi.to_array(),
        [556.0, f64::from(548.8f32), f64::from(559.2f32)]
    );
}

#[test]
fn mesh_bad_files_are_rejected_with_file_and_line() {
    let Some(dir) = models_dir() else { return };
    // (file, line that holds the defect, text expected in the message)
    let cases = [
        ("bad_index_out_of_range.obj", 9, "vertex index 5"),
        ("bad_zero_index.obj", 6, "vertex index 0"),
        ("bad_garbage_token.obj", 3, "\"abc\""),
        ("bad_truncated.obj", 9, "3 coordinates"),
        ("bad_truncated_face.obj", 9, "at least 3"),
        ("bad_nan_vertex.obj", 5, "vertex 4"),
    ];
    for (name, line, what) in cases {
        let err = load_obj(&dir.join("bad").join(name)).expect_err(name);
        let msg = err.to_string();
        eprintln!("{name}: {msg}");
        let located = format!("{name}:{line}:");
        assert!(
            msg.contains(&located),
            "{name}: expected {located:?} in {msg:?}"
        );
        assert!(msg.contains(what), "{name}: expected {what:?} in {msg:?}");
        let kind_ok = match name {
            "bad_index_out_of_range.obj" | "bad_zero_index.obj" => {
                matches!(err, MeshError::BadIndex { line: l, .. } if l == line)
            }
            "bad_truncated_face.obj" => {
                matches!(err, MeshError::FaceTooShort { count: 2, line: l, .. } if l == line)
            }
            "bad_nan_vertex.obj" => {
                matches!(err, MeshError::NonFinite { vertex: 4, line: l, .. } if l == line)
            }
            _ => matches!(err, MeshError::Syntax { line: l, .. } if l == line),
        };
        assert!(kind_ok, "{name}: unexpected error kind {err:?}");
    }
}

#[test]
fn mesh_bad_topology_files_load_and_are_reported() {
    let Some(dir) = models_dir() else { return };
    let bad = dir.join("bad");

    let (_, r) = load(&bad, "bad_nonmanifold_edge.obj");
    // Edge 1-2 is used by 3 faces; the fin's other two edges are boundary edges.
    assert_eq!(r.nonmanifold_edges, 1, "{r}");
    assert_eq!(r.boundary_edges, 2, "{r}");
    assert!(!r.is_closed());

    let (_, r) = load(&bad, "bad_flipped_face.obj");
    // One reversed face of a tetrahedron: its 3 edges are each traversed twice the same way.
    assert_eq!(r.flipped_edges, 3, "{r}");
    assert_eq!((r.boundary_edges, r.nonmanifold_edges), (0, 0), "{r}");
    assert!(!r.is_closed());

    let (mesh, r) = load(&bad, "tetra_ok.obj");
    assert_eq!(
        r,
        MeshReport {
            triangles: 4,
            ..MeshReport::default()
        }
    );
    assert!(r.is_closed());
    assert!((mesh.signed_volume() - 1.0 / 6.0).abs() < 1e-15);
}

#[test]
fn mesh_missing_file_names_the_path() {
    let Some(dir) = models_dir() else { return };
    let err = load_obj(&dir.join("no_such_model.obj")).expect_err("missing file");
    assert!(matches!(err, MeshError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("no_such_model.obj"), "{err}");
}
