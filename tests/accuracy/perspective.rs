//! The sweep and the shadow-ray reference seen through a perspective camera (issue 42) against
//! the closed form of `convshadow_reference::perspective_edge` (a half-plane before a receiver,
//! the light along the view, the eye off to the side; every pixel's ray traced there) at fields
//! of view of 30° and 90°: the renderers must match it, and their shadow lines must sit where
//! the geometric one projects.

use std::path::Path;

use crate::support;
use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{CpuPath, RenderRequest, render, render_reference};
use convshadow::reference::perspective_edge::{
    EYE, HEIGHT, WIDTH, measure as measure_image, receiver_point, scene_toml,
};

fn scene(fov_deg: f64, sweep: &str) -> Scene {
    let text = scene_toml(fov_deg, sweep);
    Scene::parse(&text, "perspective-edge.toml", Path::new(".")).expect("scene")
}

/// [`measure_image`], printed under `what`.
fn measure(what: &str, fov: f64, image: &[f32]) -> (f64, f64, f64) {
    let (rmse, band, line) = measure_image(fov, image).unwrap_or_else(|e| panic!("{what}: {e}"));
    eprintln!(
        "{what}, fov {fov}: RMSE {rmse:.2e} (penumbra band {band:.2e}); shadow line within \
         {line:.3} px"
    );
    (rmse, band, line)
}

#[test]
fn perspective_reference_matches_the_closed_form_edge_over_a_receiver() {
    for fov in [30.0, 90.0] {
        let r = render_reference(&scene(fov, ""), 0, 256, u64::MAX / 4, false, &[], None)
            .unwrap_or_else(|e| panic!("fov {fov}: {e}"));
        let (rmse, band, line) = measure("reference (M = 256)", fov, &r.image.data);
        assert!(
            rmse <= 5e-3 && band <= 5e-3,
            "fov {fov}: RMSE {rmse:.3e}, band {band:.3e}"
        );
        assert!(line <= 0.5, "fov {fov}: shadow line off by {line:.3} px");
    }
}

#[test]
fn perspective_sweep_matches_the_closed_form_edge_over_a_receiver() {
    let mut failures = Vec::new();
    for penumbra in ["distance", "iterated"] {
        for kernel in convshadow::common::model::kernel::KERNEL_NAMES {
            if (penumbra, kernel) == ("distance", "box") {
                // The one pairing that is off in orthographic views too (edge 0.038–0.044 in the
                // report: docs/accuracy.md): `box` carries fractional widths along a schedule a
                // pixel changing level every slab cannot follow.
                continue;
            }
            for fov in [30.0, 90.0] {
                let sweep = format!("penumbra = \"{penumbra}\"\nkernel = \"{kernel}\"");
                let r = render(&scene(fov, &sweep), &RenderRequest::default())
                    .unwrap_or_else(|e| panic!("fov {fov}: {e}"));
                let what = format!("sweep, {penumbra}, {kernel}");
                let (rmse, band, line) = measure(&what, fov, &r.image.data);
                if rmse > 5e-3 || band > 1.5e-2 || line > 0.5 {
                    failures.push(format!(
                        "{what}, fov {fov}: {rmse:.2e} {band:.2e} {line:.3}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn perspective_sweep_from_camera_near_matches_the_closed_form_too() {
    // The sweep starts at `near` (2.0, before the plate at 4): the slab grid shares its slabs.
    let mut s = scene(30.0, "");
    if let convshadow::common::model::scene::Projection::Perspective { near, .. } =
        &mut s.camera.projection
    {
        *near = Some(2.0);
    }
    let r = render(&s, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
    let (rmse, band, line) = measure("sweep from near = 2", 30.0, &r.image.data);
    assert!(
        rmse <= 5e-3 && band <= 1.5e-2 && line <= 0.5,
        "{rmse:.2e} {band:.2e} {line:.3}"
    );
}

#[test]
fn perspective_light_layers_add_up_to_the_image_and_depth_is_the_view_depth() {
    // Lights from behind the eye and towards it (two passes), each layer a light alone.
    // A third light travels towards the eye: its layer comes from the turned-round pass, and
    // lights the receiver, made translucent, through it.
    let edge = scene_toml(60.0, "");
    let receiver = "[material.receiver]\n";
    assert!(edge.contains(receiver));
    let text = format!(
        "{}\n[[light]]\ndirection = [0.2, -0.4, -1.0]\ncolor = [0.3, 0.6, 0.9]\n",
        edge.replacen(receiver, "[material.receiver]\nopacity = 0.5\n", 1)
    );
    let mut s = Scene::parse(&text, "perspective-edge.toml", Path::new(".")).expect("scene");
    s.lights.insert(1, s.lights[0].clone());
    s.lights[1].color = [0.5, 0.25, 0.125];
    assert!(s.lights[2].toward_viewer);
    let req = RenderRequest {
        aovs: vec![
            convshadow::pipeline::Aov::Light(1),
            convshadow::pipeline::Aov::Depth,
            convshadow::pipeline::Aov::Light(2),
            convshadow::pipeline::Aov::Light(0),
        ],
        ..RenderRequest::default()
    };
    let r = render(&s, &req).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.turned_round_lights, 1);
    assert_eq!(r.light_layers.len(), 3);
    let back = &r.light_layers[1].1;
    assert!(
        back.iter().any(|&v| v > 0.01),
        "the light towards the eye lights something"
    );
    let sum: Vec<f32> = (r.light_layers[0]
        .1
        .iter()
        .zip(back)
        .zip(&r.light_layers[2].1))
    .map(|((a, b), c)| a + b + c)
    .collect();
    let worst = sum
        .iter()
        .zip(&r.image.data)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "layers differ from the image by {worst}");
    // Depth: the receiver's view depth where a pixel's ray meets it first.
    let depth = r.depth.expect("the depth layer");
    let (mut checked, mut worst) = (0, 0.0f64);
    for j in 0..HEIGHT {
        for i in 0..WIDTH {
            if let Some(p) = receiver_point(60.0, i, j) {
                let want = p.z - EYE.z;
                worst = worst.max((f64::from(depth[(j * WIDTH + i) as usize]) - want).abs());
                checked += 1;
            }
        }
    }
    assert!(
        checked > 1000 && worst < 1e-4,
        "{checked} pixels, depth off by {worst:.2e}"
    );
}

#[test]
fn perspective_sweep_is_the_same_bits_on_both_paths_and_any_thread_count() {
    // The edge scene, and the same with a second light travelling towards the eye (its
    // turned-round pass added to the image).
    let back = format!(
        "{}\n[[light]]\ndirection = [0.2, -0.4, -1.0]\ncolor = [0.3, 0.6, 0.9]\n",
        scene_toml(60.0, "").replacen(
            "[material.receiver]\n",
            "[material.receiver]\nopacity = 0.5\n",
            1
        )
    );
    let back = Scene::parse(&back, "perspective-edge.toml", Path::new(".")).expect("scene");
    for s in [scene(60.0, ""), back] {
        let image = |path: CpuPath, threads: usize| {
            let req = RenderRequest {
                path,
                threads,
                ..RenderRequest::default()
            };
            render(&s, &req).expect("render").image_hash
        };
        let simd = image(CpuPath::Simd, 1);
        assert_eq!(image(CpuPath::Scalar, 1), simd, "scalar and SIMD paths");
        assert_eq!(image(CpuPath::Simd, 3), simd, "3 threads");
    }
}

#[test]
fn the_perspective_gallery_scene_stays_near_the_shadow_ray_reference() {
    // scenes/perspective/floor.toml at 128 × 80 and 256 slabs: 0.040 (distance) and 0.039
    // (iterated) from the reference at M = 16 and 64 when recorded (the reference's own
    // M = 16 → 64 change: 3.1e-3); held to +25 %.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/perspective/floor.toml");
    let mut scene = convshadow_io::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.image.width = 128;
    scene.image.height = 80;
    scene.sweep.slabs = convshadow::common::model::scene::SlabSpec::Count(256);
    let reference = render_reference(&scene, 0, 16, u64::MAX / 4, false, &[], None)
        .unwrap_or_else(|e| panic!("{e}"));
    let sweep = render(&scene, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
    let n = reference.image.data.len() as f64;
    let sum: f64 = (sweep.image.data.iter().zip(&reference.image.data))
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
        .sum();
    let rmse = (sum / n).sqrt();
    eprintln!("perspective/floor.toml at 128 × 80: RMSE {rmse:.4} against the reference");
    assert!(rmse <= 0.05, "RMSE {rmse:.4}");
}

/// A light travelling towards a perspective eye (the turned-round pass): the half-plane behind a
/// translucent sheet, both perpendicular to the light, the eye beyond the sheet on the light's
/// axis looking back along it (180° from the light's travel; each ray at up to half the field
/// of view off that), against the closed form along every pixel's ray
/// (`half_plane_sheet::expected_row_perspective`). Horizontal fields of view of 30° and 90°,
/// isotropic and rotated anisotropic lights, both penumbra models (measured: distance
/// 1.2e-3–1.6e-3, iterated 9.5e-3–1.15e-2, as with an orthographic camera); the scalar and SIMD
/// paths give the same bits.
#[test]
fn perspective_sweep_with_a_light_towards_the_eye_matches_the_closed_form() {
    use convshadow::reference::half_plane_sheet::{
        SheetLight, VIEW, W, expected_row_perspective, perspective_scene_toml, profile_rmse,
    };
    let mut failures = Vec::new();
    for fov_x in [30.0f64, 90.0] {
        // The view spans VIEW across at the sheet.
        let distance = 0.5 * VIEW / (0.5 * fov_x.to_radians()).tan();
        let (eye, look_at) = ([0.0, 0.0, W + distance], [0.0, 0.0, W]);
        for light in [SheetLight::ISOTROPIC, SheetLight::ROTATED] {
            let expected = expected_row_perspective(eye, look_at, fov_x, light);
            for penumbra in ["distance", "iterated"] {
                // The iterated penumbra is right at the half-plane's distance to the sheet.
                let sweep = format!("penumbra = \"{penumbra}\"\noptimal_distance = {W}");
                let text = perspective_scene_toml(eye, look_at, fov_x, light, &sweep);
                let s = Scene::parse(&text, "back-light.toml", Path::new("."))
                    .unwrap_or_else(|e| panic!("{e}\n{text}"));
                assert!(s.passes().front.is_none() && s.passes().back.is_some());
                let rendered = |path: CpuPath| {
                    let req = RenderRequest {
                        path,
                        ..RenderRequest::default()
                    };
                    render(&s, &req).unwrap_or_else(|e| panic!("{e}"))
                };
                let simd = rendered(CpuPath::Simd);
                assert_eq!(simd.turned_round_lights, 1);
                let (rmse, n) = profile_rmse(&simd.image.data, &expected)
                    .unwrap_or_else(|e| panic!("fov {fov_x}: {e}"));
                eprintln!(
                    "light towards the eye, fov {fov_x}°, {light:?}, {penumbra}: RMSE {rmse:.2e} \
                     over {n} penumbra pixels"
                );
                // The distance penumbra: the 5e-3. The iterated one is right only at
                // its optimal distance and off by 9.6e-3 (isotropic) and 1.17e-2 (rotated) in
                // this set-up with an orthographic camera at 180° too (measured when written):
                // a guard at 1.5e-2.
                let bound = if penumbra == "distance" { 5e-3 } else { 1.5e-2 };
                if rmse > bound {
                    failures.push(format!("fov {fov_x}, {light:?}, {penumbra}: {rmse:.2e}"));
                }
                if penumbra == "distance" {
                    let scalar = rendered(CpuPath::Scalar);
                    assert_eq!(scalar.image_hash, simd.image_hash, "scalar and SIMD paths");
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The shadow-ray reference with a light travelling towards a perspective eye (its turned-round
/// pass traces on the turned slab grid along the eye's rays) against the same closed form as
/// the sweep above: fov 30° and 90°, M = 256. Measured: isotropic 4.2e-4/4.7e-4 (1.6e-3 at
/// M = 64: the fine strata's 1/M along a principal axis), rotated 1.5e-3 (3.7e-3 at M = 64:
/// M^-3/4 off the axes).
#[test]
fn perspective_reference_with_a_light_towards_the_eye_matches_the_closed_form() {
    use convshadow::reference::half_plane_sheet::{
        SheetLight, VIEW, W, expected_row_perspective, perspective_scene_toml, profile_rmse,
    };
    for (fov_x, light, bound) in [
        (30.0f64, SheetLight::ISOTROPIC, 1e-3),
        (90.0, SheetLight::ISOTROPIC, 1e-3),
        (30.0, SheetLight::ROTATED, 2.5e-3),
        (90.0, SheetLight::ROTATED, 2.5e-3),
    ] {
        let distance = 0.5 * VIEW / (0.5 * fov_x.to_radians()).tan();
        let (eye, look_at) = ([0.0, 0.0, W + distance], [0.0, 0.0, W]);
        let text = perspective_scene_toml(eye, look_at, fov_x, light, "");
        let s = Scene::parse(&text, "back-light.toml", Path::new("."))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        let r = render_reference(&s, 0, 256, u64::MAX / 4, false, &[], None)
            .unwrap_or_else(|e| panic!("fov {fov_x}: {e}"));
        assert_eq!(r.turned_round_lights, 1);
        let expected = expected_row_perspective(eye, look_at, fov_x, light);
        let (rmse, n) =
            profile_rmse(&r.image.data, &expected).unwrap_or_else(|e| panic!("fov {fov_x}: {e}"));
        eprintln!(
            "reference, light towards the eye, fov {fov_x}°, {light:?}: RMSE {rmse:.2e} over {n} \
             pixels"
        );
        assert!(rmse <= bound, "fov {fov_x}, {light:?}: RMSE {rmse:.2e}");
    }
}

/// A floor running back from a perspective eye, a ball on it, lit only by a light travelling
/// towards the eye (a rim light from above and beyond): the sweep against the shadow-ray
/// reference (accuracy.md §2f: the floor is a surface the far end's sweep leaves its mesh
/// through, read one slab back along the light).
#[test]
fn a_perspective_floor_lit_towards_the_eye_against_the_reference() {
    let text = support::perspective_ball_scene(96, 64, glam::DVec3::new(0.0, 2.0, -6.0), 45.0, "");
    let text = format!(
        "{text}color = [0.9, 0.9, 0.9]\n[[light]]\ndirection = [-0.3, -0.6, -1.0]\n\
         variance = [0.004, 0.004]\n"
    );
    let mut s = Scene::parse(&text, "rim.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"));
    s.sweep.slabs = convshadow::common::model::scene::SlabSpec::Count(256);
    s.revalidate().unwrap_or_else(|e| panic!("{e}"));
    assert!(s.passes().front.is_none());
    let reference = render_reference(&s, 0, 16, u64::MAX / 4, false, &[], None)
        .unwrap_or_else(|e| panic!("{e}"));
    let sweep = render(&s, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
    let n = reference.image.data.len() as f64;
    let sum: f64 = (sweep.image.data.iter().zip(&reference.image.data))
        .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
        .sum();
    let mean = reference
        .image
        .data
        .iter()
        .map(|&v| f64::from(v))
        .sum::<f64>()
        / n;
    let rmse = (sum / n).sqrt();
    eprintln!(
        "perspective floor lit towards the eye: RMSE {rmse:.4} against the reference (mean {mean:.4})"
    );
    assert!(
        mean > 0.05,
        "the rim light lights the floor (mean {mean:.4})"
    );
    // Measured 0.0138 (mean 0.117) when written; 0.162, the floor in bands, before the eye read
    // a crossed surface one slab back along the light (accuracy.md §2f). Held to +25 %.
    assert!(rmse <= 0.0175, "RMSE {rmse:.4}");
}

/// A thin shell seen in perspective reads the light arriving at it from the light's side of it:
/// grid pixels already through the shell (or, where the light crosses it the other way from the
/// grid's rays, not yet through it) are left out of the read, as a closed mesh's inside is.
/// Against the reference (M = 16): a light from behind the eye 0.0035 (0.034 before, the shell
/// in bands, reading its own attenuation), a light towards the eye from above 0.0140 (0.0211
/// reading the shell's far side). Held to +25 %.
#[test]
fn a_thin_shell_in_perspective_reads_the_light_from_the_lights_side() {
    let dir = support::temp_dir("perspective-shell");
    for (light, bound) in [
        ("direction = [0.1, -0.3, 1.0]", 0.0045),
        (
            "direction = [0.1, -1.2, -1.0]\nvariance = [0.01, 0.01]",
            0.0175,
        ),
    ] {
        let text = support::perspective_shell_scene_text(&dir, &format!("[[light]]\n{light}\n"));
        let s = support::scene(&text, &dir);
        let req = RenderRequest {
            allow_open: true,
            ..RenderRequest::default()
        };
        let sweep = render(&s, &req).unwrap_or_else(|e| panic!("{e}"));
        let reference = render_reference(&s, 0, 16, u64::MAX / 4, true, &[], None)
            .unwrap_or_else(|e| panic!("{e}"));
        let n = reference.image.data.len() as f64;
        let sum: f64 = (sweep.image.data.iter().zip(&reference.image.data))
            .map(|(a, b)| (f64::from(*a) - f64::from(*b)).powi(2))
            .sum();
        let rmse = (sum / n).sqrt();
        eprintln!("thin shell, {light:?}: RMSE {rmse:.4} against the reference");
        assert!(rmse <= bound, "{light:?}: RMSE {rmse:.4}");
    }
}

/// `sweep.light_resolution`: the light grid's cells per eye pixel at `look_at` (issue 41 item 3,
/// a speed-against-error axis). With the edge between the grid's pixel centres (0.3 and 0.7 of a
/// pixel of the default grid off a boundary, off the finer grids' boundaries too) the grid's LDI
/// quantises it (issue 46); a finer grid quantises it less. Measured 2026-12-06 (RMSE over the
/// receiver, fov 30° / 90°): s = 0.5: 1.1e-2–4.2e-2; 1: 9.0e-3–1.9e-2; 2: 6.2e-3–1.2e-2;
/// 4: 1.7e-3–3.2e-3, the half-shadow line within 0.06 px.
#[test]
fn a_finer_light_grid_sharpens_an_edge_off_its_pixel_boundaries() {
    use convshadow::reference::perspective_edge::{
        grid_pixel, measure_with_edge, scene_toml_with_edge,
    };
    for fov in [30.0, 90.0] {
        for off in [0.3, 0.7] {
            let edge = off / grid_pixel(fov);
            let rmse_at = |s: f64| {
                let text = scene_toml_with_edge(fov, &format!("light_resolution = {s:?}"), edge);
                let scene = Scene::parse(&text, "edge.toml", Path::new(".")).unwrap();
                let r = render(&scene, &RenderRequest::default()).unwrap();
                let (rmse, band, line) = measure_with_edge(fov, &r.image.data, edge).unwrap();
                eprintln!(
                    "fov {fov}, edge {off} px off, light_resolution {s}: RMSE {rmse:.2e} \
                     (band {band:.2e}), line within {line:.3} px"
                );
                (rmse, line)
            };
            let [half, one, two, four] = [0.5, 1.0, 2.0, 4.0].map(rmse_at);
            assert!(
                four.0 < two.0 && two.0 < one.0 && one.0 <= half.0,
                "fov {fov}, {off}: {half:?} {one:?} {two:?} {four:?}"
            );
            assert!(
                four.0 <= 5e-3 && four.1 <= 0.1,
                "fov {fov}, {off}: {four:?}"
            );
            assert!(
                one.1 <= 0.5 && two.1 <= 0.5,
                "fov {fov}, {off}: {one:?} {two:?}"
            );
        }
    }
}
