//! Shared helpers for the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use convshadow::common::scene::Scene;

/// Every kernel family; `gaussian:7` stands for `gaussian:K` (same code, fewer taps, faster).
pub const KERNELS: [&str; 9] = [
    "ellipse2",
    "ellipse3",
    "ellipse2:slab",
    "ellipse5",
    "dirac",
    "poisson8",
    "poisson16",
    "gaussian:7",
    "box",
];

/// `../shared/models` beside the repository, or `None` (with a loud message) when it is missing.
/// Under CI (env `CI` set) a missing folder is a failure, not a skip.
pub fn models_dir() -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/models");
    if dir.is_dir() {
        Some(dir)
    } else if std::env::var_os("CI").is_some() {
        panic!("../shared/models not found next to the repository (required in CI)");
    } else {
        eprintln!("SKIP: ../shared/models not found next to the repository; model tests skipped");
        None
    }
}

/// A scene from TOML text (paths resolve against `base`).
pub fn scene(text: &str, base: &Path) -> Scene {
    Scene::parse(text, "test-scene.toml", base).unwrap_or_else(|e| panic!("{e}"))
}

/// A unique temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("convshadow-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs the binary with arguments; returns (exit code, stdout, stderr).
pub fn run_cli(args: &[&str], cwd: &Path) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_convshadow"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the binary runs");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A one-mesh scene around an OBJ file, camera framing a box of half-size `half`.
pub fn obj_scene(path: &Path, width: u32, view_width: f64) -> String {
    format!(
        r#"
[image]
width = {width}
height = {width}
[camera]
direction = [0.3, -0.2, 1.0]
view_width = {view_width}
[sweep]
slabs = 64
optimal_distance = 0.5
[[mesh]]
shape = "obj"
path = "{}"
material = "m"
[material.m]
"#,
        path.display()
    )
}

/// The text of a scene framing an OBJ file (centred on its bounds, `margin` × its largest
/// extent across); a fixed 4-unit view when the file does not load.
pub fn framed_obj_scene(obj: &Path, width: u32, margin: f64) -> String {
    match convshadow::common::mesh::load_obj(obj) {
        Ok(m) => {
            let (lo, hi) = m.bounds();
            let c = (lo + hi) * 0.5;
            obj_scene(obj, width, (hi - lo).max_element() * margin).replace(
                "direction = [0.3, -0.2, 1.0]",
                &format!(
                    "direction = [0.3, -0.2, 1.0]\ncenter = [{}, {}, {}]",
                    c.x, c.y, c.z
                ),
            )
        }
        Err(_) => obj_scene(obj, width, 4.0),
    }
}
