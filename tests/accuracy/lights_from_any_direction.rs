//! World-space lights from any direction (issue 41): an opaque thin half-plane and a translucent
//! thin receiver sheet, both perpendicular to a directional light's mean direction, seen by a
//! camera at 0°, 45°, 80°, 100°, 135° and 180° from that direction, against the closed form
//! of the Gaussian light's visibility behind the half-plane, integrated along each pixel's view
//! ray through the sheet.
//!
//! The set-up and its closed form: `convshadow_reference::half_plane_sheet` (shared with the
//! report's `direction` family).

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{Aov, CpuPath, RenderRequest, render};
use convshadow::reference::half_plane_sheet::{
    POINT_SETUPS, SheetLight, expected_row, expected_row_point, point_light_at, point_profile_rmse,
    point_scene_toml, profile_rmse, scene_toml,
};

/// The bound on the normalised profile's RMSE.
const ASKED_RMSE: f64 = 5e-3;

/// The RMSE of the render's normalised middle rows over the sheet's penumbra, the number of
/// pixels measured, and the render.
fn measure(theta: f64, light: SheetLight, path: CpuPath) -> (f64, usize, Vec<f32>) {
    let text = scene_toml(theta, light, "");
    let s = Scene::parse(&text, "any_direction.toml", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}\n{text}"));
    let req = RenderRequest {
        path,
        ..RenderRequest::default()
    };
    let image = render(&s, &req).unwrap_or_else(|e| panic!("{e}"));
    let data = image.image.data;
    let (rmse, n) = profile_rmse(&data, &expected_row(theta, light))
        .unwrap_or_else(|e| panic!("θ = {theta}: {e}"));
    (rmse, n, data)
}

const ISOTROPIC: SheetLight = SheetLight::ISOTROPIC;
const ROTATED: SheetLight = SheetLight::ROTATED;

/// Per angle: the largest RMSE allowed for (isotropic, rotated anisotropic) light. 0° and 180°
/// are the bound; in between, today's numbers plus 25 % (a guard, not the target): there
/// the half-plane is oblique to the slabs and its surface hold lets light through it
/// (docs/accuracy.md §2e).
const BOUNDS: [(f64, [f64; 2]); 6] = [
    (0.0, [ASKED_RMSE, ASKED_RMSE]),
    (45.0, [0.45, 0.44]),
    (80.0, [0.68, 0.76]),
    (100.0, [0.81, 0.81]),
    (135.0, [0.40, 0.40]),
    (180.0, [ASKED_RMSE, ASKED_RMSE]),
];

#[test]
fn a_half_planes_shadow_on_a_sheet_from_every_camera_angle() {
    let mut failures = Vec::new();
    for (l, light) in [ISOTROPIC, ROTATED].into_iter().enumerate() {
        for (theta, bound) in BOUNDS {
            let (rmse, n, _) = measure(theta, light, CpuPath::Simd);
            eprintln!("θ = {theta:5.1}°, {light:?}: RMSE {rmse:.2e} over {n} penumbra pixels");
            if rmse > bound[l] {
                failures.push(format!(
                    "θ = {theta}°, {light:?}: {rmse:.2e} > {}",
                    bound[l]
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

#[test]
fn a_half_planes_shadow_is_whole_at_45_and_135_degrees_with_held_light_on_its_lit_side() {
    // At 45° and 135° the half-plane is oblique to the slabs and held; its held light stepped
    // sideways into columns behind it, and the umbra on the sheet came out half lit (0.32–0.34
    // above). With `sweep.held_lit_side` a gather reads no light from a held pixel behind
    // whose surface it lies: measured 0.0207 / 0.0196 (isotropic) and 0.0217 / 0.0227 (rotated
    // anisotropic), held here to those + 25 % (issue 41 asks 5e-3), scalar and SIMD bits equal.
    let bounds = [(45.0, [0.026, 0.028]), (135.0, [0.025, 0.029])];
    let mut failures = Vec::new();
    for (l, light) in [ISOTROPIC, ROTATED].into_iter().enumerate() {
        for (theta, bound) in bounds {
            let text = scene_toml(theta, light, "held_lit_side = true");
            let s = Scene::parse(&text, "any_direction.toml", Path::new("."))
                .unwrap_or_else(|e| panic!("{e}\n{text}"));
            let image = |path| {
                let req = RenderRequest {
                    path,
                    ..RenderRequest::default()
                };
                render(&s, &req)
                    .unwrap_or_else(|e| panic!("{e}"))
                    .image
                    .data
            };
            let data = image(CpuPath::Simd);
            let (rmse, n) = profile_rmse(&data, &expected_row(theta, light))
                .unwrap_or_else(|e| panic!("θ = {theta}: {e}"));
            eprintln!("θ = {theta:5.1}°, {light:?}, lit side: RMSE {rmse:.2e} over {n} pixels");
            if rmse > bound[l] {
                failures.push(format!(
                    "θ = {theta}°, {light:?}: {rmse:.2e} > {}",
                    bound[l]
                ));
            }
            if l == 0 && theta == 45.0 {
                assert!(
                    image(CpuPath::Scalar) == data,
                    "scalar and SIMD bits differ"
                );
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

#[test]
fn a_light_towards_the_camera_gives_the_same_bits_on_the_scalar_and_simd_paths() {
    let (_, _, simd) = measure(135.0, ROTATED, CpuPath::Simd);
    let (_, _, scalar) = measure(135.0, ROTATED, CpuPath::Scalar);
    let bits = |d: &[f32]| d.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert!(
        bits(&simd) == bits(&scalar),
        "the turned-round pass differs between paths"
    );
}

/// The set-up at 30° with a second light travelling towards the camera (a second pass) and both
/// lights' layers asked for, last light first: each layer is that light's own render (the
/// scene with the other light left out; the background is black) and the two add up to the
/// image.
#[test]
fn each_lights_layer_is_its_own_render_when_the_lights_need_two_passes() {
    let one = scene_toml(30.0, ISOTROPIC, "");
    let back_light = "[[light]]\ndirection = [0.2, 0.0, -1.0]\ncolor = [0.3, 0.5, 1.0]\n\
                      variance = [0.02, 0.02]\n";
    let parse = |text: &str| {
        Scene::parse(text, "two_lights.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
    };
    let both = parse(&format!("{one}{back_light}"));
    let only_front = parse(&one);
    // The back light alone: the same scene text with its [[light]] block replaced.
    let start = one.find("[[light]]").unwrap();
    let end = one.find("[[mesh]]").unwrap();
    let only_back = parse(&format!("{}{back_light}{}", &one[..start], &one[end..]));
    assert_eq!(both.passes().back.map(|s| s.lights.len()), Some(1));

    let req = RenderRequest {
        aovs: vec![Aov::Light(1), Aov::Light(0)],
        ..RenderRequest::default()
    };
    let r = render(&both, &req).unwrap_or_else(|e| panic!("{e}"));
    let alone = |s: &Scene| {
        render(s, &RenderRequest::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .image
            .data
    };
    let own = [alone(&only_front), alone(&only_back)];
    assert_eq!(
        r.light_layers.iter().map(|(l, _)| *l).collect::<Vec<_>>(),
        [1, 0],
        "layers in request order"
    );
    let layer = |l: usize| &r.light_layers.iter().find(|(i, _)| *i == l).unwrap().1;
    let image = &r.image.data;
    let mut lit = [0.0f64; 2];
    for p in 0..image.len() {
        for (l, lit) in lit.iter_mut().enumerate() {
            let (got, want) = (layer(l)[p], own[l][p]);
            assert!(
                (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                "light {l}, value {p}: layer {got}, alone {want}"
            );
            *lit += f64::from(got);
        }
        let sum = layer(0)[p] + layer(1)[p];
        assert!(
            (sum - image[p]).abs() <= 1e-5 * image[p].abs().max(1.0),
            "value {p}: layers {sum}, image {}",
            image[p]
        );
    }
    assert!(
        lit[0] > 10.0 && lit[1] > 10.0,
        "both lights light the sheet: {lit:?}"
    );
}

/// Per angle of `POINT_SETUPS`: the largest RMSE allowed for the soft point light, today's
/// numbers plus 25 % (a guard, far from the 5e-3; docs/accuracy.md §2e): at 0° and 180°
/// the plate's edge on the light's grid, half a cell at light resolution 1 (0.024 and 0.022;
/// 0.034 and 0.033 while the grid ended at the eye's 8 rows, its penumbra reading unoccluded
/// light beyond them); at 45° and 135° the plate's shadow, which its surface hold let through
/// until a hold ended at a crossing with something behind it (0.64 then, 0.039 and 0.080 now).
/// `None`: not rendered here (80° and 100°, 12–30 s each on the light's grid of about
/// 13596 × 100 cells, still at 0.39 and 0.32; the report's `direction` family has them).
const POINT_BOUNDS: [Option<f64>; 6] = [
    Some(0.030),
    Some(0.048),
    None,
    None,
    Some(0.10),
    Some(0.027),
];

#[test]
fn a_soft_point_lights_shadow_on_a_sheet_from_every_camera_angle() {
    let mut report = Vec::new();
    let mut failed = false;
    for ((theta, distance, resolution), bound) in POINT_SETUPS.into_iter().zip(POINT_BOUNDS) {
        let Some(bound) = bound else { continue };
        let (position, radius) = point_light_at(distance);
        let text = point_scene_toml(theta, position, radius, "");
        let mut s = Scene::parse(&text, "any_direction_point.toml", Path::new("."))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        s.sweep.light_resolution = resolution;
        let r = render(&s, &RenderRequest::default()).unwrap_or_else(|e| panic!("{theta}: {e}"));
        let (rmse, n) =
            point_profile_rmse(&r.image.data, &expected_row_point(theta, position, radius))
                .unwrap_or_else(|e| panic!("θ = {theta}: {e}"));
        failed |= rmse > bound;
        report.push(format!(
            "θ = {theta:5.1}°, light {distance} before the plate, grid {resolution}: RMSE \
             {rmse:.2e} over {n} penumbra pixels (guard {bound})"
        ));
    }
    let report = report.join("\n");
    println!("{report}");
    assert!(!failed, "{report}");
}

/// A level floor lit by a light towards the viewer (the turned-round pass), as `rimlit`'s rim
/// light at a small image size: the face the viewer sees is the sweep's exit from the floor box,
/// and without the exit hold every row whose exit fell on a slab where the narrow light's drift
/// was carried 0 pixels read the box's own inside — half the rows near black at 384 slabs, most
/// at 1536 (docs/accuracy.md §2e). Closed form: Lambert, albedo × light × n·l, over the pixels
/// whose view ray meets the floor's top 0.3 inside its edges (computed from the camera here).
#[test]
fn a_floor_lit_towards_the_viewer_is_even_at_any_slab_count() {
    let (w, h, view_width) = (128usize, 96usize, 4.0f64);
    let light = [0.25f64, -0.55, -1.0];
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / l, v[1] / l, v[2] / l]
    };
    let n_dot_l = -norm(light)[1];
    let expected = 0.68 * n_dot_l; // green: albedo 0.68, light 1.0
    // The orthographic camera's frame: `up` made orthogonal to the view, `right = up × d`.
    let d = norm([0.0, -0.36, 1.0]);
    let up = norm([-d[1] * d[0], 1.0 - d[1] * d[1], -d[1] * d[2]]);
    let right = [
        up[1] * d[2] - up[2] * d[1],
        up[2] * d[0] - up[0] * d[2],
        up[0] * d[1] - up[1] * d[0],
    ];
    let (centre, pixel) = ([0.0, -0.5, 0.5], view_width / w as f64);
    for slabs in [384, 1536] {
        let text = format!(
            "[image]\nwidth = {w}\nheight = {h}\n[camera]\ndirection = [0.0, -0.36, 1.0]\n\
             up = [0.0, 1.0, 0.0]\ncenter = [0.0, -0.5, 0.5]\nview_width = {view_width}\n\
             [sweep]\nslabs = {slabs}\n[[light]]\ncolor = [1.0, 1.0, 1.0]\n\
             direction = [{}, {}, {}]\nvariance = [0.003, 0.003]\n[[mesh]]\nshape = \"box\"\n\
             size = [7.0, 0.3, 8.0]\ntranslate = [0.0, -1.15, 1.5]\nmaterial = \"floor\"\n\
             [material.floor]\ncolor = [0.7, 0.68, 0.62]\n",
            light[0], light[1], light[2]
        );
        let s = Scene::parse(&text, "turned_floor.toml", Path::new("."))
            .unwrap_or_else(|e| panic!("{e}\n{text}"));
        let r = render(&s, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
        let (mut sum2, mut n, mut darkest) = (0.0f64, 0usize, f64::INFINITY);
        for row in 0..h {
            for col in 0..w {
                let (u, v) = (
                    (col as f64 + 0.5 - w as f64 / 2.0) * pixel,
                    (h as f64 / 2.0 - row as f64 - 0.5) * pixel,
                );
                let o: Vec<f64> = (0..3)
                    .map(|a| centre[a] + u * right[a] + v * up[a])
                    .collect();
                // Where the view ray meets the floor's top, y = −1.
                let t = (-1.0 - o[1]) / d[1];
                let (x, z) = (o[0] + t * d[0], o[2] + t * d[2]);
                if x.abs() > 3.2 || !(-2.2..=5.2).contains(&z) {
                    continue;
                }
                let got = f64::from(r.image.data[3 * (row * w + col) + 1]);
                sum2 += (got - expected) * (got - expected);
                darkest = darkest.min(got);
                n += 1;
            }
        }
        let rmse = (sum2 / n as f64).sqrt() / expected;
        println!(
            "{slabs} slabs: relative RMSE {rmse:.2e} over {n} floor pixels, darkest {darkest:.4} \
             (closed form {expected:.4})"
        );
        assert!(n > 2000, "{slabs} slabs: only {n} floor pixels");
        assert!(
            rmse <= 2e-2 && darkest >= 0.9 * expected,
            "{slabs} slabs: relative RMSE {rmse:.2e}, darkest {darkest} (closed form {expected})"
        );
    }
}

/// The soft point light's shadow through the translucent sheet at 0°, light resolution 2: the
/// grid column through the plate's edge enters the plate's front face and leaves through its
/// side face. A crossing that left a closed mesh used to start a surface hold there (the side
/// face is steep on the light's grid: 1023 slabs), which the sheet's crossing ended 500 slabs
/// on, taking out that column's light at the sheet: a dark line along the shadow's middle, the
/// pixel on it at 0.25 of the lit level where 0.50 is right (RMSE 0.059). Leaving a mesh now
/// starts no hold. Reference: the visibility integrated over the light (`expected_row_point`).
#[test]
fn a_soft_point_lights_shadow_through_a_translucent_sheet_has_no_dark_line_at_its_middle() {
    let (theta, distance) = (0.0, 2.0);
    let (position, radius) = point_light_at(distance);
    let text = point_scene_toml(theta, position, radius, "");
    let mut s = Scene::parse(&text, "any_direction_point.toml", Path::new("."))
        .unwrap_or_else(|e| panic!("{e}\n{text}"));
    s.sweep.light_resolution = 2.0;
    let r = render(&s, &RenderRequest::default()).unwrap_or_else(|e| panic!("{e}"));
    let expected = expected_row_point(theta, position, radius);
    let (rmse, n) = point_profile_rmse(&r.image.data, &expected).unwrap_or_else(|e| panic!("{e}"));
    // The largest difference over the penumbra, each pixel over its own unshadowed light and the
    // render over its lit level (as `point_profile_rmse` does).
    let w = convshadow::reference::half_plane_sheet::WIDTH as usize;
    let row = convshadow::reference::half_plane_sheet::HEIGHT as usize / 2;
    let levelled = |i: usize, e: f64| f64::from(r.image.data[3 * (row * w + i)]) / e;
    let lit: Vec<f64> = (0..w)
        .filter_map(|i| {
            expected[i]
                .filter(|&(v, _)| v > 1.0 - 1e-12)
                .map(|(_, e)| levelled(i, e))
        })
        .collect();
    let level = lit.iter().sum::<f64>() / lit.len() as f64;
    let worst = (0..w)
        .filter_map(|i| {
            let (v, e) = expected[i]?;
            (1e-4..1.0 - 1e-4)
                .contains(&v)
                .then(|| (levelled(i, e) / level - v).abs())
        })
        .fold(0.0f64, f64::max);
    println!("light resolution 2: RMSE {rmse:.2e} over {n} pixels, largest difference {worst:.3}");
    assert!(
        worst <= 0.05,
        "largest difference {worst:.3} (RMSE {rmse:.2e})"
    );
    assert!(rmse <= 0.012, "RMSE {rmse:.2e}");
}
