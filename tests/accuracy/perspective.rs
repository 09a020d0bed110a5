//! The sweep and the shadow-ray reference seen through a perspective camera (issue 42) against
//! the closed form: an opaque half-plane 0.5 in front of a receiver plane, a Gaussian directional light
//! along the view (so the light's slopes per unit depth are its own: no linearisation of a
//! turned Gaussian enters), the eye off to the side at fields of view of 30° and 90°. The test
//! traces every pixel's ray itself (its own camera basis from `eye`, `look_at`, `up` and
//! `fov_deg`), meets the receiver and evaluates the visibility there in closed form; the
//! renderers must match it, and their shadow lines must sit where the geometric one projects.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{CpuPath, RenderRequest, render, render_reference};
use convshadow::reference::normal_cdf;
use glam::DVec3;

const EYE: DVec3 = DVec3::new(-1.0, 0.3, -4.0);
/// The receiver's front face (depth z).
const RECEIVER: f64 = 0.5;
/// The occluder plate: x ≥ 0, between these depths (thin, so both faces count).
const PLATE: (f64, f64) = (-0.001, 0.001);
const WIDTH: u32 = 192;
const HEIGHT: u32 = 144;

/// The point looked at: on the view axis (+z from the eye), at about 4, at the distance that
/// makes the slab grid's pixel (the pixel's footprint there) divide the edge's distance from
/// the axis, 1, a whole number of times — the edge on a pixel boundary of the grid the light is
/// swept on, as in the orthographic edge tests (an edge between pixel centres is quantised by
/// the LDI, issue 46: measured in how-it-works.md).
fn look_at(fov_deg: f64) -> DVec3 {
    EYE + DVec3::Z * (focal(fov_deg) / grid_pixel(fov_deg))
}

/// The focal length in pixels.
fn focal(fov_deg: f64) -> f64 {
    0.5 * f64::from(HEIGHT) / (0.5 * fov_deg).to_radians().tan()
}

/// The grid pixels per world unit at the `look_at` distance (a whole number, see [`look_at`]).
fn grid_pixel(fov_deg: f64) -> f64 {
    (focal(fov_deg) / 4.0).round()
}

/// The light's angular standard deviation (isotropic; its slopes' σ per unit distance): a
/// penumbra of 1.5 grid pixels (σ·w, w = 0.5) — a light buffer of pixels resolves no narrower
/// one, in perspective as in orthographic views.
fn sigma(fov_deg: f64) -> f64 {
    1.5 / (grid_pixel(fov_deg) * RECEIVER)
}

fn scene(fov_deg: f64, sweep: &str) -> Scene {
    let look = look_at(fov_deg);
    let text = format!(
        r#"
[image]
width = {WIDTH}
height = {HEIGHT}
[camera]
projection = "perspective"
eye = [{}, {}, {}]
look_at = [{}, {}, {}]
fov_deg = {fov_deg}
[sweep]
slabs = 128
optimal_distance = 0.5
{sweep}
[[light]]
variance = [{v:e}, {v:e}]
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.2]
translate = [0.0, 0.0, {r:e}]
material = "receiver"
[[mesh]]
shape = "box"
size = [3.0, 6.0, {t:e}]
translate = [1.5, 0.0, {c:e}]
material = "plate"
[material.receiver]
surface = "flat"
[material.plate]
color = [0.0, 0.0, 0.0]
"#,
        EYE.x,
        EYE.y,
        EYE.z,
        look.x,
        look.y,
        look.z,
        v = sigma(fov_deg) * sigma(fov_deg),
        r = RECEIVER + 0.1,
        t = PLATE.1 - PLATE.0,
        c = 0.5 * (PLATE.0 + PLATE.1),
    );
    Scene::parse(&text, "perspective-edge.toml", Path::new(".")).expect("scene")
}

/// Where pixel centre (i + ½, j + ½)'s ray from the eye meets the receiver's front face
/// (z = RECEIVER), if it does within the face and not through the plate; the test's own camera
/// (right-handed, y down).
fn receiver_point(fov_deg: f64, i: u32, j: u32) -> Option<DVec3> {
    let forward = (look_at(fov_deg) - EYE).normalize();
    let up = DVec3::Y;
    let down = -(up - forward * up.dot(forward)).normalize();
    let right = down.cross(forward);
    let f = focal(fov_deg);
    let dx = (f64::from(i) + 0.5 - 0.5 * f64::from(WIDTH)) / f;
    let dy = (f64::from(j) + 0.5 - 0.5 * f64::from(HEIGHT)) / f;
    let d = forward + right * dx + down * dy;
    let at = |z: f64| EYE + d * ((z - EYE.z) / d.z);
    let hit = at(RECEIVER);
    // Away from the plate's ends (|y| = 3), where light passes round them: the closed form is
    // a half-plane's.
    let on_receiver = hit.x.abs() < 2.9 && hit.y.abs() < 2.0;
    // The plate (x in [0, 3], |y| ≤ 3) seen before the receiver: the ray is inside it at one of
    // its faces (the ray is a straight line, the plate convex and thin).
    let through_plate = [PLATE.0, PLATE.1].iter().any(|&z| {
        let p = at(z);
        p.x >= -1e-9 && p.x <= 3.0 && p.y.abs() <= 3.0
    });
    (on_receiver && !through_plate).then_some(hit)
}

/// The closed form: a shadow ray from receiver point x heading back towards the light with
/// slope s ~ N(0, σ²) along x per unit depth is blocked where it reaches x ≥ 0 between the
/// plate's faces — at the front face for x < 0 (distance w = RECEIVER − PLATE.0), at the back
/// face for x > 0 (w = RECEIVER − PLATE.1) — so the visibility is Φ(−x / (w·σ)).
fn visibility(x: f64, sigma: f64) -> f64 {
    let w = RECEIVER - if x < 0.0 { PLATE.0 } else { PLATE.1 };
    normal_cdf(-x / (w * sigma))
}

/// The receiver's RMSE against the closed form over every receiver pixel and over the penumbra
/// band (|x| < 4wσ), and the largest offset of the half-shadow line from the projected geometric
/// one (pixels), for a `WIDTH × HEIGHT` linear image (`image[3·(j·W + i)]`, the red channel)
/// seen at `fov`: `(rmse, band, line)`, printed.
fn measure(what: &str, fov: f64, image: &[f32]) -> (f64, f64, f64) {
    let value = |i: u32, j: u32| f64::from(image[3 * (j * WIDTH + i) as usize]);
    let (mut sum, mut n, mut band_sum, mut band_n) = (0.0, 0u32, 0.0, 0u32);
    let mut worst_line: f64 = 0.0;
    let mut rows = 0;
    for j in 0..HEIGHT {
        let mut row: Vec<(u32, f64, f64)> = Vec::new();
        for i in 0..WIDTH {
            if let Some(p) = receiver_point(fov, i, j) {
                let (got, want) = (value(i, j), visibility(p.x, sigma(fov)));
                let d = got - want;
                sum += d * d;
                n += 1;
                if p.x.abs() < 4.0 * RECEIVER * sigma(fov) {
                    band_sum += d * d;
                    band_n += 1;
                }
                row.push((i, got, want));
            }
        }
        // The shadow line: where each profile crosses ½, interpolated between neighbouring
        // receiver pixels; the closed form's crossing is the geometric line x = 0 projected.
        let cross = |pick: fn(&(u32, f64, f64)) -> f64| {
            row.windows(2).find_map(|w| {
                let (a, b) = (pick(&w[0]), pick(&w[1]));
                (w[1].0 == w[0].0 + 1 && (a - 0.5) * (b - 0.5) <= 0.0 && a != b)
                    .then(|| f64::from(w[0].0) + (0.5 - a) / (b - a))
            })
        };
        if let (Some(got), Some(want)) = (cross(|t| t.1), cross(|t| t.2)) {
            worst_line = worst_line.max((got - want).abs());
            rows += 1;
        }
    }
    let rmse = (sum / f64::from(n)).sqrt();
    let band = (band_sum / f64::from(band_n)).sqrt();
    eprintln!(
        "{what}, fov {fov}: {n} receiver pixels, RMSE {rmse:.2e} (penumbra band, {band_n} px: \
         {band:.2e}); shadow line within {worst_line:.3} px over {rows} rows"
    );
    assert!(
        n > 2000 && band_n > 100 && rows > 50,
        "{what}, fov {fov}: too few pixels checked"
    );
    (rmse, band, worst_line)
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
    let mut s = scene(60.0, "");
    s.lights.push(s.lights[0].clone());
    s.lights[1].color = [0.5, 0.25, 0.125];
    let req = RenderRequest {
        aovs: vec![
            convshadow::pipeline::Aov::Light(1),
            convshadow::pipeline::Aov::Depth,
            convshadow::pipeline::Aov::Light(0),
        ],
        ..RenderRequest::default()
    };
    let r = render(&s, &req).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.light_layers.len(), 2);
    let sum: Vec<f32> = (r.light_layers[0].1.iter().zip(&r.light_layers[1].1))
        .map(|(a, b)| a + b)
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
    let s = scene(60.0, "");
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
