//! PLY, glTF 2.0 and STL through `convshadow_io::mesh::load_mesh`: the bunny of
//! `../shared/models` converted in the test (by `convshadow_testkit::mesh_files`, a writer
//! independent of the loaders) loads to the OBJ loader's mesh, and malformed files of each
//! format are errors that name the file and the element, never panics.

use std::path::{Path, PathBuf};

use convshadow_common::prepare::mesh::{MeshError, TriMesh};
use convshadow_io::mesh::load_mesh;
use convshadow_io::obj::load_obj;
use convshadow_testkit::mesh_files::{self as mf, GltfNode, PlyEncoding, SoupMesh};

/// The models folder beside the repository (see `convshadow_testkit::models_dir`).
fn models_dir() -> Option<PathBuf> {
    convshadow_testkit::models_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
}

/// A fresh temporary folder for one test.
fn temp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("convshadow-formats-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes `bytes` to `dir/name` and loads it.
fn write_load(dir: &Path, name: &str, bytes: &[u8]) -> Result<TriMesh, MeshError> {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    load_mesh(&p)
}

/// A file to write: its name and bytes.
type File = (&'static str, Vec<u8>);

/// Every conversion of `m` the loaders read: (file name, bytes, extra files).
fn conversions(m: &SoupMesh) -> Vec<(&'static str, Vec<u8>, Vec<File>)> {
    let (nodes, roots) = mf::one_node();
    let (json, bin) = mf::gltf_with_bin(std::slice::from_ref(m), &nodes, &roots, "m%20data.bin");
    vec![
        ("m.ply", mf::ply(m, PlyEncoding::Ascii, false), vec![]),
        ("m_double.ply", mf::ply(m, PlyEncoding::Ascii, true), vec![]),
        (
            "m_le.ply",
            mf::ply(m, PlyEncoding::LittleEndian, false),
            vec![],
        ),
        ("m_be.ply", mf::ply(m, PlyEncoding::BigEndian, true), vec![]),
        ("m_ascii.stl", mf::stl_ascii(m), vec![]),
        ("m_bin.stl", mf::stl_binary(m, "binary"), vec![]),
        // Many exporters start a binary STL's header with "solid".
        ("m_solid.stl", mf::stl_binary(m, "solid exported"), vec![]),
        ("m.gltf", json.into_bytes(), vec![("m data.bin", bin)]),
        (
            "m_embedded.gltf",
            mf::gltf_embedded(std::slice::from_ref(m), &nodes, &roots).into_bytes(),
            vec![],
        ),
        (
            "m.glb",
            mf::glb(std::slice::from_ref(m), &nodes, &roots),
            vec![],
        ),
    ]
}

#[test]
fn bunny_in_every_format_loads_to_the_obj_mesh() {
    let Some(models) = models_dir() else { return };
    let obj_path = models.join("bunny.obj");
    let reference = load_obj(&obj_path).unwrap();
    let soup = mf::read_obj_triangles(&std::fs::read_to_string(&obj_path).unwrap());
    assert_eq!(soup.triangles.len(), 6598);
    let dir = temp("bunny");
    for (name, bytes, extra) in conversions(&soup) {
        for (n, b) in &extra {
            std::fs::write(dir.join(n), b).unwrap();
        }
        let m = write_load(&dir, name, &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The same triangles, corner for corner, over the same positions (STL's corners are
        // welded back into 3301 vertices).
        assert_eq!(m.triangles.len(), reference.triangles.len(), "{name}");
        assert_eq!(m.positions.len(), reference.positions.len(), "{name}");
        for (k, (a, b)) in m.triangles.iter().zip(&reference.triangles).enumerate() {
            let pa = a.map(|i| m.positions[i as usize]);
            let pb = b.map(|i| reference.positions[i as usize]);
            assert_eq!(pa, pb, "{name}: triangle {k}");
        }
        let (_, report) = m.analyze();
        assert!(report.is_closed(), "{name}: {report}");
        assert_eq!(m.euler_characteristic(), 2, "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A closed tetrahedron (outward winding).
fn tetra() -> SoupMesh {
    mf::read_obj_triangles(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
}

#[test]
fn gltf_node_transforms_are_composed_and_mirrors_keep_the_winding_outward() {
    let dir = temp("gltf-nodes");
    let t = tetra();
    // Root: translate (1, 2, 3) · scale 2, holding mesh 0; its child mirrors x and holds it too.
    let scale_translate = [
        2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 1.0, 2.0, 3.0, 1.0,
    ];
    let mirror_x = [
        -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 10.0, 0.0, 0.0, 1.0,
    ];
    let nodes = [
        GltfNode {
            mesh: Some(0),
            matrix: Some(scale_translate),
            children: vec![1],
        },
        GltfNode {
            mesh: Some(0),
            matrix: Some(mirror_x),
            children: vec![],
        },
    ];
    let m = write_load(
        &dir,
        "n.glb",
        &mf::glb(std::slice::from_ref(&t), &nodes, &[0]),
    )
    .unwrap();
    assert_eq!((m.positions.len(), m.triangles.len()), (8, 8));
    // First copy: 2p + (1, 2, 3).
    assert_eq!(m.positions[1].to_array(), [3.0, 2.0, 3.0]);
    // Second copy: the parent's transform after the child's: 2·(10 − x, y, z) + (1, 2, 3).
    assert!(
        m.positions.iter().any(|p| p.to_array() == [21.0, 2.0, 3.0]),
        "{:?}",
        m.positions
    );
    let (_, r) = m.analyze();
    assert!(r.is_closed(), "{r}");
    // Both copies outward: 8 × 1/6, the mirrored one with its winding reversed.
    assert!(
        (m.signed_volume() - 2.0 * 8.0 / 6.0).abs() < 1e-12,
        "{}",
        m.signed_volume()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `text` in `msg`, or a failure naming both.
#[track_caller]
fn says(msg: &str, text: &str) {
    assert!(msg.contains(text), "expected {text:?} in {msg:?}");
}

#[test]
fn malformed_ply_files_are_errors_naming_the_file_and_element() {
    let dir = temp("bad-ply");
    let t = tetra();
    let good = mf::ply(&t, PlyEncoding::Ascii, false);
    let good_text = String::from_utf8(good.clone()).unwrap();
    let bin = mf::ply(&t, PlyEncoding::LittleEndian, false);
    let body = bin.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let mut nan_bin = bin.clone();
    // Vertex 1's y.
    nan_bin[body + 16..body + 20].copy_from_slice(&f32::NAN.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "index.ply",
            good_text.replace("3 1 2 3\n", "3 1 99 3\n").into_bytes(),
            &["face 3", "index 99 out of range"],
        ),
        (
            "negative.ply",
            good_text.replace("\n3 0 1 3\n", "\n3 0 -1 3\n").into_bytes(),
            &["face 1", "index -1 out of range"],
        ),
        (
            "short_face.ply",
            good_text.replace("\n3 0 1 3\n", "\n2 0 1\n").into_bytes(),
            &["face 1", "at least 3"],
        ),
        (
            "nan.ply",
            good_text.replacen("\n1 0 0\n", "\nnan 0 0\n", 1).into_bytes(),
            &["line 12", "vertex elements"],
        ),
        ("nan_binary.ply", nan_bin, &["vertex 1", "non-finite coordinate [1.0, NaN, 0.0]"]),
        (
            "truncated_ascii.ply",
            good[..good.len() - 12].to_vec(),
            &["face"],
        ),
        ("truncated_binary.ply", bin[..bin.len() - 7].to_vec(), &["face"]),
        (
            "count.ply",
            good_text.replace("element face 4", "element face 4000000000").into_bytes(),
            &["truncated file or a wrong count"],
        ),
        (
            "no_faces.ply",
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n".to_vec(),
            &["no \"face\" element"],
        ),
        (
            "no_z.ply",
            good_text.replace("property float z\n", "").into_bytes(),
            &["no property \"z\""],
        ),
        (
            "float_index.ply",
            good_text
                .replace("list uchar int vertex_indices", "list uchar float vertex_indices")
                .into_bytes(),
            &["integer vertex indices"],
        ),
        ("header.ply", b"ply\nformat ascii 1.0\nelement vertex\n".to_vec(), &["bad header"]),
        ("empty.ply", Vec::new(), &["bad header"]),
        ("garbage.ply", good_text.replace("0 0 1\n", "0 zero 1\n").into_bytes(), &["line"]),
    ];
    check_errors(&dir, cases);
}

/// Loads each case and checks: an error (not a panic), naming the file and each text.
fn check_errors(dir: &Path, cases: Vec<(&str, Vec<u8>, &[&str])>) {
    for (name, bytes, texts) in cases {
        let p = dir.join(name);
        std::fs::write(&p, &bytes).unwrap();
        let r = std::panic::catch_unwind(|| load_mesh(&p));
        let msg = match r {
            Err(_) => panic!("{name}: the loader panicked"),
            Ok(Ok(m)) => panic!(
                "{name}: loaded {} triangles, expected an error",
                m.triangles.len()
            ),
            Ok(Err(e)) => e.to_string(),
        };
        eprintln!("{name}: {msg}");
        says(&msg, name);
        for t in texts {
            says(&msg, t);
        }
    }
}

#[test]
fn ply_index_and_face_errors_name_the_face() {
    let dir = temp("ply-face");
    let t = tetra();
    let text = String::from_utf8(mf::ply(&t, PlyEncoding::Ascii, false)).unwrap();
    // Faces are "3 0 2 1", "3 0 1 3", "3 0 3 2", "3 1 2 3" (0-based).
    let bad = text.replace("3 1 2 3\n", "3 1 2 99\n");
    let e = write_load(&dir, "bunny.ply", bad.as_bytes())
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        format!(
            "{}: face 3: index 99 out of range (the file has 4 vertices, indices 0..=3)",
            dir.join("bunny.ply").display()
        )
    );
    let bad = text.replace("3 0 3 2\n", "2 0 3\n");
    let e = write_load(&dir, "short.ply", bad.as_bytes())
        .unwrap_err()
        .to_string();
    says(&e, "face 2: 2 vertex indices, expected at least 3");
    // A quad is a fan of two triangles; extra elements and properties are skipped.
    let quad = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                property float z\nproperty uchar red\nelement face 1\nproperty uchar flags\n\
                property list uchar int vertex_index\nelement edge 1\nproperty int v1\n\
                property int v2\nend_header\n0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n7 4 0 1 2 3\n0 1\n";
    let m = write_load(&dir, "quad.ply", quad.as_bytes()).unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_stl_files_are_errors_naming_the_file_and_facet() {
    let dir = temp("bad-stl");
    let t = tetra();
    let ascii = String::from_utf8(mf::stl_ascii(&t)).unwrap();
    let bin = mf::stl_binary(&t, "binary");
    let mut nan_bin = bin.clone();
    // Facet 2, vertex 1, y: 84 + 2·50 + 12 + 12 + 4.
    nan_bin[84 + 100 + 28..84 + 100 + 32].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut wrong_count = bin.clone();
    wrong_count[80..84].copy_from_slice(&5u32.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "truncated.stl",
            bin[..bin.len() - 10].to_vec(),
            &["declares 4 triangles", "274 bytes"],
        ),
        ("count.stl", wrong_count, &["declares 5 triangles"]),
        ("nan.stl", nan_bin, &["facet 2", "vertex 1", "non-finite"]),
        ("short.stl", b"not an stl".to_vec(), &["shorter than"]),
        ("empty.stl", Vec::new(), &["0 bytes"]),
        (
            "ascii_truncated.stl",
            ascii.as_bytes()[..ascii.len() / 2].to_vec(),
            &["facet 2", "EOF"],
        ),
        (
            "ascii_vertex.stl",
            ascii.replacen("vertex 1 0 0", "vertex 1 0", 1).into_bytes(),
            &["facet 0", "vertex"],
        ),
        (
            "ascii_nan.stl",
            ascii
                .replacen("vertex 1 0 0", "vertex 1 NaN 0", 1)
                .into_bytes(),
            &["facet 0"],
        ),
        (
            "ascii_empty.stl",
            b"solid x\nendsolid x\n".to_vec(),
            &["no triangles"],
        ),
        (
            "binary_empty.stl",
            mf::stl_binary(&SoupMesh::default(), "x"),
            &["no triangles"],
        ),
    ];
    check_errors(&dir, cases);
    // "solid" with no name is ASCII STL too.
    let m = write_load(
        &dir,
        "noname.stl",
        ascii.replacen("solid test", "solid", 1).as_bytes(),
    )
    .unwrap();
    assert_eq!((m.positions.len(), m.triangles.len()), (4, 4));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_gltf_files_are_errors_naming_the_file_and_element() {
    let dir = temp("bad-gltf");
    let t = tetra();
    let (nodes, roots) = mf::one_node();
    let glb = mf::glb(std::slice::from_ref(&t), &nodes, &roots);
    let json = mf::gltf_embedded(std::slice::from_ref(&t), &nodes, &roots);
    let (ext_json, bin) = mf::gltf_with_bin(std::slice::from_ref(&t), &nodes, &roots, "t.bin");
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    std::fs::write(dir.join("short.bin"), &bin[..bin.len() - 4]).unwrap();
    // Positions: 4 × 12 bytes at 0; indices: 12 u32 at 48. In the GLB the BIN chunk's data
    // starts after the 12-byte header, the JSON chunk and the BIN chunk header.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin_at = 12 + 8 + json_len + 8;
    let mut bad_index = glb.clone();
    bad_index[bin_at + 48 + 4 * 7..bin_at + 48 + 4 * 8].copy_from_slice(&99u32.to_le_bytes());
    let mut nan = glb.clone();
    nan[bin_at + 12 * 2..bin_at + 12 * 2 + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let cases: Vec<(&str, Vec<u8>, &[&str])> = vec![
        (
            "index.glb",
            bad_index,
            &[
                "mesh 0 primitive 0",
                "index 7: vertex 99 out of range (POSITION has 4 vertices",
            ],
        ),
        ("nan.glb", nan, &["accessor 0", "vertex 2", "non-finite"]),
        (
            "truncated.glb",
            glb[..glb.len() - 20].to_vec(),
            &["not a valid glTF file"],
        ),
        ("header.glb", glb[..10].to_vec(), &["not a valid glTF file"]),
        ("empty.gltf", Vec::new(), &["not a valid glTF file"]),
        (
            "syntax.gltf",
            json.replacen('{', "[", 1).into_bytes(),
            &["not a valid glTF file"],
        ),
        (
            "count.gltf",
            json.replacen("\"count\":4", "\"count\":4000000", 1)
                .into_bytes(),
            &["accessor 0", "do not fit"],
        ),
        (
            "indices_count.gltf",
            json.replacen("\"count\":12", "\"count\":11", 1)
                .into_bytes(),
            &["mesh 0 primitive 0", "not a multiple of 3"],
        ),
        (
            "view.gltf",
            json.replacen("\"byteLength\":48", "\"byteLength\":4800", 1)
                .into_bytes(),
            &["bufferView 0", "beyond"],
        ),
        (
            "accessor_ref.gltf",
            json.replacen("\"POSITION\":0", "\"POSITION\":7", 1)
                .into_bytes(),
            &["mesh 0 primitive 0", "accessor 7, but the file has 2"],
        ),
        (
            "type.gltf",
            json.replacen("\"type\":\"VEC3\"", "\"type\":\"VEC2\"", 1)
                .into_bytes(),
            &["accessor 0", "expected VEC3 of FLOAT"],
        ),
        (
            "base64.gltf",
            json.replacen(";base64,", ";base64,!!", 1).into_bytes(),
            &["buffer 0", "base64"],
        ),
        (
            "missing_bin.gltf",
            ext_json.replace("t.bin", "no_such.bin").into_bytes(),
            &["buffer 0", "no_such.bin"],
        ),
        (
            "short_bin.gltf",
            ext_json.replace("t.bin", "short.bin").into_bytes(),
            &["buffer 0", "fewer than its byteLength"],
        ),
        (
            "absolute.gltf",
            ext_json.replace("t.bin", "/dev/zero").into_bytes(),
            &["buffer 0", "not a relative file name"],
        ),
        (
            "cycle.gltf",
            json.replacen("{\"mesh\":0}", "{\"mesh\":0,\"children\":[0]}", 1)
                .into_bytes(),
            &["node 0"],
        ),
        (
            "points.gltf",
            json.replacen("\"mode\":4", "\"mode\":0", 1).into_bytes(),
            &["no triangles", "1 point or line primitive"],
        ),
    ];
    check_errors(&dir, cases);
    // The control: each form loads.
    for (name, bytes) in [
        ("ok.glb", glb.clone()),
        ("ok.gltf", json.clone().into_bytes()),
        ("ext.gltf", ext_json.clone().into_bytes()),
    ] {
        let m = write_load(&dir, name, &bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.triangles.len(), 4, "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
