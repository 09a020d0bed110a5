//! Shared helpers for the integration tests (every test binary declares `mod support;`): the
//! kernel list, scene fixtures, the test RNG, temporary folders, running the binary; [`gpu`]:
//! the GPU tests' adapter and small scenes.
#![allow(dead_code)]

pub mod gpu;

use glam::DVec3;
use std::path::{Path, PathBuf};

use convshadow::common::model::kernel::KERNEL_NAMES;
use convshadow::common::model::scene::Scene;

/// The one kernel list of `common`, with `gaussian:K` at K = 7 (the same code as 19, a fraction
/// of the taps) and `ellipse5` (an N other than 2 and 3): the grid the golden hashes record.
pub fn kernels() -> Vec<&'static str> {
    let mut out: Vec<&'static str> = KERNEL_NAMES
        .iter()
        .map(|&k| {
            if k.starts_with("gaussian:") {
                "gaussian:7"
            } else {
                k
            }
        })
        .collect();
    out.insert(3, "ellipse5");
    out
}

/// The one test RNG: a counter through the project's `mix32`.
#[allow(unused_imports)] // not every test binary draws random numbers
pub use convshadow_testkit::TestRng;

/// `../shared/models` beside the repository, or `None` (with a loud message) when it is missing;
/// a failure under CI (`convshadow_testkit::models_dir`).
pub fn models_dir() -> Option<PathBuf> {
    convshadow_testkit::models_dir(Path::new(env!("CARGO_MANIFEST_DIR")))
}

/// `../shared/volumes` beside the repository, as [`models_dir`].
pub fn volumes_dir() -> Option<PathBuf> {
    convshadow_testkit::volumes_dir(Path::new(env!("CARGO_MANIFEST_DIR")))
}

/// Whether the example scene at `path` can be rendered here: the `../shared` folders it reads
/// exist (a loud skip otherwise, a failure under CI).
pub fn example_scene_inputs_present(path: &Path) -> bool {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    convshadow_testkit::shared_inputs_present(Path::new(env!("CARGO_MANIFEST_DIR")), &text)
}

/// A scene from TOML text (paths resolve against `base`).
pub fn scene(text: &str, base: &Path) -> Scene {
    Scene::parse(text, "test-scene.toml", base).unwrap_or_else(|e| panic!("{e}"))
}

/// A unique temporary folder for one test, removed when the test passes (a failing test keeps
/// it, and says where, so its files can be looked at).
pub fn temp_dir(name: &str) -> TestDir {
    let d = std::env::temp_dir().join(format!("convshadow-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TestDir(d)
}

/// A test's temporary folder ([`temp_dir`]): a path that removes its folder when dropped,
/// unless the test is failing.
#[derive(Debug)]
pub struct TestDir(PathBuf);

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept the failing test's files in {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The names of the files in `dir`, sorted (outputs, temporary `.partial` files, anything).
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
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

/// One opaque box filling a `size`² view and nothing between it and the light: every shadow
/// ray leaves the scene unblocked, so the sweep and the shadow-ray reference see light 1.
pub fn lone_box_scene(size: u32, slabs: u32) -> String {
    format!(
        r#"
[image]
width = {size}
height = {size}
[camera]
view_width = 4.0
[sweep]
slabs = {slabs}
optimal_distance = 0.5
[[light]]
tilt_deg = [20.0, 10.0]
variance = [0.02, 0.02]
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.5]
material = "m"
[material.m]
color = [0.8, 0.6, 0.4]
"#
    )
}

/// The closed models of `../shared/models` (their parity must be exact).
#[allow(dead_code)] // the contract and gpu tests' only
pub const CLOSED_MODELS: [&str; 9] = [
    "bunny.obj",
    "bunny_hr.obj",
    "spot.obj",
    "spot_remeshed_lowres.obj",
    "armadillo.obj",
    "armadillo_100k.obj",
    "torus.obj",
    "sphere.obj",
    "cube.obj",
];

/// The text of a `width × height` scene seen by a perspective camera at `eye` looking at
/// `look_at` (world points, `[x, y, z]`) with a vertical field of view of `fov_deg` (`extra`:
/// more `[camera]` lines), 32 slabs, whose meshes are `meshes` (`[[mesh]]` tables, each naming
/// material `m`).
#[allow(dead_code)] // the contract, cli and gpu tests' only
pub fn perspective_scene_text(
    (width, height): (u32, u32),
    (eye, look_at): (DVec3, DVec3),
    fov_deg: f64,
    extra: &str,
    meshes: &str,
) -> String {
    let v = |p: DVec3| format!("[{:e}, {:e}, {:e}]", p.x, p.y, p.z);
    format!(
        r#"
[image]
width = {width}
height = {height}
[camera]
projection = "perspective"
eye = {}
look_at = {}
fov_deg = {fov_deg:e}
{extra}
[sweep]
slabs = 32
optimal_distance = 0.5
{meshes}
[material.m]
"#,
        v(eye),
        v(look_at)
    )
}

/// A ball on a floor running back from it, seen by a `width × height` perspective camera at
/// `eye` looking at the ball's centre (the origin) with a vertical field of view of `fov_deg`;
/// `extra` adds lines to `[camera]`.
#[allow(dead_code)] // the cli and gpu tests' only
pub fn perspective_ball_scene(
    width: u32,
    height: u32,
    eye: DVec3,
    fov_deg: f64,
    extra: &str,
) -> String {
    let meshes = "[[mesh]]\nshape = \"sphere\"\nsize = [1.0, 4]\nmaterial = \"m\"\n\
                  [[mesh]]\nshape = \"box\"\nsize = [6.0, 0.2, 20.0]\n\
                  translate = [0.0, -1.2, 8.0]\nmaterial = \"m\"";
    perspective_scene_text((width, height), (eye, DVec3::ZERO), fov_deg, extra, meshes)
}

/// The text of a perspective view of a translucent open square (a thin shell) tilted 60° under
/// a translucent ball, lit by the `[[light]]` tables `lights`; the square's OBJ is written into
/// `dir`.
#[allow(dead_code)] // the accuracy and gpu tests' only
pub fn perspective_shell_scene_text(dir: &Path, lights: &str) -> String {
    std::fs::write(
        dir.join("square.obj"),
        "v -1.5 -1.5 0\nv 1.5 -1.5 0\nv 1.5 1.5 0\nv -1.5 1.5 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    format!(
        "[image]\nwidth = 48\nheight = 32\n[camera]\nprojection = \"perspective\"\n\
         eye = [0.0, 1.0, -5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 40\n[sweep]\nslabs = 48\n\
         [[mesh]]\nshape = \"obj\"\npath = \"square.obj\"\nrotate_deg = [60.0, 0.0, 0.0]\n\
         material = \"m\"\n[[mesh]]\nshape = \"sphere\"\nsize = [0.5, 3]\n\
         translate = [0.0, 0.5, 1.0]\nmaterial = \"g\"\n[material.m]\nopacity = 0.4\n\
         [material.g]\nopacity = 0.6\ntransport = [0.8, 0.5, 0.2]\n{lights}"
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
    match convshadow::io::obj::load_obj(obj) {
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

/// A 4×4 EXR in `dir` whose every value is 0.25 but pixel (1, 2) channel 0, which is `at`.
#[allow(dead_code)] // the cli tests' only
pub fn exr_with(dir: &Path, name: &str, at: f32) {
    let mut data = vec![0.25f32; 4 * 4 * 3];
    data[(2 * 4 + 1) * 3] = at;
    convshadow::io::image::RgbImage {
        width: 4,
        height: 4,
        data,
    }
    .save(&dir.join(name))
    .unwrap();
}

/// A scene that reaches the shader paths the example scenes may not (the GPU tests'
/// `render::path_scene`: every detail kind in 3D and 4D, a 3D texture, both highlights on opaque
/// and translucent crossings, Lambert and flat surfaces, phase functions, a guard band, grey or
/// coloured light): its text, its 3D texture written into `dir`.
pub fn path_scene_text(dir: &std::path::Path, monochrome: bool, jitter: bool) -> String {
    let dims = [5u32, 4, 3];
    let voxels: Vec<u8> = (0..60u32).map(|i| (i * 37 % 256) as u8).collect();
    std::fs::write(dir.join("tex.raw"), &voxels).unwrap();
    let transport = if monochrome {
        "[0.3, 0.3, 0.3]"
    } else {
        "[0.6, 0.4, 0.2]"
    };
    format!(
        r#"
[image]
width = 40
height = 36
background = [0.1, 0.2, 0.3]
[camera]
direction = [0.2, -0.3, 1.0]
view_width = 5.0
[sweep]
slabs = 20
optimal_distance = 0.7
jitter = {jitter}
seed = 99
guard_band = 3
[[light]]
color = [1.0, 0.8, 0.6]
tilt_deg = [-35.0, 20.0]
variance = [0.03, 0.005]
rotation_deg = 30.0
[[light]]
color = [0.3, 0.4, 0.9]
tilt_deg = [10.0, -5.0]
variance = [0.0, 0.0]
[[light]]
color = [0.2, 0.2, 0.2]
tilt_deg = [60.0, 0.0]
variance = [0.08, 0.08]
[[mesh]]
shape = "sphere"
size = [0.7, 3]
translate = [-1.1, -0.9, 0.0]
material = "perlin4"
[[mesh]]
shape = "torus"
size = [0.6, 0.25, 24]
translate = [0.9, -0.9, 0.2]
rotate_deg = [50.0, 10.0, 0.0]
material = "ridged"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
translate = [-1.0, 1.0, 0.3]
rotate_deg = [20.0, 30.0, 0.0]
material = "tex"
[[mesh]]
shape = "sphere"
size = [0.6, 2]
translate = [1.0, 1.0, -0.2]
material = "turb"
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.3]
translate = [0.0, 0.0, 1.5]
material = "wall"
[[mesh]]
shape = "sphere"
size = [0.4, 3]
translate = [0.0, 0.0, -0.6]
material = "glossy"
[material.perlin4]
detail = {{ kind = "perlin", frequency = 2.0, time = 0.37 }}
gradient = [[0.0, 0.9, 0.2, 0.1, 0.0], [1.0, 1.0, 0.9, 0.5, 0.9]]
transport = {transport}
reference_length = 0.05
[material.ridged]
detail = {{ kind = "ridged", frequency = 1.5, octaves = 3, time = -2.5 }}
gradient = [[0.0, 0.2, 0.9, 0.2, 0.0], [0.6, 0.5, 0.9, 0.5, 0.4], [1.0, 1.0, 1.0, 1.0, 1.0]]
transport = {transport}
reference_length = 0.05
specular = {{ model = "ashikmin-shirley", exponent = 17, f0 = 0.3, strength = 0.8 }}
phase = {{ g = 0.5 }}
[material.tex]
texture = {{ path = "tex.raw", dims = [{}, {}, {}], type = "u8" }}
gradient = [[0.0, 1.0, 1.0, 1.0, 0.0], [1.0, 0.9, 0.6, 0.3, 1.0]]
transport = {transport}
reference_length = 0.05
[material.turb]
detail = {{ kind = "turbulence", frequency = 3.0, octaves = 4, lacunarity = 2.3, gain = 0.6 }}
gradient = [[0.0, 0.1, 0.1, 0.1, 0.1], [1.0, 0.9, 0.9, 0.9, 0.8]]
transport = {transport}
reference_length = 0.05
specular = {{ strength = 0.5, exponent = 4 }}
phase = {{ g = -0.4 }}
surface = "flat"
[material.wall]
color = [0.8, 0.8, 0.75]
opacity = 1.0
specular = {{ strength = 0.2, exponent = 64 }}
[material.glossy]
color = [0.7, 0.3, 0.2]
opacity = 1.0
specular = {{ model = "ashikmin-shirley", exponent = 40 }}
"#,
        dims[0], dims[1], dims[2]
    )
}

/// The orthographic camera of `path_scene_text` seen instead in perspective from in front and
/// above, off the axis.
pub fn perspective_path_scene(dir: &std::path::Path, monochrome: bool, jitter: bool) -> Scene {
    let scene = scene(&perspective_path_scene_text(dir, monochrome, jitter), dir);
    assert!(scene.camera.is_perspective());
    scene
}

/// The text of [`perspective_path_scene`].
pub fn perspective_path_scene_text(
    dir: &std::path::Path,
    monochrome: bool,
    jitter: bool,
) -> String {
    let text = path_scene_text(dir, monochrome, jitter);
    let ortho = "[camera]\ndirection = [0.2, -0.3, 1.0]\nview_width = 5.0\n";
    assert!(text.contains(ortho), "the shader-path scene's camera moved");
    text.replacen(
        ortho,
        "[camera]\nprojection = \"perspective\"\neye = [-1.5, 2.0, -7.0]\n\
         look_at = [0.2, -0.2, 0.4]\nfov_deg = 48\n",
        1,
    )
}
