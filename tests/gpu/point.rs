//! Point and spot lights on the GPU (`gpu/src/shaders/eye.wgsl` `point_terms`, the point grid's
//! projective material map and ψ depth scale in `shading.wgsl` and `kernels.wgsl`): on lavapipe
//! the same image and final grid light bits as the CPU's point passes — a soft spot with a
//! falloff and a pattern, a soft point light beside a directional one, a soft point light behind
//! every mesh (a turned-round pass; the scene's opaque wall taken out), a hard point light with
//! the iterated penumbra, over every shader path (detail, textures, specular, phase functions,
//! jitter), for an orthographic and a perspective camera.

use crate::render::check;
use crate::support;
use crate::support::gpu as gpu_common;

use convshadow::common::model::scene::Penumbra;

/// The shader-path scene's opaque wall behind its meshes.
const WALL: &str = "[[mesh]]\nshape = \"box\"\nsize = [6.0, 6.0, 0.3]\ntranslate = [0.0, 0.0, 1.5]\n\
                    material = \"wall\"\n";

/// The shader-path scene's three directional lights, replaced by each case's.
const PATH_SCENE_LIGHTS: &str = "[[light]]\ncolor = [1.0, 0.8, 0.6]";

#[test]
fn gpu_point_and_spot_lights_equal_cpu_for_both_cameras() {
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-point-lights");
    gpu_common::write_gobo(&dir, (5, 3), (7, 3, 11));
    let cases = [
        (
            "soft spot, falloff, pattern",
            "[[light]]\nkind = \"spot\"\nposition = [0.4, -0.6, -3.0]\n\
             direction = [-0.1, 0.15, 1.0]\nradius = 0.05\ncone_deg = 18.0\nfalloff_deg = 9.0\n\
             color = [9.0, 8.0, 7.0]\n\
             pattern = { path = \"gobo.png\", size = [0.9, 0.6], center = [0.05, -0.02] }\n",
        ),
        (
            "directional and soft point",
            "[[light]]\ncolor = [0.3, 0.3, 0.3]\ntilt_deg = [10.0, -5.0]\n\
             variance = [0.01, 0.01]\n\
             [[light]]\nkind = \"point\"\nposition = [-0.8, 0.5, -2.5]\nradius = 0.08\n\
             color = [6.0, 5.0, 4.0]\n",
        ),
        (
            "soft point behind every mesh",
            "[[light]]\nkind = \"point\"\nposition = [0.5, -0.4, 6.0]\nradius = 0.1\n\
             color = [30.0, 28.0, 25.0]\n",
        ),
        (
            "hard point, iterated penumbra",
            "[[light]]\nkind = \"point\"\nposition = [0.6, 0.3, -2.8]\n\
             color = [7.0, 7.0, 6.0]\n",
        ),
    ];
    for perspective in [false, true] {
        let text = if perspective {
            support::perspective_path_scene_text(&dir, false, true)
        } else {
            support::path_scene_text(&dir, false, true)
        };
        let start = text
            .find(PATH_SCENE_LIGHTS)
            .expect("the path scene's lights");
        let end = text.find("[[mesh]]").expect("the path scene's meshes");
        for (what, lights) in cases {
            let mut text = format!("{}{lights}{}", &text[..start], &text[end..]);
            if what.contains("behind") {
                // The opaque wall behind the scene would hide a light behind it.
                assert!(text.contains(WALL), "the path scene's wall");
                text = text.replacen(WALL, "", 1);
            }
            let mut scene = support::scene(&text, &dir);
            if what.contains("iterated") {
                scene.sweep.penumbra = Penumbra::Iterated;
                scene.revalidate().unwrap_or_else(|e| panic!("{e}"));
            }
            let what = format!("{what}, perspective {perspective}");
            let cpu = check(&ctx, &scene, &what);
            // A scene of one point light has the point pass's plan: its grid is projective, and
            // a soft light's distance penumbra runs in ψ.
            if scene.lights.len() == 1 {
                let soft = !what.contains("hard");
                assert!(
                    cpu.plan.projective.is_some(),
                    "{what}: a point light's grid"
                );
                assert_eq!(cpu.plan.depth_scale.is_some(), soft, "{what}: ψ");
            }
            assert!(
                cpu.image.data.iter().any(|&v| v > 0.5),
                "{what}: the light lights the scene"
            );
            let behind = what.contains("behind");
            assert_eq!(cpu.turned_round_lights, usize::from(behind), "{what}");
        }
    }
}

#[test]
fn gpu_lights_amid_the_meshes_equal_cpu_for_both_cameras() {
    // Two passes per light (the meshes in front of it turned round, those behind it not), each
    // on the GPU as on the CPU, composited on the host: the same bits.
    let Some(ctx) = gpu_common::gpu() else {
        return;
    };
    let dir = support::temp_dir("gpu-amid-lights");
    let meshes = "[[mesh]]\nshape = \"box\"\nsize = [1.4, 1.0, 0.6]\nmaterial = \"cloud\"\n\
                  [[mesh]]\nshape = \"box\"\nsize = [0.4, 0.4, 0.1]\n\
                  translate = [-0.1, 0.1, 1.15]\nmaterial = \"plate\"\n\
                  [[mesh]]\nshape = \"box\"\nsize = [8.0, 8.0, 0.02]\n\
                  translate = [0.0, 0.0, 1.8]\nmaterial = \"plate\"\n\
                  [material.cloud]\ncolor = [1.0, 0.8, 0.6]\nopacity = 0.6\nphase = { g = 0.4 }\n\
                  [material.plate]\ncolor = [1.0, 1.0, 1.0]\n";
    for camera in [
        "direction = [0.0, 0.0, 1.0]\nview_width = 3.0",
        "projection = \"perspective\"\neye = [0.3, -0.2, -3.0]\nlook_at = [0.0, 0.0, 1.0]\n\
         fov_deg = 50.0",
    ] {
        for radius in [0.0, 0.05] {
            let text = format!(
                "[image]\nwidth = 48\nheight = 32\n[camera]\n{camera}\n[sweep]\nslabs = 64\n\
                 [[light]]\nkind = \"point\"\nposition = [0.2, 0.1, 0.75]\nradius = {radius}\n\
                 color = [3.0, 3.0, 3.0]\n{meshes}"
            );
            let scene = support::scene(&text, &dir);
            let what = format!("amid, radius {radius}, {camera}");
            let cpu = check(&ctx, &scene, &what);
            assert!(cpu.image.data.iter().any(|&v| v > 0.5), "{what}: lit");
        }
    }
}
