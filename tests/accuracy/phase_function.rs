//! The Henyey–Greenstein phase function of `[material.X] phase = { g }`: with distant lights and
//! an orthographic camera it is one constant per (material, light), so in a homogeneous fog the
//! image scales by exactly that constant — in the sweep (scalar and SIMD paths) and in the
//! shadow-ray reference. Expected factors are computed here from the formula and the light's
//! geometry, not taken from the code under test.

use crate::support;

use std::path::Path;

use convshadow::common::contract::ldi::Ldi;
use convshadow::common::model::scene::Scene;
use convshadow::cpu::ldi::BuildLdi;
use convshadow::pipeline::{CpuPath, RenderRequest, render};
use convshadow::reference::{Reference, ReferenceOptions};

/// A fog slab (a 4×4×1 box of constant, partly transparent medium filling the view) lit by one
/// hard light tilted by `tilt` degrees about the camera's y axis, medium asymmetry `g`.
fn fog(tilt: f64, g: f64) -> Scene {
    let text = format!(
        r#"
[image]
width = 24
height = 16
[camera]
view_width = 2.0
[sweep]
slabs = 16
optimal_distance = 0.5
[[light]]
color = [1.0, 0.7, 0.4]
tilt_deg = [{tilt}, 0.0]
[[mesh]]
shape = "box"
size = [4.0, 4.0, 1.0]
material = "fog"
[material.fog]
color = [0.9, 0.9, 1.0]
opacity = 0.2
reference_length = 0.25
phase = {{ g = {g} }}
"#
    );
    Scene::parse(&text, "fog.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// The normalised Henyey–Greenstein factor for a light tilted by `tilt` degrees about one axis.
/// The light propagates along (−tan ω, 0, 1)/|…| in camera space (its shadows move by −d·tan ω),
/// the camera is seen along (0, 0, −1): cos θ = −1/√(1 + tan²ω) = −cos ω.
fn expected_factor(g: f64, tilt: f64) -> f64 {
    let t = tilt.to_radians().tan();
    let n = (1.0 + t * t).sqrt();
    let propagation = [-t / n, 0.0, 1.0 / n];
    let to_camera = [0.0, 0.0, -1.0];
    let cos = propagation[0] * to_camera[0]
        + propagation[1] * to_camera[1]
        + propagation[2] * to_camera[2];
    (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos).powf(1.5)
}

fn sweep(scene: &Scene, path: CpuPath) -> (Vec<f32>, u64) {
    let req = RenderRequest {
        path,
        ..RenderRequest::default()
    };
    let r = render(scene, &req).unwrap_or_else(|e| panic!("{e}"));
    (r.image.data, r.image_hash)
}

/// Every lit value of `a / b` against `factor`, relative; returns the worst error and the count.
fn worst_ratio_error(a: &[f32], b: &[f32], factor: f64) -> (f64, usize) {
    let mut worst = 0.0f64;
    let mut n = 0;
    for (x, y) in a.iter().zip(b) {
        if *y > 1e-6 {
            n += 1;
            let r = f64::from(*x) / f64::from(*y);
            worst = worst.max((r / factor - 1.0).abs());
        }
    }
    (worst, n)
}

#[test]
fn fog_pixels_scale_by_the_phase_factor_at_0_30_and_60_degrees() {
    // Spot values of the formula: g = 0.6 seen against a light straight behind the viewer is
    // back-scattering, (1 − 0.36)/(1 + 0.36 + 1.2)^{3/2} = 0.64/4.096 = 0.15625.
    assert!((expected_factor(0.6, 0.0) - 0.15625).abs() < 1e-15);
    for tilt in [0.0, 30.0, 60.0] {
        let factor = expected_factor(0.6, tilt);
        let (iso, iso_hash) = sweep(&fog(tilt, 0.0), CpuPath::Simd);
        let (hg, hg_hash) = sweep(&fog(tilt, 0.6), CpuPath::Simd);
        let (worst, n) = worst_ratio_error(&hg, &iso, factor);
        eprintln!("tilt {tilt}°: factor {factor:.6}, {n} values, worst relative error {worst:.2e}");
        assert!(n >= 24 * 16 * 3, "the fog covers the view: {n} lit values");
        assert!(
            worst <= 1e-5,
            "tilt {tilt}: ratio off by {worst:e} (factor {factor})"
        );
        // The scalar path gives the same bits as the SIMD path.
        assert_eq!(sweep(&fog(tilt, 0.6), CpuPath::Scalar).1, hg_hash);
        assert_eq!(sweep(&fog(tilt, 0.0), CpuPath::Scalar).1, iso_hash);
        // The scattering angle is over 90° for every light behind the viewer, so backward
        // scattering (g < 0) is brighter than forward (g > 0).
        let back = sweep(&fog(tilt, -0.6), CpuPath::Simd).0;
        let (worst_back, _) = worst_ratio_error(&back, &iso, expected_factor(-0.6, tilt));
        assert!(worst_back <= 1e-5, "g = −0.6, tilt {tilt}: {worst_back:e}");
        assert!(expected_factor(-0.6, tilt) > factor);
    }
}

#[test]
fn the_reference_honours_the_same_phase_function() {
    for tilt in [0.0, 30.0, 60.0] {
        let render_ref = |g: f64| {
            let scene = fog(tilt, g);
            let geometry = convshadow_io::build_geometry(&scene).unwrap();
            let ldi = Ldi::build(&geometry.raster, 1 << 30).unwrap();
            let plan = convshadow_io::build_plan(&scene, &geometry).unwrap();
            Reference::new(&scene, &geometry, &plan, 0.0).render(
                &ldi,
                &ReferenceOptions {
                    samples: 4,
                    ..ReferenceOptions::default()
                },
            )
        };
        let factor = expected_factor(0.6, tilt);
        let (worst, n) = worst_ratio_error(&render_ref(0.6), &render_ref(0.0), factor);
        assert!(n >= 24 * 16 * 3, "{n}");
        assert!(worst <= 1e-5, "reference, tilt {tilt}: {worst:e}");
    }
}

#[test]
fn the_specular_highlight_is_a_surface_term_without_the_phase_factor() {
    // A black, opaque, glossy box: its image is the highlight alone, the same for any g.
    let glossy = |g: f64| {
        let text = format!(
            r#"
[image]
width = 16
height = 16
[camera]
direction = [0.3, 0.2, 1.0]
view_width = 3.0
[sweep]
slabs = 8
optimal_distance = 0.5
[[light]]
tilt_deg = [20.0, -10.0]
[[mesh]]
shape = "sphere"
size = [1.0, 3]
material = "m"
[material.m]
color = [0.0, 0.0, 0.0]
specular = {{ strength = 1.0, exponent = 8 }}
phase = {{ g = {g} }}
"#
        );
        support::scene(&text, Path::new("."))
    };
    let (a, ha) = sweep(&glossy(0.0), CpuPath::Simd);
    let (_, hb) = sweep(&glossy(0.8), CpuPath::Simd);
    assert!(a.iter().any(|&v| v > 0.01), "the highlight shows");
    assert_eq!(ha, hb);
}

#[test]
fn g_out_of_range_is_refused_naming_the_key() {
    for bad in ["1.0", "-1.0", "1.5", "nan", "0.9995"] {
        let toml = format!(
            "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
             optimal_distance = 0.5\n[[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\n\
             material = \"fog\"\n[material.fog]\nopacity = 0.2\nphase = {{ g = {bad} }}\n"
        );
        let e = Scene::parse(&toml, "bad.toml", Path::new(".")).unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains("bad.toml") && msg.contains("material.fog.phase.g"),
            "{bad}: {msg}"
        );
        if bad != "nan" {
            assert!(msg.contains("-1 < g < 1"), "{bad}: {msg}");
        }
    }
    let e = Scene::parse(
        "[image]\nwidth = 8\nheight = 8\n[camera]\nview_width = 2.0\n[sweep]\nslabs = 4\n\
         optimal_distance = 0.5\n[[mesh]]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\n\
         material = \"fog\"\n[material.fog]\nphase = { k = 0.5 }\n",
        "bad.toml",
        Path::new("."),
    )
    .unwrap_err();
    assert!(e.to_string().contains("unknown field `k`"), "{e}");
}
