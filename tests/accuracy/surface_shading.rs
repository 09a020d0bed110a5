//! Surface shading at crossed opaque surfaces (`[material.X] surface`, `specular.model`): a
//! Lambert-shaded icosphere against max(0, n·l) of the true sphere, and the shading stage's
//! Lambert and Ashikmin–Shirley values at chosen normals against an independent f64 evaluation
//! of the published formulas written here (never values taken from the code under test).

use crate::support;

use std::f64::consts::PI;
use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::cpu::shading::{Surface, shade};
use convshadow::pipeline::{CpuPath, RenderRequest, render};

/// Image size of the icosphere renders (pixels a side) and the view width (world units).
const SIZE: u32 = 160;
const VIEW: f64 = 2.4;
/// The icosphere's radius.
const RADIUS: f64 = 1.0;

/// An opaque white icosphere (7 subdivisions: 327 680 triangles) of radius [`RADIUS`] at the
/// origin, seen along +z, under one hard white light of tilt (`tilt`, 0) degrees.
fn icosphere(tilt: f64, surface: &str) -> Scene {
    let text = format!(
        r#"
[image]
width = {SIZE}
height = {SIZE}
[camera]
view_width = {VIEW}
[sweep]
slabs = 96
optimal_distance = 0.5
[[light]]
color = [1.0, 1.0, 1.0]
tilt_deg = [{tilt}, 0.0]
variance = [0.0, 0.0]
[[mesh]]
shape = "sphere"
size = [{RADIUS}, 7]
material = "white"
[material.white]
color = [1.0, 1.0, 1.0]
opacity = 1.0
surface = "{surface}"
"#
    );
    support::scene(&text, Path::new("."))
}

/// Direction towards a light of tilt (ωx, ωy) degrees in camera space: the light propagates along
/// (−tan ωx, −tan ωy, 1)/‖·‖ (its shadows move by −d·tan ω), so towards it is the opposite.
fn to_light(tilt: [f64; 2]) -> [f64; 3] {
    let (tx, ty) = (tilt[0].to_radians().tan(), tilt[1].to_radians().tan());
    let n = (tx * tx + ty * ty + 1.0).sqrt();
    [tx / n, ty / n, -1.0 / n]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = dot(v, v).sqrt();
    [v[0] / n, v[1] / n, v[2] / n]
}

/// RMSE of the red channel against max(0, n·l) of the true sphere (n at each pixel centre, on
/// the visible hemisphere), over the pixels whose centre lies at most `RADIUS − margin_px·px`
/// from the sphere's centre in the image; returns (RMSE, max abs error, pixels).
fn lambert_error(image: &[f32], tilt: f64, margin_px: f64) -> (f64, f64, usize) {
    let px = VIEW / f64::from(SIZE);
    let l = to_light([tilt, 0.0]);
    let (mut sum, mut worst, mut n) = (0.0f64, 0.0f64, 0usize);
    for j in 0..SIZE as usize {
        for i in 0..SIZE as usize {
            // Camera space: x right, y down; the image centre is the camera centre.
            let x = (i as f64 + 0.5 - f64::from(SIZE) / 2.0) * px;
            let y = (j as f64 + 0.5 - f64::from(SIZE) / 2.0) * px;
            let rho = (x * x + y * y).sqrt();
            if rho > RADIUS - margin_px * px {
                continue;
            }
            let normal = [
                x / RADIUS,
                y / RADIUS,
                -(RADIUS * RADIUS - rho * rho).sqrt() / RADIUS,
            ];
            let expected = dot(normal, l).max(0.0);
            let got = f64::from(image[3 * (j * SIZE as usize + i)]);
            let e = got - expected;
            sum += e * e;
            worst = worst.max(e.abs());
            n += 1;
        }
    }
    ((sum / n as f64).sqrt(), worst, n)
}

fn render_image(scene: &Scene, path: CpuPath) -> (Vec<f32>, u64) {
    let req = RenderRequest {
        path,
        ..RenderRequest::default()
    };
    let r = render(scene, &req).unwrap_or_else(|e| panic!("{e}"));
    (r.image.data, r.image_hash)
}

#[test]
fn a_lambert_icosphere_under_a_light_along_the_view_matches_the_true_sphere() {
    let (image, hash) = render_image(&icosphere(0.0, "lambert"), CpuPath::Simd);
    for margin in [0.0, 2.0, 8.0] {
        let (rmse, worst, n) = lambert_error(&image, 0.0, margin);
        eprintln!(
            "tilt 0°, {margin} px from the silhouette: RMSE {rmse:.2e}, max {worst:.2e}, {n} px"
        );
    }
    // Asked: RMSE ≤ 5e-3 away from the silhouette: every pixel whose centre is 2 px or more
    // inside the sphere's outline.
    let (rmse, worst, n) = lambert_error(&image, 0.0, 2.0);
    assert!(n > 12_000, "{n} pixels compared");
    assert!(rmse <= 5e-3, "RMSE {rmse:e} (max {worst:e})");
    assert_eq!(
        render_image(&icosphere(0.0, "lambert"), CpuPath::Scalar).1,
        hash
    );
    // The flat surface is the silhouette of before: 1 everywhere on the sphere.
    let (flat, _) = render_image(&icosphere(0.0, "flat"), CpuPath::Simd);
    let (rmse_flat, _, _) = lambert_error(&flat, 0.0, 2.0);
    assert!(rmse_flat > 0.1, "flat shading is not shaded: {rmse_flat}");
}

#[test]
fn a_lambert_icosphere_under_a_tilted_hard_light() {
    // Tilted 30° about the camera's y axis: the terminator crosses the visible hemisphere. The
    // shadow-ray reference shades through the same `shade` with straight shadow rays, so it
    // evaluates the same Lambert term. Both images are measured against max(0, n·l), both asked
    // RMSE ≤ 5e-3: the sweep's is 1.38e-3 (0.134 before the surface hold, when the sphere's
    // oblique parts shadowed themselves in bands, docs/how-it-works.md "Surfaces oblique to the
    // slabs"), the reference's 1.38e-3 (9.7e-2 before its shadow rays started on the exact
    // surface and skipped the crossed triangle: they met the sphere's own facets, issue 46).
    use convshadow::common::contract::ldi::Ldi;
    use convshadow::cpu::ldi::BuildLdi;
    use convshadow::reference::{Reference, ReferenceOptions};
    let tilt = 30.0;
    let scene = icosphere(tilt, "lambert");
    let geometry = convshadow_io::build_geometry(&scene).unwrap();
    let ldi = Ldi::build(&geometry.raster, 1 << 30).unwrap();
    let plan = convshadow_io::build_plan(&scene, &geometry).unwrap();
    let options = ReferenceOptions {
        samples: 1,
        ..ReferenceOptions::default()
    };
    let reference = Reference::new(&scene, &geometry, &plan, 0.0).render(&ldi, &options);
    let (rmse, worst, n) = lambert_error(&reference, tilt, 2.0);
    eprintln!("reference, tilt {tilt}°, 2 px in: RMSE {rmse:.2e}, max {worst:.2e}, {n} px");
    let (image, _) = render_image(&scene, CpuPath::Simd);
    let (sweep_rmse, sweep_worst, _) = lambert_error(&image, tilt, 2.0);
    eprintln!("sweep, tilt {tilt}°, 2 px in: RMSE {sweep_rmse:.2e}, max {sweep_worst:.2e}");
    assert!(n > 12_000, "{n} pixels compared");
    assert!(
        sweep_rmse <= 5e-3,
        "sweep, tilt {tilt}°: RMSE {sweep_rmse:.2e}"
    );
    assert!(rmse <= 5e-3, "reference, tilt {tilt}°: RMSE {rmse:.2e}");
    // What holds for both: shadowing only darkens, so no pixel is brighter than
    // max(0, n·l) (beyond the facets' error), and the side facing away is exactly black.
    for (what, img) in [("sweep", &image), ("reference", &reference)] {
        let (brighter, dark_lit) = bounds_violations(img, tilt, 2.0);
        assert_eq!(
            (brighter, dark_lit),
            (0, 0),
            "{what}: brighter, lit on the dark side"
        );
    }
}

/// Pixels (2 px or more inside the outline) brighter than max(0, n·l) + 1e-2 (twice the largest
/// facet error seen with the light along the view, 4.7e-3), and pixels not
/// exactly 0 where n·l < −1e-2.
fn bounds_violations(image: &[f32], tilt: f64, margin_px: f64) -> (usize, usize) {
    let px = VIEW / f64::from(SIZE);
    let l = to_light([tilt, 0.0]);
    let (mut brighter, mut dark_lit) = (0, 0);
    for j in 0..SIZE as usize {
        for i in 0..SIZE as usize {
            let x = (i as f64 + 0.5 - f64::from(SIZE) / 2.0) * px;
            let y = (j as f64 + 0.5 - f64::from(SIZE) / 2.0) * px;
            let rho = (x * x + y * y).sqrt();
            if rho > RADIUS - margin_px * px {
                continue;
            }
            let normal = [
                x / RADIUS,
                y / RADIUS,
                -(RADIUS * RADIUS - rho * rho).sqrt() / RADIUS,
            ];
            let nl = dot(normal, l);
            let got = f64::from(image[3 * (j * SIZE as usize + i)]);
            brighter += usize::from(got > nl.max(0.0) + 1e-2);
            dark_lit += usize::from(nl < -1e-2 && got != 0.0);
        }
    }
    (brighter, dark_lit)
}

/// A scene with two lights and one material `m` of colour `color`, `surface` and `specular`
/// (TOML), for calling the shading stage directly.
fn shading_scene(color: f64, surface: &str, specular: &str) -> Scene {
    let text = format!(
        r#"
[image]
width = 8
height = 8
[camera]
view_width = 2.0
[sweep]
slabs = 4
optimal_distance = 0.5
[[light]]
color = [1.0, 1.0, 1.0]
tilt_deg = [25.0, -10.0]
[[light]]
color = [0.5, 0.5, 0.5]
tilt_deg = [-40.0, 30.0]
[[mesh]]
shape = "box"
size = [1.0, 1.0, 1.0]
material = "m"
[material.m]
color = [{color}, {color}, {color}]
surface = "{surface}"
{specular}
"#
    );
    support::scene(&text, Path::new("."))
}

/// The lights of [`shading_scene`]: (tilt, grey level).
const LIGHTS: [([f64; 2], f64); 2] = [([25.0, -10.0], 1.0), ([-40.0, 30.0], 0.5)];

/// Normals to test, facing the viewer (z < 0) or not (flipped by the shading stage), chosen so
/// that n·l > n·v for some light and < for another, one grazing and one facing away from the
/// first light.
fn normals() -> Vec<[f64; 3]> {
    vec![
        [0.0, 0.0, -1.0],
        unit([0.3, -0.1, -1.0]),
        unit([-0.5, 0.4, -1.0]),
        unit([0.8, 0.1, -0.3]),
        unit([-0.9, 0.0, -0.2]),
        unit([0.2, 0.3, 1.0]), // back-facing: shaded as (−0.2, −0.3, −1)
    ]
}

/// The shading stage's value (red channel) at normal `n` with the slab opacity `alpha`, every
/// light buffer 1, the surface crossed.
fn shade_at(scene: &Scene, n: [f64; 3], alpha: f32) -> f64 {
    let geometry = convshadow_io::build_geometry(scene).unwrap();
    let plan = convshadow_io::build_plan(scene, &geometry).unwrap();
    let material = &plan.materials[0];
    let iin = vec![1.0f32; plan.lights.len() * plan.channels as usize];
    let color = material.tf[0].color;
    let surface = Surface {
        normal: n.map(|v| v as f32),
        lanes: true,
        alpha,
    };
    f64::from(shade::<f32>(&plan, material, color, &iin, Some(&surface))[0])
}

/// The facing normal (z ≤ 0).
fn facing(n: [f64; 3]) -> [f64; 3] {
    if n[2] > 0.0 { n.map(|v| -v) } else { n }
}

/// Ashikmin & Shirley 2000, "An anisotropic Phong BRDF model", eq. 4 with n_u = n_v = e and
/// Schlick's Fresnel approximation, times the cosine n·l of the incident light:
/// ρ_s·(n·l) = (e + 1)/(8π) · (n·h)^e / ((h·k)·max(n·l, n·v)) · F(h·k) · (n·l).
fn ashikmin_shirley(n: [f64; 3], l: [f64; 3], e: f64, f0: f64) -> f64 {
    let v = [0.0, 0.0, -1.0];
    let h = unit([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    let (nh, nl, nv, hk) = (dot(n, h).max(0.0), dot(n, l), dot(n, v), dot(h, l));
    if nl <= 0.0 {
        return 0.0;
    }
    let fresnel = f0 + (1.0 - f0) * (1.0 - hk).powi(5);
    (e + 1.0) / (8.0 * PI) * nh.powf(e) / (hk * nl.max(nv)) * fresnel * nl
}

#[test]
fn ashikmin_shirley_matches_the_published_formula_at_several_normals() {
    for (e, f0, strength) in [(8u32, 0.04, 1.0), (33, 0.5, 0.7), (1, 1.0, 2.0)] {
        // A black material: the value is the highlight alone.
        let scene = shading_scene(
            0.0,
            "lambert",
            &format!(
                "specular = {{ model = \"ashikmin-shirley\", exponent = {e}, f0 = {f0}, \
                 strength = {strength} }}"
            ),
        );
        let mut largest = 0.0f64;
        for n in normals() {
            let f = facing(n);
            let expected: f64 = LIGHTS
                .iter()
                .map(|&(tilt, grey)| {
                    strength * grey * ashikmin_shirley(f, to_light(tilt), f64::from(e), f0)
                })
                .sum();
            let got = shade_at(&scene, n, 1.0);
            largest = largest.max(expected);
            let err = (got - expected).abs();
            eprintln!("e {e}, f0 {f0}, n {n:.3?}: {got:.6e} against {expected:.6e}");
            // The normal and n·h are rounded to f32 (relative 6e-8 each); (n·h)^e multiplies
            // that relative error by e.
            let tolerance = (f64::from(e) + 10.0) * 1.2e-7 * expected + 1e-9;
            assert!(
                err <= tolerance,
                "e {e}, f0 {f0}, n {n:?}: got {got:e}, expected {expected:e}"
            );
        }
        assert!(largest > 0.01, "some normal shows the highlight");
    }
}

#[test]
fn lambert_is_the_cosine_at_opaque_crossings_only() {
    let lambert = shading_scene(0.8, "lambert", "");
    let mut flat = shading_scene(0.8, "flat", "");
    // Without the horizon (its own test below) a flat crossing is colour × light.
    flat.sweep.horizon = false;
    let light_sum: f64 = LIGHTS.iter().map(|l| l.1).sum();
    for n in normals() {
        let f = facing(n);
        let expected: f64 = LIGHTS
            .iter()
            .map(|&(tilt, grey)| 0.8 * grey * dot(f, to_light(tilt)).max(0.0))
            .sum();
        // A translucent crossing, and any flat crossing, keep colour × light.
        let translucent = assert_opaque_and_translucent(&lambert, n, expected, 0.8 * light_sum);
        assert_eq!(shade_at(&flat, n, 1.0), translucent);
    }
}

/// Asserts `scene`'s shading at normal `n` within 1e-6 of `opaque` at an opaque crossing and of
/// `translucent` at a translucent one (slab opacity 0.999); returns the translucent value.
fn assert_opaque_and_translucent(scene: &Scene, n: [f64; 3], opaque: f64, translucent: f64) -> f64 {
    let got = shade_at(scene, n, 1.0);
    assert!(
        (got - opaque).abs() <= 1e-6,
        "n {n:?}: {got} against {opaque}"
    );
    let got = shade_at(scene, n, 0.999);
    assert!((got - translucent).abs() <= 1e-6, "{got}");
    got
}

#[test]
fn the_horizon_blocks_the_lights_below_an_opaque_surfaces_tangent_plane() {
    // The scene's lights are hard (no variance): each reaches an opaque crossing only from
    // above its tangent plane, f·l > 0, whatever the surface model; a translucent crossing keeps
    // colour × light.
    let flat = shading_scene(0.8, "flat", "");
    assert!(flat.sweep.horizon, "on by default");
    let light_sum: f64 = LIGHTS.iter().map(|l| l.1).sum();
    let mut blocked = 0;
    for n in normals() {
        let f = facing(n);
        let above = |tilt: [f64; 2]| dot(f, to_light(tilt)) > 0.0;
        let expected: f64 = LIGHTS
            .iter()
            .map(|&(tilt, grey)| if above(tilt) { 0.8 * grey } else { 0.0 })
            .sum();
        blocked += LIGHTS.iter().filter(|l| !above(l.0)).count();
        assert_opaque_and_translucent(&flat, n, expected, 0.8 * light_sum);
    }
    assert!(blocked > 0, "some normal faces away from a light");
}

#[test]
fn the_default_surface_is_lambert_and_a_specular_table_without_model_is_blinn_phong() {
    use convshadow::common::model::scene::{SpecularModel, SurfaceModel};
    let text = "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
                [[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n\
                [material.m]\nspecular = { strength = 0.5, exponent = 8 }\n";
    let scene = Scene::parse(text, "s.toml", Path::new(".")).unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.surface, SurfaceModel::Lambert);
    let s = m.specular.as_ref().unwrap();
    assert_eq!(s.model, SpecularModel::BlinnPhong);
    assert_eq!((s.strength, s.exponent), (0.5, 8));
    let as_text = text.replace(
        "{ strength = 0.5, exponent = 8 }",
        "{ model = \"ashikmin-shirley\", exponent = 8 }",
    );
    let scene = Scene::parse(&as_text, "s.toml", Path::new(".")).unwrap();
    let s = scene.materials[0].specular.as_ref().unwrap();
    assert_eq!(s.model, SpecularModel::AshikminShirley { f0: 0.04 });
    assert_eq!(s.strength, 1.0);
}

#[test]
fn bad_surface_and_specular_keys_are_refused_naming_the_key() {
    let base = "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
                [[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\nmaterial = \"m\"\n\
                [material.m]\n";
    for (line, key, says) in [
        ("surface = \"phong\"", "material.m.surface", "\"lambert\""),
        (
            "specular = { model = \"ward\", exponent = 8 }",
            "material.m.specular.model",
            "\"ashikmin-shirley\"",
        ),
        (
            "specular = { model = \"ashikmin-shirley\", exponent = 8, f0 = -0.1 }",
            "material.m.specular.f0",
            "[0, 1]",
        ),
        (
            "specular = { model = \"ashikmin-shirley\", exponent = 8, f0 = 1.01 }",
            "material.m.specular.f0",
            "[0, 1]",
        ),
        (
            "specular = { strength = 1.0, exponent = 8, f0 = 0.5 }",
            "material.m.specular.f0",
            "ashikmin-shirley",
        ),
        (
            "specular = { model = \"ashikmin-shirley\", exponent = 5000 }",
            "material.m.specular.exponent",
            "1 to 4096",
        ),
        (
            "specular = { model = \"ashikmin-shirley\", exponent = 8, strength = 2e4 }",
            "material.m.specular.strength",
            "1e4",
        ),
        (
            "specular = { model = \"ashikmin-shirley\", exponent = 8, nu = 4 }",
            "nu",
            "unknown field",
        ),
    ] {
        let e = Scene::parse(&format!("{base}{line}\n"), "bad.toml", Path::new("."))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bad.toml") && e.contains(key) && e.contains(says),
            "{line}: {e}"
        );
    }
}
