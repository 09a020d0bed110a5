//! The shadow-ray reference seen through a perspective camera (issue 42) against the closed
//! form: an opaque half-plane 0.5 in front of a receiver plane, a Gaussian directional light
//! along the view (so the light's slopes per unit depth are its own: no linearisation of a
//! turned Gaussian enters), the eye off to the side at fields of view of 30° and 90°. The test
//! traces every pixel's ray itself (its own camera basis from `eye`, `look_at`, `up` and
//! `fov_deg`), meets the receiver and evaluates the visibility there in closed form; the
//! reference must match it, and its shadow line must sit where the geometric one projects.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::render_reference;
use convshadow::reference::normal_cdf;
use glam::DVec3;

const EYE: DVec3 = DVec3::new(-1.0, 0.3, -4.0);
const LOOK_AT: DVec3 = DVec3::new(-1.0, 0.3, 0.0);
/// The receiver's front face (depth z).
const RECEIVER: f64 = 0.5;
/// The occluder plate: x ≥ 0, between these depths (thin, so both faces count).
const PLATE: (f64, f64) = (-0.001, 0.001);
/// The light's angular standard deviation (isotropic; its slopes' σ per unit distance).
const SIGMA: f64 = 0.05;
const WIDTH: u32 = 192;
const HEIGHT: u32 = 144;

fn scene(fov_deg: f64) -> Scene {
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
slabs = 64
optimal_distance = 0.5
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
        LOOK_AT.x,
        LOOK_AT.y,
        LOOK_AT.z,
        v = SIGMA * SIGMA,
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
    let forward = (LOOK_AT - EYE).normalize();
    let up = DVec3::Y;
    let down = -(up - forward * up.dot(forward)).normalize();
    let right = down.cross(forward);
    let f = 0.5 * f64::from(HEIGHT) / (0.5 * fov_deg).to_radians().tan();
    let dx = (f64::from(i) + 0.5 - 0.5 * f64::from(WIDTH)) / f;
    let dy = (f64::from(j) + 0.5 - 0.5 * f64::from(HEIGHT)) / f;
    let d = forward + right * dx + down * dy;
    let at = |z: f64| EYE + d * ((z - EYE.z) / d.z);
    let hit = at(RECEIVER);
    let on_receiver = hit.x.abs() < 2.9 && hit.y.abs() < 2.9;
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
fn visibility(x: f64) -> f64 {
    let w = RECEIVER - if x < 0.0 { PLATE.0 } else { PLATE.1 };
    normal_cdf(-x / (w * SIGMA))
}

#[test]
fn perspective_reference_matches_the_closed_form_edge_over_a_receiver() {
    for fov in [30.0, 90.0] {
        let scene = scene(fov);
        let r = render_reference(&scene, 0, 256, u64::MAX / 4, false, &[], None)
            .unwrap_or_else(|e| panic!("fov {fov}: {e}"));
        let value = |i: u32, j: u32| f64::from(r.image.data[3 * (j * WIDTH + i) as usize]);
        let (mut sum, mut n, mut band_sum, mut band_n) = (0.0, 0u32, 0.0, 0u32);
        let mut worst_line: f64 = 0.0;
        let mut rows = 0;
        for j in 0..HEIGHT {
            let mut row: Vec<(u32, f64, f64)> = Vec::new();
            for i in 0..WIDTH {
                if let Some(p) = receiver_point(fov, i, j) {
                    let (got, want) = (value(i, j), visibility(p.x));
                    let d = got - want;
                    sum += d * d;
                    n += 1;
                    if p.x.abs() < 4.0 * RECEIVER * SIGMA {
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
            "fov {fov}: {n} receiver pixels, RMSE {rmse:.2e} (penumbra band, {band_n} px: {band:.2e}); \
             shadow line within {worst_line:.3} px over {rows} rows"
        );
        assert!(
            n > 2000 && band_n > 100 && rows > 50,
            "fov {fov}: too few pixels checked"
        );
        assert!(rmse <= 5e-3, "fov {fov}: RMSE {rmse:.3e}");
        assert!(band <= 5e-3, "fov {fov}: penumbra RMSE {band:.3e}");
        assert!(
            worst_line <= 0.5,
            "fov {fov}: shadow line off by {worst_line:.3} px"
        );
    }
}
