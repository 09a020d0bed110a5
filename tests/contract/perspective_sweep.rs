//! The perspective camera's eye pass keeps the sweep's contracts (`cpu/src/sweep/eye.rs`): the
//! same image and alpha bits on the scalar path (one pixel at a time) and the SIMD path (a row's
//! samples shaded eight at a time on the lanes, runs of pixels with nothing to do skipped), at
//! any thread count, and with or without the early finish, which stops the sweep once every eye
//! pixel is opaque (front to back only).

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{CpuPath, RenderRequest, Rendered, render};

use crate::support;

fn run(scene: &Scene, path: CpuPath, threads: usize, every_slab: bool) -> Rendered {
    let req = RenderRequest {
        path,
        threads,
        every_slab,
        allow_open: true,
        ..RenderRequest::default()
    };
    render(scene, &req).unwrap_or_else(|e| panic!("{}: {e}", scene.source))
}

fn bits(r: &Rendered) -> Vec<u32> {
    let image = r.image.data.iter().map(|v| v.to_bits());
    image.chain(r.alpha.iter().map(|v| v.to_bits())).collect()
}

/// A detail-filled ball and an opaque, glossy box in front of an opaque wall that fills the
/// view, seen in perspective 53 pixels wide (rows end in a partial run of pixels); `lights`
/// appended.
fn walled_scene(lights: &str) -> Scene {
    let text = format!(
        r#"
[image]
width = 53
height = 40
[camera]
projection = "perspective"
eye = [0.3, 0.8, -5.0]
look_at = [0.0, 0.0, 0.5]
fov_deg = 40
[sweep]
slabs = 64
[[mesh]]
shape = "sphere"
size = [0.8, 3]
translate = [-0.4, 0.0, 0.0]
material = "cloud"
[[mesh]]
shape = "box"
size = [0.6, 0.6, 0.6]
translate = [0.7, 0.3, 0.4]
rotate_deg = [20.0, 35.0, 0.0]
material = "glossy"
[[mesh]]
shape = "box"
size = [12.0, 12.0, 0.2]
translate = [0.0, 0.0, 1.5]
material = "wall"
[material.cloud]
detail = {{ kind = "fbm", frequency = 3.0, octaves = 3 }}
gradient = [[0.0, 0.9, 0.6, 0.4, 0.0], [1.0, 1.0, 0.9, 0.8, 0.9]]
transport = [0.6, 0.4, 0.2]
reference_length = 0.05
[material.glossy]
color = [0.7, 0.3, 0.2]
specular = {{ strength = 0.4, exponent = 16 }}
[material.wall]
color = [0.8, 0.8, 0.75]
{lights}"#
    );
    support::scene(&text, std::path::Path::new("."))
}

#[test]
fn perspective_images_are_the_same_bits_on_both_paths_any_thread_count_and_early_finish() {
    let dir = support::temp_dir("perspective-sweep-paths");
    let from_behind = "[[light]]\ndirection = [0.3, -0.5, 1.0]\nvariance = [0.01, 0.02]\n\
                       [[light]]\ncolor = [0.2, 0.3, 0.5]\nvariance = [0.05, 0.05]\n";
    let towards_eye = "[[light]]\ncolor = [0.7, 0.9, 0.5]\ndirection = [0.3, -0.2, -1.0]\n\
                       variance = [0.01, 0.01]\n";
    let mut scenes = vec![
        ("walled", walled_scene(from_behind)),
        (
            "walled, a light towards the eye",
            walled_scene(&format!("{from_behind}{towards_eye}")),
        ),
        (
            "thin shell",
            support::scene(
                &support::perspective_shell_scene_text(&dir, from_behind),
                &dir,
            ),
        ),
    ];
    for (monochrome, jitter) in [(false, true), (true, false)] {
        scenes.push((
            "shader paths",
            support::perspective_path_scene(&dir, monochrome, jitter),
        ));
    }
    // Pre-integrated materials: the detail on the slab's faces along each ray.
    let mut pre = support::perspective_path_scene(&dir, false, true);
    pre.sweep.preintegration = true;
    pre.revalidate().unwrap_or_else(|e| panic!("{e}"));
    scenes.push(("shader paths, pre-integrated", pre));
    let text = support::perspective_path_scene_text(&dir, false, true);
    scenes.push((
        "shader paths, a light towards the eye",
        support::scene(&format!("{text}\n{towards_eye}"), &dir),
    ));
    // Light grids finer and coarser than the eye's pixels (`sweep.light_resolution`), for a
    // perspective camera and an orthographic one (whose eye then reads a grid of its own).
    for s in [0.5, 2.5] {
        let mut scene = walled_scene(&format!("{from_behind}{towards_eye}"));
        scene.sweep.light_resolution = s;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        scenes.push(("walled, another light resolution", scene));
        let text = support::path_scene_text(&dir, false, true);
        let mut scene = support::scene(&format!("{text}\n{towards_eye}"), &dir);
        assert!(!scene.camera.is_perspective());
        scene.sweep.light_resolution = s;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        scenes.push(("orthographic shader paths, another light resolution", scene));
    }
    for (what, scene) in &scenes {
        let reference = run(scene, CpuPath::Scalar, 1, true);
        for (path, threads, every_slab) in [
            (CpuPath::Scalar, 1, false),
            (CpuPath::Simd, 1, true),
            (CpuPath::Simd, 1, false),
            (CpuPath::Simd, 3, false),
        ] {
            let r = run(scene, path, threads, every_slab);
            assert!(
                bits(&r) == bits(&reference),
                "{what}: {path:?}, {threads} threads, every slab {every_slab}: not the bits of \
                 the scalar path's sweep of every slab"
            );
        }
    }
}

#[test]
fn a_perspective_sweep_stops_once_every_eye_pixel_is_opaque() {
    let lights = "[[light]]\ndirection = [0.3, -0.5, 1.0]\nvariance = [0.01, 0.02]\n";
    let scene = walled_scene(lights);
    let every = run(&scene, CpuPath::Simd, 1, true);
    let early = run(&scene, CpuPath::Simd, 1, false);
    assert_eq!(every.slabs_swept, every.plan.slabs);
    assert!(
        every.alpha.iter().all(|&a| a == 1.0),
        "the wall fills the view"
    );
    assert!(
        early.slabs_swept < early.plan.slabs,
        "the wall makes every eye pixel opaque before the last slab, yet {} of {} slabs were \
         swept",
        early.slabs_swept,
        early.plan.slabs
    );
    assert!(bits(&every) == bits(&early));
    // A light towards the eye composites back to front: nearer slabs still change an opaque
    // pixel, so that pass sweeps every slab (the front pass may stop).
    let both = walled_scene(&format!(
        "{lights}[[light]]\ndirection = [0.3, -0.2, -1.0]\nvariance = [0.01, 0.01]\n"
    ));
    assert!(both.passes().back.is_some());
    let (every, early) = (
        run(&both, CpuPath::Simd, 1, true),
        run(&both, CpuPath::Simd, 1, false),
    );
    assert!(bits(&every) == bits(&early));
}
