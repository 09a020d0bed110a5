//! The perspective camera's eye pass on the GPU (`gpu/src/eye.rs`, `shaders/eye.wgsl`): on
//! lavapipe the same image, alpha and final grid light bits as the CPU's
//! `sweep_perspective` — every shader path (detail, textures, specular, phase functions, jitter,
//! grey and coloured light), every kernel with both penumbra models, fov 30° and 90°, `near`,
//! second-order media, a patterned light and lights travelling towards the eye (the
//! turned-round pass); on other adapters within docs/gpu.md's thresholds.

use crate::render::{check, check_distance, run};
use crate::support;
use crate::support::gpu as gpu_common;

use convshadow::common::model::scene::{Media, PatternSpec, Penumbra, SlabSpec};
use convshadow::pipeline::Backend;
use convshadow::reference::half_plane_sheet::{
    SLAB_DISTANCE, SheetLight, W, perspective_scene_toml,
};
use glam::DVec3;

#[test]
fn gpu_perspective_image_equals_cpu_on_every_shader_path() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-perspective-paths");
    for (monochrome, jitter) in [(false, true), (true, false)] {
        let scene = support::perspective_path_scene(&dir, monochrome, jitter);
        assert_eq!(scene.is_monochrome(), monochrome);
        let what = format!("perspective shader paths, monochrome {monochrome}, jitter {jitter}");
        check(&ctx, &scene, &what);
        check_distance(&ctx, &scene, &what);
    }
    // Second-order media (a medium's part of its entry and exit slabs) and pre-integrated
    // materials (the eye reads their detail on the slab's faces along its ray).
    let mut scene = support::perspective_path_scene(&dir, false, true);
    scene.sweep.media = Media::SecondOrder;
    scene.sweep.preintegration = true;
    scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
    check(
        &ctx,
        &scene,
        "perspective, second-order media, pre-integration",
    );
}

#[test]
fn gpu_perspective_image_equals_cpu_for_every_kernel_and_both_penumbrae() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let text = support::perspective_ball_scene(40, 32, DVec3::new(1.0, 2.5, -6.0), 40.0, "");
    let text = format!(
        "{text}color = [0.9, 0.8, 0.7]\n[[light]]\ndirection = [0.3, -1.0, 0.5]\n\
         variance = [0.02, 0.01]\nrotation_deg = 20.0\n"
    );
    let mut scene = support::scene(&text, &support::temp_dir("gpu-perspective-kernels"));
    for kernel in support::kernels() {
        scene.sweep.kernel = kernel.parse().unwrap();
        scene.sweep.penumbra = Penumbra::Iterated;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        check(&ctx, &scene, &format!("perspective ball, kernel {kernel}"));
        if kernel != "box" {
            let cpu = run(&scene, Backend::Cpu);
            assert_eq!(cpu.image.width, 40, "the eye's image, not the grid's");
            check_distance(&ctx, &scene, &format!("perspective ball, kernel {kernel}"));
        }
    }
}

#[test]
fn gpu_perspective_image_equals_cpu_at_fov_30_and_90_with_near_and_a_pattern() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-perspective-near");
    let gobo = gpu_common::write_gobo(&dir, (5, 4), (41, 7, 89));
    for fov in [30.0, 90.0] {
        for near in ["", "near = 2.0"] {
            let text =
                support::perspective_ball_scene(36, 28, DVec3::new(-0.5, 1.5, -4.0), fov, near);
            let mut scene = support::scene(&text, &dir);
            scene.lights[0].pattern = Some(PatternSpec {
                path: gobo.clone(),
                size: [2.5, 1.9],
                center: [0.3, -0.2],
            });
            scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
            check(
                &ctx,
                &scene,
                &format!("perspective ball, fov {fov}, {near:?}, gobo"),
            );
        }
    }
}

#[test]
fn gpu_perspective_image_equals_cpu_at_other_light_resolutions() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-perspective-light-resolution");
    for (s, toward) in [(0.5, false), (2.0, false), (1.5, true)] {
        let text = support::perspective_ball_scene(36, 28, DVec3::new(-0.5, 1.5, -4.0), 50.0, "");
        // A soft light from behind the eye, and one travelling towards it: the turned-round
        // pass's grid too.
        let mut text =
            format!("{text}[[light]]\ntilt_deg = [10.0, 5.0]\nvariance = [0.02, 0.01]\n");
        if toward {
            text.push_str("[[light]]\ndirection = [0.2, -0.3, -1.0]\nvariance = [0.01, 0.01]\n");
        }
        let mut scene = support::scene(&text, &dir);
        scene.sweep.light_resolution = s;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        let what = format!("perspective ball, light_resolution {s}, towards the eye {toward}");
        check(&ctx, &scene, &what);
        check_distance(&ctx, &scene, &what);
    }
    // An orthographic camera's eye reading a grid of its own, with a light towards it.
    for s in [0.5, 2.0] {
        let text = support::path_scene_text(&dir, false, true);
        let mut scene = support::scene(
            &format!("{text}\n[[light]]\ndirection = [0.2, -0.3, -1.0]\nvariance = [0.01, 0.01]\n"),
            &dir,
        );
        scene.sweep.light_resolution = s;
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        check(
            &ctx,
            &scene,
            &format!("orthographic shader paths, light_resolution {s}"),
        );
    }
}

#[test]
fn gpu_perspective_image_equals_cpu_with_lights_towards_the_eye() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // The shader-path scene with a fourth light travelling towards the eye (its own pass from
    // the far end, added to the front pass's image), and the half-plane and sheet lit only
    // from behind them (the turned-round pass alone).
    let dir = support::temp_dir("gpu-perspective-back");
    for (monochrome, jitter) in [(false, true), (true, false)] {
        let text = support::perspective_path_scene_text(&dir, monochrome, jitter);
        let text = format!(
            "{text}\n[[light]]\ncolor = [0.7, 0.9, 0.5]\ndirection = [0.3, -0.2, -1.0]\n\
             variance = [0.01, 0.02]\n"
        );
        let scene = support::scene(&text, &dir);
        let passes = scene.passes();
        assert!(passes.front.is_some() && passes.back.is_some());
        let what = format!("perspective, a light towards the eye, monochrome {monochrome}");
        let cpu = check(&ctx, &scene, &what);
        assert_eq!(cpu.turned_round_lights, 1);
        check_distance(&ctx, &scene, &what);
    }
    // A pattern on the light towards the eye (the far end's initial light buffer).
    let gobo = gpu_common::write_gobo(&dir, (6, 5), (29, 3, 83));
    let text = support::perspective_path_scene_text(&dir, false, true);
    let text = format!(
        "{text}\n[[light]]\ndirection = [0.3, -0.2, -1.0]\nvariance = [0.01, 0.02]\n\
         pattern = {{ path = {:?}, size = [3.0, 2.5], center = [0.4, -0.3] }}\n",
        gobo.to_str().unwrap()
    );
    let scene = support::scene(&text, &dir);
    assert!(scene.lights[3].toward_viewer && scene.lights[3].pattern.is_some());
    check(
        &ctx,
        &scene,
        "perspective, a patterned light towards the eye",
    );
    let (eye, look_at) = ([0.0, 0.0, W + 1.0], [0.0, 0.0, W]);
    for penumbra in ["distance", "iterated"] {
        let sweep = format!("penumbra = \"{penumbra}\"\noptimal_distance = {W}");
        let text = perspective_scene_toml(eye, look_at, 90.0, SheetLight::ROTATED, &sweep);
        let mut scene = support::scene(&text, &dir);
        // The thin sheet takes out 4.5 % of what it passes: a bright light makes it visible.
        scene.lights[0].color = [20.0; 3];
        // Five times the accuracy test's slab distance: the sheet still spans two slabs, and
        // the bits need no more (about 100 slabs, not 500, on lavapipe).
        scene.sweep.slabs = SlabSpec::Distance(5.0 * SLAB_DISTANCE);
        scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
        assert!(scene.passes().front.is_none());
        check(
            &ctx,
            &scene,
            &format!("perspective sheet lit from behind, {penumbra}"),
        );
    }
}

#[test]
fn gpu_perspective_gallery_scene_equals_cpu() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // scenes/perspective/floor.toml, small (its lights: a key from above, a fill along the view).
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/perspective/floor.toml");
    let mut scene = convshadow_io::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.image.width = 64;
    scene.image.height = 40;
    scene.sweep.slabs = convshadow::common::model::scene::SlabSpec::Count(48);
    scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
    check(&ctx, &scene, "scenes/perspective/floor.toml");
}

#[test]
fn gpu_perspective_image_equals_cpu_with_a_thin_shell() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    // A translucent open square (a thin shell) tilted under a translucent ball: the eye's read
    // leaves out the grid pixels on the shell's far side from each light (through it, for the
    // light from behind the eye; not yet through it, for the light towards the eye from above).
    let dir = support::temp_dir("gpu-perspective-shell");
    let text = support::perspective_shell_scene_text(
        &dir,
        "[[light]]\ndirection = [0.1, -0.3, 1.0]\n\
         [[light]]\ndirection = [0.1, -1.2, -1.0]\nvariance = [0.01, 0.01]\n",
    );
    let scene = support::scene(&text, &dir);
    let g = convshadow_io::build_geometry(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(g.shell_meshes(), vec![0], "the square is a shell");
    check(
        &ctx,
        &scene,
        "perspective, a thin shell, lights from both ends",
    );
}
