//! Point and spot lights on the convolution sweep (issue 41; docs/how-it-works.md "Point and spot
//! lights"): a hard point light's shadow of an opaque half-plane on a receiver wall against its
//! closed form (the line from the light through the edge, the light `cos / d²` on the lit side),
//! for an orthographic and a perspective camera; a translucent medium under a spot light and a
//! point light beside a directional light against the shadow-ray reference (an independent
//! renderer: shadow rays, no light buffers), lights behind every mesh (a turned-round pass)
//! lighting a cloud from behind and lights amid the meshes (two passes, one per side) against it
//! too; the same bits on both CPU paths at any thread count.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{Aov, CpuPath, RenderRequest, render, render_reference};
use convshadow::reference::point_edge::{self, H, View, wall_point};
use glam::DVec3;

/// The plate-and-wall scene of `point_edge`, `width × height`, 64 slabs.
fn plate_and_wall(size: (usize, usize), camera: &str, light: &str) -> Scene {
    let text = point_edge::scene_toml(size, camera, 64, light);
    Scene::parse(&text, "point_sweep", Path::new(".")).unwrap()
}

#[test]
fn a_hard_point_lights_shadow_on_a_wall_is_its_closed_form_on_the_sweep() {
    // The light at P; the plate's edge (x = 0, z = ±H) casts the line x = min over the two
    // corners of P_x − P_x·(1 − P_z)/(z − P_z) on the wall. A wall point X on the lit side gets
    // (1 − P_z)/|X − P|³ (the cosine of the direction to P over the squared distance), 0 beyond.
    let cameras = [
        // (camera lines, a perspective camera's focal length in pixels)
        ("direction = [0.0, 0.0, 1.0]\nview_width = 2.0", None),
        (
            "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 1.0]\n\
             fov_deg = 8.0",
            Some(4.0 / (4.0f64).to_radians().tan()),
        ),
    ];
    for (camera, focal) in cameras {
        for p in [DVec3::new(0.2, 0.1, -2.0), DVec3::new(0.6, -0.3, -1.2)] {
            let light = format!("kind = \"point\"\nposition = [{}, {}, {}]", p.x, p.y, p.z);
            let scene = plate_and_wall((64, 8), camera, &light);
            let r = render(&scene, &RenderRequest::default()).unwrap();
            let line = [-H, H]
                .map(|z| p.x - p.x * (1.0 - p.z) / (z - p.z))
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            let view = focal.map_or(View::Orthographic(2.0), View::Perspective);
            let px = view.pixel_on_wall(64);
            for row in 0..8usize {
                let mut crossing: Option<f64> = None;
                let mut last: Option<(f64, f64, f64)> = None;
                for i in 0..64usize {
                    let (eye, dir) = view.ray((64, 8), (i, row));
                    let Some(x) = wall_point(eye, dir) else {
                        continue;
                    };
                    let d = (x - p).length();
                    let lit = (1.0 - p.z) / (d * d * d);
                    let got = f64::from(r.image.data[3 * (row * 64 + i)]);
                    // Two pixels from the line, exactly the closed form.
                    if (x.x - line).abs() > 2.0 * px {
                        let want = if x.x < line { lit } else { 0.0 };
                        assert!(
                            (got - want).abs() <= 1e-4 * lit,
                            "{camera} P {p}: pixel ({i}, {row}) at x {}: {got} vs {want}",
                            x.x
                        );
                    }
                    // Where the normalised light crosses ½, between pixel centres.
                    let level = got / lit;
                    if let Some((x0, l0, _)) = last
                        && (l0 >= 0.5) != (level >= 0.5)
                        && crossing.is_none()
                    {
                        crossing = Some(x0 + (x.x - x0) * (l0 - 0.5) / (l0 - level));
                    }
                    last = Some((x.x, level, lit));
                }
                let crossing = crossing.expect("the row crosses the shadow line");
                assert!(
                    (crossing - line).abs() <= 0.5 * px,
                    "{camera} P {p}: row {row}: the line at {crossing}, projected {line} (px {px})"
                );
            }
        }
    }
}

#[test]
fn a_soft_point_lights_penumbra_on_a_wall_matches_the_integrated_visibility_on_the_sweep() {
    // The light of radius r at P past the plate: the wall point X gets V(X)·cos/|X − P|², V the
    // visibility integrated over the light's Gaussian in the test (`point_lights::visibility`).
    // The sweep's profile over the wall, normalised by the unshadowed cos/|X − P|², against V,
    // 128 × 16 px, penumbrae of 3–4 px; the edge's rasterization on the light's grid (up to half
    // a cell) is the error left, so it falls with `light_resolution`.
    let cameras = [
        ("direction = [0.0, 0.0, 1.0]\nview_width = 2.0", None),
        (
            "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, 1.0]\n\
             fov_deg = 4.0",
            Some(8.0 / (2.0f64).to_radians().tan()),
        ),
    ];
    let (w, h) = (128usize, 16usize);
    for (camera, focal) in cameras {
        for (p, r) in [
            (DVec3::new(0.2, 0.1, -2.0), 0.1),
            (DVec3::new(0.6, -0.3, -1.2), 0.05),
        ] {
            let light = format!(
                "kind = \"point\"\nposition = [{}, {}, {}]\nradius = {r}",
                p.x, p.y, p.z
            );
            let mut rmse_at = Vec::new();
            for light_resolution in [1.0, 4.0] {
                let mut scene = plate_and_wall((w, h), camera, &light);
                scene.sweep.light_resolution = light_resolution;
                let image = render(&scene, &RenderRequest::default())
                    .unwrap()
                    .image
                    .data;
                let view = focal.map_or(View::Orthographic(2.0), View::Perspective);
                let (rmse, n) = point_edge::wall_rmse(&image, (w, h), view, p, r);
                eprintln!(
                    "{camera:?}, P {p}, r {r}, light_resolution {light_resolution}: RMSE \
                     {rmse:.3e} over {n} wall pixels"
                );
                rmse_at.push(rmse);
            }
            let [one, four] = rmse_at[..] else {
                unreachable!()
            };
            // Near the light's axis (P₁: the edge's rays 6° off the view axis) the issue's bar,
            // the grid's cells the error left (it falls with `light_resolution`). 27° off (P₂)
            // the grid's light takes the blur of the light's depth extent at one slope (the
            // middle of what it sees, 21° off here): across the edge 5 % narrow in σ at the
            // edge's. A looser bar, and no convergence to claim (docs/how-it-works.md).
            if p.x < 0.5 {
                assert!(four <= 5e-3, "{camera:?} P {p} r {r}: RMSE {rmse_at:?}");
                assert!(four < 0.6 * one, "{camera:?} P {p} r {r}: RMSE {rmse_at:?}");
            } else {
                assert!(four <= 8e-3, "{camera:?} P {p} r {r}: RMSE {rmse_at:?}");
            }
        }
    }
}

/// The same soft light's penumbra in an image only 8 rows high: the light's grid spans what the
/// eye sees and a read beyond it is the unoccluded light, so until the grid reached past the
/// eye's rows by the penumbra's reach (2026-12-07) the penumbra gathered light from beyond the
/// grid's top and bottom rows — there is none, the plate runs on — and the shadow came out
/// brighter: RMSE 7.0e-3 at `light_resolution` 4 (4.6e-3 at 16 rows; 0.067 with the light level
/// with the middle rows, y = 0), now 4.3e-3. The issue's bar at 4, as for the taller image above.
#[test]
fn a_soft_point_lights_penumbra_in_an_image_a_few_rows_high_is_as_right_as_in_a_tall_one() {
    let (w, h) = (128usize, 8usize);
    let (p, r) = (DVec3::new(0.2, 0.1, -2.0), 0.1);
    let light = format!(
        "kind = \"point\"\nposition = [{}, {}, {}]\nradius = {r}",
        p.x, p.y, p.z
    );
    let mut scene = plate_and_wall(
        (w, h),
        "direction = [0.0, 0.0, 1.0]\nview_width = 2.0",
        &light,
    );
    scene.sweep.light_resolution = 4.0;
    let image = render(&scene, &RenderRequest::default())
        .unwrap()
        .image
        .data;
    let (rmse, n) = point_edge::wall_rmse(&image, (w, h), View::Orthographic(2.0), p, r);
    eprintln!("128 × 8, light_resolution 4: RMSE {rmse:.3e} over {n} wall pixels");
    assert!(rmse <= 5e-3, "RMSE {rmse:.3e}");
}

/// A translucent box (a Henyey–Greenstein medium) on a white wall in a 64 × 48 view by
/// `camera`, lit by `lights` (`[[light]]` tables).
fn medium_scene(camera: &str, lights: &str) -> Scene {
    let meshes = r#"
[[mesh]]
shape = "box"
size = [1.0, 1.0, 0.6]
translate = [0.2, 0.0, 0.0]
material = "cloud"
[[mesh]]
shape = "box"
size = [8.0, 8.0, 0.02]
translate = [0.0, 0.0, 1.01]
material = "wall"
[material.cloud]
color = [1.0, 0.8, 0.6]
opacity = 0.8
phase = { g = 0.4 }
[material.wall]
color = [1.0, 1.0, 1.0]"#;
    small_scene(camera, lights, meshes, "point_medium")
}

const ORTHOGRAPHIC: &str = "direction = [0.0, 0.0, 1.0]\nview_width = 3.0";
const PERSPECTIVE: &str = "projection = \"perspective\"\neye = [0.3, -0.2, -3.0]\nlook_at = [0.0, 0.0, 1.0]\nfov_deg = 50.0";
/// A spot with a soft cone edge and a point light beside a directional light.
const LIGHTS: [&str; 2] = [
    "[[light]]\nkind = \"spot\"\nposition = [0.9, -0.6, -1.5]\ndirection = [-0.25, 0.2, 1.0]\n\
     cone_deg = 25.0\nfalloff_deg = 8.0\ncolor = [4.0, 4.0, 4.0]",
    "[[light]]\ntilt_deg = [10.0, 0.0]\nvariance = [0.0, 0.0]\ncolor = [0.3, 0.3, 0.3]\n\
     [[light]]\nkind = \"point\"\nposition = [-0.5, 0.4, -1.0]\ncolor = [2.0, 1.5, 1.0]",
];

#[test]
fn point_and_spot_lights_on_media_match_the_shadow_ray_reference() {
    // The reference traces a shadow ray from every shading point (a hard light: all its samples
    // at the centre); the sweep carries the light on the light's own grid. They differ where a
    // pixel straddles a shadow edge (the grid's bilinear read) and by the slab's sampling.
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        for lights in LIGHTS {
            let scene = medium_scene(camera, lights);
            let sweep = render(&scene, &RenderRequest::default()).unwrap();
            let reference = render_reference(&scene, 0, 1, 1 << 30, false, &[], None).unwrap();
            let (a, b) = (&sweep.image.data, &reference.image.data);
            let peak = b.iter().fold(0.0f32, |m, &v| m.max(v));
            let rmse = root_mean_square(a, b);
            eprintln!("{camera:?} / {lights:?}: RMSE {rmse:.3e} of a peak {peak}");
            assert!(peak > 0.1, "the scene is lit");
            assert!(rmse <= 5e-3 * f64::from(peak), "RMSE {rmse} (peak {peak})");
        }
    }
}

#[test]
fn point_lights_have_the_same_bits_on_both_paths_at_any_thread_count() {
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        // Before the meshes, behind them (a turned-round pass) and amid them (both).
        let scenes = (LIGHTS
            .map(|lights| medium_scene(camera, lights))
            .into_iter())
        .chain(BACK_LIGHTS.map(|lights| backlit_scene(camera, lights)))
        .chain(AMID_LIGHTS.map(|lights| amid_scene(camera, lights)));
        for scene in scenes {
            let with = |path, threads| {
                let req = RenderRequest {
                    path,
                    threads,
                    ..RenderRequest::default()
                };
                render(&scene, &req).unwrap().image.data
            };
            let simd = with(CpuPath::Simd, 2);
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&simd), bits(&with(CpuPath::Scalar, 1)), "{camera}");
            assert_eq!(bits(&simd), bits(&with(CpuPath::Simd, 1)), "{camera}");
        }
    }
}

#[test]
fn a_scene_with_point_lights_is_the_sum_of_its_light_layers_and_background() {
    // A directional light, a soft point light and a light towards the viewer (its own pass):
    // each light's layer is a sweep of its own with the others dark, so the image must be their
    // sum plus the background where nothing covers it.
    let lights = "[[light]]\ntilt_deg = [10.0, 5.0]\nvariance = [0.01, 0.01]\n\
                  color = [0.3, 0.3, 0.3]\n\
                  [[light]]\nkind = \"point\"\nposition = [-0.5, 0.4, -1.0]\nradius = 0.05\n\
                  color = [2.0, 1.5, 1.0]\n\
                  [[light]]\ndirection = [0.3, 0.0, -1.0]\ncolor = [0.2, 0.2, 0.2]";
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        let mut scene = medium_scene(camera, lights);
        scene.image.background = [0.1, 0.2, 0.3];
        let req = RenderRequest {
            aovs: vec![Aov::Light(2), Aov::Light(0), Aov::Light(1)],
            ..RenderRequest::default()
        };
        let r = render(&scene, &req).unwrap();
        let order: Vec<usize> = r.light_layers.iter().map(|(l, _)| *l).collect();
        assert_eq!(order, [2, 0, 1], "the layers in request order");
        let mut worst = 0.0f32;
        for (k, v) in r.image.data.iter().enumerate() {
            let lights: f32 = r.light_layers.iter().map(|(_, layer)| layer[k]).sum();
            let background = (1.0 - r.alpha[k / 3]) * scene.image.background[k % 3];
            worst = worst.max((v - (lights + background)).abs());
        }
        assert!(worst < 1e-5, "{camera}: largest difference {worst}");
        assert!(
            r.light_layers[2].1.iter().any(|&v| v > 0.01),
            "the point light lights"
        );
    }
}

#[test]
fn a_point_light_whose_grid_would_be_too_large_is_refused_by_name() {
    // A light a hair before a wide wall sees it at nearly 90° either way: its grid (tangents of
    // the view axis at the eye's cell size) would pass 16384 cells a side.
    let scene = plate_and_wall(
        (64, 8),
        "direction = [0.0, 0.0, 1.0]\nview_width = 8.0",
        "kind = \"point\"\nposition = [0.0, 0.0, -0.006]",
    );
    let e = render(&scene, &RenderRequest::default())
        .err()
        .expect("refused");
    let msg = e.to_string();
    assert!(
        matches!(e, convshadow::pipeline::RenderError::OutOfMemory(_))
            && msg.contains("light[0]")
            && msg.contains("16384"),
        "{msg}"
    );
}

/// A translucent cloud (Henyey–Greenstein g = 0.4, so a light behind it makes it glow) and a
/// small opaque plate between it and `lights`, placed behind both: nothing else.
fn backlit_scene(camera: &str, lights: &str) -> Scene {
    let plate = "[[mesh]]\nshape = \"box\"\nsize = [0.3, 0.3, 0.1]\ntranslate = [0.6, 0.05, 0.6]\n\
                 material = \"plate\"";
    let meshes = format!("{CLOUD}\n{plate}\n{CLOUD_AND_PLATE_MATERIALS}");
    small_scene(camera, lights, &meshes, "point_backlit")
}

/// The backlit and amid scenes' translucent cloud, 1.4 × 1.0 × 0.6 at the origin.
const CLOUD: &str = "[[mesh]]\nshape = \"box\"\nsize = [1.4, 1.0, 0.6]\nmaterial = \"cloud\"";
/// Their materials: the cloud (Henyey–Greenstein g = 0.4, so a light behind it makes it glow)
/// and a white plate.
const CLOUD_AND_PLATE_MATERIALS: &str = "[material.cloud]\ncolor = [1.0, 0.8, 0.6]\n\
                                         opacity = 0.6\nphase = { g = 0.4 }\n\
                                         [material.plate]\ncolor = [1.0, 1.0, 1.0]";

/// Lights behind every mesh: a hard point light, and a spot pointing back at the viewer with a
/// soft cone edge.
const BACK_LIGHTS: [&str; 2] = [
    "[[light]]\nkind = \"point\"\nposition = [2.0, -0.1, 2.5]\ncolor = [8.0, 8.0, 8.0]",
    "[[light]]\nkind = \"spot\"\nposition = [1.8, 0.2, 2.4]\ndirection = [-0.6, -0.05, -1.0]\n\
     cone_deg = 20.0\nfalloff_deg = 8.0\ncolor = [9.0, 8.0, 7.0]",
];

#[test]
fn point_and_spot_lights_behind_every_mesh_match_the_shadow_ray_reference() {
    // The light travels towards the viewer: its pass is turned round (its grid looks back along
    // the view from the light, the eye composites back to front). The reference traces shadow
    // rays from every shading point towards the light's centre. The plate's shadow runs
    // obliquely through the cloud, its edges rasterized on the light's grid: at light
    // resolution 1 RMSE 3e-3–1e-2 of the peak, at 4 within 5e-3 of it and lower.
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        for lights in BACK_LIGHTS {
            let mut scene = backlit_scene(camera, lights);
            let reference = render_reference(&scene, 0, 1, 1 << 30, false, &[], None).unwrap();
            let b = &reference.image.data;
            let peak = b.iter().fold(0.0f32, |m, &v| m.max(v));
            assert!(peak > 0.1, "the scene is lit");
            let mut rmse = [0.0f64; 2];
            for (k, resolution) in [1.0, 4.0].into_iter().enumerate() {
                scene.sweep.light_resolution = resolution;
                let sweep = render(&scene, &RenderRequest::default()).unwrap();
                assert_eq!(sweep.turned_round_lights, 1, "a turned-round pass");
                let a = &sweep.image.data;
                rmse[k] = root_mean_square(a, b) / f64::from(peak);
            }
            eprintln!(
                "behind, {camera:?} / {lights:?}: RMSE / peak {:.3e} (1), {:.3e} (4)",
                rmse[0], rmse[1]
            );
            assert!(rmse[1] <= 5e-3 && rmse[1] < rmse[0], "RMSE / peak {rmse:?}");
        }
    }
}

/// A translucent cloud in front of `lights` (Henyey–Greenstein g = 0.4: lit from behind, it
/// glows towards the viewer) and behind them a small opaque plate over a wall: lights at view
/// depth 0.75, amid the meshes.
fn amid_scene(camera: &str, lights: &str) -> Scene {
    let behind = "[[mesh]]\nshape = \"box\"\nsize = [0.4, 0.4, 0.1]\ntranslate = [-0.1, 0.1, 1.15]\n\
                  material = \"plate\"\n\
                  [[mesh]]\nshape = \"box\"\nsize = [8.0, 8.0, 0.02]\ntranslate = [0.0, 0.0, 1.8]\n\
                  material = \"plate\"";
    let meshes = format!("{CLOUD}\n{behind}\n{CLOUD_AND_PLATE_MATERIALS}");
    small_scene(camera, lights, &meshes, "point_amid")
}

/// Lights amid the meshes: a hard point light, a spot pointing away from the viewer with a soft
/// cone edge, a soft point light.
const AMID_LIGHTS: [&str; 3] = [
    "[[light]]\nkind = \"point\"\nposition = [0.2, 0.1, 0.75]\ncolor = [3.0, 3.0, 3.0]",
    "[[light]]\nkind = \"spot\"\nposition = [0.2, 0.1, 0.75]\ndirection = [-0.1, 0.0, 1.0]\n\
     cone_deg = 25.0\nfalloff_deg = 8.0\ncolor = [3.0, 3.0, 3.0]",
    "[[light]]\nkind = \"point\"\nposition = [0.2, 0.1, 0.75]\nradius = 0.05\n\
     color = [3.0, 3.0, 3.0]",
];

#[test]
fn point_and_spot_lights_amid_the_meshes_match_the_shadow_ray_reference() {
    // The cloud in front of the light is lit by a turned-round pass, the plate and the wall
    // behind it by an ordinary one, and the eye sees the second through the first. The
    // reference traces shadow rays from every shading point (a soft light: 256 of its points);
    // they differ along the plate's shadow edges (the light's grid) and by the slabs' sampling.
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        for lights in AMID_LIGHTS {
            let scene = amid_scene(camera, lights);
            let samples = if lights.contains("radius") { 256 } else { 1 };
            let reference = render_reference(&scene, 0, samples, 1 << 30, false, &[], None);
            let b = &reference.unwrap().image.data;
            let sweep = render(&scene, &RenderRequest::default()).unwrap();
            let a = &sweep.image.data;
            let peak = b.iter().fold(0.0f32, |m, &v| m.max(v));
            let rmse = root_mean_square(a, b) / f64::from(peak);
            eprintln!("amid, {camera:?} / {lights:?}: RMSE / peak {rmse:.3e}");
            assert!(peak > 1.0, "the scene is lit");
            // Either side left out would be off by its whole image (the cloud's glow, the lit
            // plate and wall).
            assert!(rmse <= 5e-3, "RMSE / peak {rmse}");
        }
    }
}

#[test]
fn a_light_amid_the_meshes_keeps_the_background_layers_and_depth_of_the_whole_scene() {
    // The amid light's pass alone, on a grey background, with its light layer and the depth
    // layer: the image is the layer plus the background where the composited opacity leaves
    // it, and the depth layer (the nearer side's first hit where it has one, else the far
    // side's) is a directional light's, whose eye sees every mesh at once.
    for camera in [ORTHOGRAPHIC, PERSPECTIVE] {
        let mut scene = amid_scene(camera, AMID_LIGHTS[2]);
        scene.image.background = [0.1, 0.2, 0.3];
        let req = RenderRequest {
            aovs: vec![Aov::Light(0), Aov::Depth],
            ..RenderRequest::default()
        };
        let r = render(&scene, &req).unwrap();
        let layer = &r.light_layers[0].1;
        let mut worst = 0.0f32;
        for (k, v) in r.image.data.iter().enumerate() {
            let background = (1.0 - r.alpha[k / 3]) * scene.image.background[k % 3];
            worst = worst.max((v - (layer[k] + background)).abs());
        }
        assert!(worst < 1e-5, "{camera}: largest difference {worst}");
        // Where the wall is seen, the composited opacity is 1: no background.
        assert!(
            r.alpha.iter().all(|&a| a > 0.999),
            "{camera}: the wall covers the view"
        );
        let mut directional = amid_scene(camera, "[[light]]\ncolor = [1.0, 1.0, 1.0]");
        directional.image.background = scene.image.background;
        let whole = render(&directional, &req).unwrap();
        let (depth, want) = (r.depth.unwrap(), whole.depth.unwrap());
        for (d, w) in depth.iter().zip(&want) {
            assert!(
                (d - w).abs() <= 1e-5 * w.abs().max(1.0),
                "{camera}: depth {d} vs {w}"
            );
        }
    }
}

#[test]
fn the_lamp_example_renders_amid_its_meshes_like_the_shadow_ray_reference() {
    // scenes/perspective/lamp.toml, small: a soft point light between a cloud in front of it
    // and a ball, a ring and a wall behind it. At 60 × 40 and 64 slabs, M = 16: RMSE 0.025
    // (M = 64: 0.025; the reference's own noise between the two, 0.0045), most of it at the
    // ring's and the ball's outlines, a pixel being a sixteenth of the gallery's; at 120 × 80,
    // 128 slabs, M = 64: 0.012 (README).
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/perspective/lamp.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = Scene::parse(&text, "lamp.toml", path.parent().unwrap()).unwrap();
    scene.image.width = 60;
    scene.image.height = 40;
    scene.sweep.slabs = convshadow::common::model::scene::SlabSpec::Count(64);
    let sweep = render(&scene, &RenderRequest::default()).unwrap();
    let reference = render_reference(&scene, 0, 16, 1 << 30, false, &[], None).unwrap();
    let (a, b) = (&sweep.image.data, &reference.image.data);
    let rmse = root_mean_square(a, b);
    let mean = b.iter().map(|&v| f64::from(v)).sum::<f64>() / b.len() as f64;
    eprintln!("lamp example, 60 × 40: RMSE {rmse:.4} (mean level {mean:.3})");
    assert!(mean > 0.1, "the scene is lit");
    assert!(rmse <= 0.035, "RMSE {rmse}");
}

/// The root-mean-square difference of two images' values.
fn root_mean_square(a: &[f32], b: &[f32]) -> f64 {
    let sum: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
    (sum / a.len() as f64).sqrt()
}

/// A 64 × 48 scene on a black background, 96 slabs, seen by `camera` and lit by `lights`
/// (`[[light]]` tables), with `meshes` (its meshes' and materials' tables), named `name`.
fn small_scene(camera: &str, lights: &str, meshes: &str, name: &str) -> Scene {
    let text = format!(
        "[image]\nwidth = 64\nheight = 48\nbackground = [0.0, 0.0, 0.0]\n[camera]\n{camera}\n\
         [sweep]\nslabs = 96\n{lights}\n{meshes}"
    );
    Scene::parse(&text, name, Path::new(".")).unwrap()
}
