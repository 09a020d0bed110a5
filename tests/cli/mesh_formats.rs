//! PLY, glTF 2.0 and STL meshes through the CLI: the bunny converted in the test (by
//! `convshadow_testkit::mesh_files`, independent of the loaders) gives the OBJ bunny's
//! `ldi_hash`, and malformed files of every format exit with code 3 naming the file, without a
//! panic.

use crate::support;

use std::path::Path;

use convshadow_testkit::mesh_files::{self as mf, PlyEncoding, SoupMesh};

/// Exit code for a bad scene or mesh file.
const BAD_INPUT: i32 = 3;

/// `ldi` on a scene framing the bunny (framed by the OBJ's bounds) with the mesh file `mesh`:
/// (exit code, ldi_hash or "", stderr).
fn ldi_hash(dir: &Path, scene_text: &str, obj: &Path, mesh: &Path) -> (i32, String, String) {
    let scene = dir.join(format!(
        "{}.toml",
        mesh.file_name().unwrap().to_string_lossy()
    ));
    let text = scene_text.replace(
        &format!("path = \"{}\"", obj.display()),
        &format!("path = \"{}\"", mesh.display()),
    );
    assert!(text.contains(&mesh.display().to_string()));
    std::fs::write(&scene, text).unwrap();
    let json = dir.join("stats.json");
    let _ = std::fs::remove_file(&json);
    let (code, out, err) = support::run_cli(
        &[
            "ldi",
            scene.to_str().unwrap(),
            "--stats-json",
            json.to_str().unwrap(),
        ],
        dir,
    );
    assert!(!err.contains("panicked"), "{}: {err}", mesh.display());
    let hash = if code == 0 {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        v["ldi_hash"].as_str().unwrap().to_string()
    } else {
        String::new()
    };
    (code, hash, format!("{out}{err}"))
}

/// Every encoding the loaders read, of `m`: (file name, bytes), written into `dir` (a glTF's
/// `.bin` too).
fn write_conversions(dir: &Path, m: &SoupMesh) -> Vec<std::path::PathBuf> {
    let one = std::slice::from_ref(m);
    let (nodes, roots) = mf::one_node();
    let (json, bin) = mf::gltf_with_bin(one, &nodes, &roots, "bunny.bin");
    std::fs::write(dir.join("bunny.bin"), bin).unwrap();
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("bunny_ascii.ply", mf::ply(m, PlyEncoding::Ascii, false)),
        ("bunny_le.ply", mf::ply(m, PlyEncoding::LittleEndian, false)),
        ("bunny_be.ply", mf::ply(m, PlyEncoding::BigEndian, true)),
        ("bunny_ascii.stl", mf::stl_ascii(m)),
        ("bunny_bin.stl", mf::stl_binary(m, "solid bunny")),
        ("bunny.gltf", json.into_bytes()),
        (
            "bunny_embedded.gltf",
            mf::gltf_embedded(one, &nodes, &roots).into_bytes(),
        ),
        ("bunny.glb", mf::glb(one, &nodes, &roots)),
    ];
    files
        .into_iter()
        .map(|(name, bytes)| {
            let p = dir.join(name);
            std::fs::write(&p, bytes).unwrap();
            p
        })
        .collect()
}

#[test]
fn ply_gltf_and_stl_bunnies_give_the_obj_bunnys_ldi_hash() {
    let Some(models) = support::models_dir() else {
        return;
    };
    let dir = support::temp_dir("mesh-formats");
    let obj = models.join("bunny.obj");
    let scene_text = support::framed_obj_scene(&obj, 256, 1.2);
    let (code, reference, log) = ldi_hash(&dir, &scene_text, &obj, &obj);
    assert_eq!(code, 0, "{log}");
    let soup = mf::read_obj_triangles(&std::fs::read_to_string(&obj).unwrap());
    for mesh in write_conversions(&dir, &soup) {
        let (code, hash, log) = ldi_hash(&dir, &scene_text, &obj, &mesh);
        let name = mesh.file_name().unwrap().to_string_lossy();
        assert_eq!(code, 0, "{name}: {log}");
        assert_eq!(hash, reference, "{name}: ldi_hash differs from the OBJ's");
        eprintln!("{name}: ldi_hash {hash} (OBJ {reference})");
    }
    // A different mesh gives a different hash (the comparison can fail): one triangle fewer,
    // an open mesh (a thin shell).
    let mut fewer = soup.clone();
    fewer.triangles.pop();
    let p = dir.join("fewer.stl");
    std::fs::write(&p, mf::stl_binary(&fewer, "x")).unwrap();
    let (code, hash, log) = ldi_hash(&dir, &scene_text, &obj, &p);
    assert_eq!(code, 0, "an open mesh is a thin shell: {log}");
    assert!(log.contains("thin shell"), "{log}");
    assert!(
        !hash.is_empty() && hash != reference,
        "{hash} vs {reference}"
    );
}

#[test]
fn malformed_ply_gltf_and_stl_files_exit_3_naming_the_file() {
    let dir = support::temp_dir("bad-mesh-formats");
    let tetra = mf::read_obj_triangles(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    );
    let ply = String::from_utf8(mf::ply(&tetra, PlyEncoding::Ascii, false)).unwrap();
    let stl = mf::stl_binary(&tetra, "x");
    let (nodes, roots) = mf::one_node();
    let glb = mf::glb(std::slice::from_ref(&tetra), &nodes, &roots);
    let gltf = mf::gltf_embedded(std::slice::from_ref(&tetra), &nodes, &roots);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "index.ply",
            ply.replace("3 1 2 3\n", "3 1 2 99\n").into_bytes(),
            "face 3: index 99 out of range",
        ),
        (
            "count.ply",
            ply.replace("element vertex 4", "element vertex 400")
                .into_bytes(),
            "wrong count",
        ),
        (
            "truncated.ply",
            ply.as_bytes()[..ply.len() - 9].to_vec(),
            "face",
        ),
        ("truncated.stl", stl[..stl.len() - 1].to_vec(), "truncated"),
        ("empty.stl", Vec::new(), "not a valid STL file"),
        (
            "truncated.glb",
            glb[..glb.len() - 8].to_vec(),
            "not a valid glTF file",
        ),
        (
            "count.gltf",
            gltf.replacen("\"count\":12", "\"count\":13", 1)
                .into_bytes(),
            "accessor 1",
        ),
        (
            "points.gltf",
            gltf.replacen("\"mode\":4", "\"mode\":1", 1).into_bytes(),
            "no triangles",
        ),
    ];
    let control = dir.join("ok.glb");
    std::fs::write(&control, &glb).unwrap();
    let scene_for = |mesh: &Path| {
        let scene = dir.join(format!(
            "{}.toml",
            mesh.file_name().unwrap().to_string_lossy()
        ));
        std::fs::write(&scene, support::obj_scene(mesh, 32, 4.0)).unwrap();
        scene
    };
    let (code, out, err) = support::run_cli(&["ldi", scene_for(&control).to_str().unwrap()], &dir);
    assert_eq!(code, 0, "the control must load: {out}{err}");
    for (name, bytes, what) in cases {
        let mesh = dir.join(name);
        std::fs::write(&mesh, bytes).unwrap();
        let (code, out, err) = support::run_cli(&["ldi", scene_for(&mesh).to_str().unwrap()], &dir);
        assert!(!err.contains("panicked"), "{name}: {err}");
        assert_eq!(code, BAD_INPUT, "{name}: {out}{err}");
        assert!(
            err.contains(name),
            "{name}: the message names the file: {err}"
        );
        assert!(err.contains(what), "{name}: expected {what:?} in {err}");
    }
}
