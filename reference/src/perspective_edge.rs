//! A perspective camera's closed-form case (issue 42): an opaque half-plane 0.5 in front of a
//! receiver plane, a Gaussian directional light along the view (its slopes per unit depth are
//! its own: no linearisation of a turned Gaussian enters), the eye off to the side. Every pixel's
//! ray is traced here (its own camera basis from `eye`, `look_at`, `up` and `fov_deg`), meets the
//! receiver, and the visibility there is evaluated in closed form; [`measure`] compares an image
//! with it. Shared by `tests/accuracy/perspective.rs` and the report's `perspective` family.

use glam::DVec3;

use crate::normal_cdf;

/// The eye.
pub const EYE: DVec3 = DVec3::new(-1.0, 0.3, -4.0);
/// The receiver's front face (depth z).
pub const RECEIVER: f64 = 0.5;
/// The occluder plate: x ≥ 0, between these depths (thin, so both faces count).
pub const PLATE: (f64, f64) = (-0.001, 0.001);
/// Image width.
pub const WIDTH: u32 = 192;
/// Image height.
pub const HEIGHT: u32 = 144;

/// The point looked at: on the view axis (+z from the eye), at about 4, at the distance that
/// makes the slab grid's pixel (the pixel's footprint there) divide the edge's distance from
/// the axis, 1, a whole number of times — the edge on a pixel boundary of the grid the light is
/// swept on, as in the orthographic edge tests (an edge between pixel centres is quantised by
/// the LDI, issue 46: measured in how-it-works.md).
pub fn look_at(fov_deg: f64) -> DVec3 {
    EYE + DVec3::Z * (focal(fov_deg) / grid_pixel(fov_deg))
}

/// The focal length in pixels.
pub fn focal(fov_deg: f64) -> f64 {
    0.5 * f64::from(HEIGHT) / (0.5 * fov_deg).to_radians().tan()
}

/// The grid pixels per world unit at the `look_at` distance (a whole number, see [`look_at`]).
pub fn grid_pixel(fov_deg: f64) -> f64 {
    (focal(fov_deg) / 4.0).round()
}

/// The light's angular standard deviation (isotropic; its slopes' σ per unit distance): a
/// penumbra of 1.5 grid pixels (σ·w, w = 0.5) — a light buffer of pixels resolves no narrower
/// one, in perspective as in orthographic views.
pub fn sigma(fov_deg: f64) -> f64 {
    1.5 / (grid_pixel(fov_deg) * RECEIVER)
}

/// The scene's text at vertical field of view `fov_deg`, `sweep` added to `[sweep]`.
pub fn scene_toml(fov_deg: f64, sweep: &str) -> String {
    scene_toml_with_edge(fov_deg, sweep, 0.0)
}

/// [`scene_toml`] with the half-plane's edge at world x = `edge` (0: on a boundary of the grid's
/// pixels; `k / grid_pixel` puts it k of those pixels across).
pub fn scene_toml_with_edge(fov_deg: f64, sweep: &str, edge: f64) -> String {
    let look = look_at(fov_deg);
    format!(
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
translate = [{x:e}, 0.0, {c:e}]
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
        x = 1.5 + edge,
    )
}

/// Where pixel centre (i + ½, j + ½)'s ray from the eye meets the receiver's front face
/// (z = RECEIVER), if it does within the face and not through the plate; the test's own camera
/// (right-handed, y down).
pub fn receiver_point(fov_deg: f64, i: u32, j: u32) -> Option<DVec3> {
    receiver_point_with_edge(fov_deg, i, j, 0.0)
}

/// [`receiver_point`] with the half-plane's edge at world x = `edge`.
pub fn receiver_point_with_edge(fov_deg: f64, i: u32, j: u32, edge: f64) -> Option<DVec3> {
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
    // The plate (x in [edge, edge + 3], |y| ≤ 3) seen before the receiver: the ray is inside it
    // at one of its faces (the ray is a straight line, the plate convex and thin).
    let through_plate = [PLATE.0, PLATE.1].iter().any(|&z| {
        let p = at(z);
        p.x - edge >= -1e-9 && p.x - edge <= 3.0 && p.y.abs() <= 3.0
    });
    (on_receiver && !through_plate).then_some(hit)
}

/// The closed form: a shadow ray from receiver point x heading back towards the light with
/// slope s ~ N(0, σ²) along x per unit depth is blocked where it reaches x ≥ 0 between the
/// plate's faces — at the front face for x < 0 (distance w = RECEIVER − PLATE.0), at the back
/// face for x > 0 (w = RECEIVER − PLATE.1) — so the visibility is Φ(−x / (w·σ)).
pub fn visibility(x: f64, sigma: f64) -> f64 {
    let w = RECEIVER - if x < 0.0 { PLATE.0 } else { PLATE.1 };
    normal_cdf(-x / (w * sigma))
}

/// The receiver's RMSE against the closed form over every receiver pixel and over the penumbra
/// band (|x| < 4wσ), and the largest offset of the half-shadow line from the projected geometric
/// one (pixels), for a `WIDTH × HEIGHT` linear image (`image[3·(j·W + i)]`, the red channel)
/// seen at `fov`: `(rmse, band, line)`; `Err` when too few pixels were compared (more than 2000
/// receiver pixels, 100 in the band and 50 rows with a shadow line are wanted).
pub fn measure(fov: f64, image: &[f32]) -> Result<(f64, f64, f64), String> {
    measure_with_edge(fov, image, 0.0)
}

/// [`measure`] with the half-plane's edge at world x = `edge` (the closed form moved with it).
pub fn measure_with_edge(fov: f64, image: &[f32], edge: f64) -> Result<(f64, f64, f64), String> {
    let value = |i: u32, j: u32| f64::from(image[3 * (j * WIDTH + i) as usize]);
    let (mut sum, mut n, mut band_sum, mut band_n) = (0.0, 0u32, 0.0, 0u32);
    let mut worst_line: f64 = 0.0;
    let mut rows = 0;
    for j in 0..HEIGHT {
        let mut row: Vec<(u32, f64, f64)> = Vec::new();
        for i in 0..WIDTH {
            if let Some(p) = receiver_point_with_edge(fov, i, j, edge) {
                let x = p.x - edge;
                let (got, want) = (value(i, j), visibility(x, sigma(fov)));
                let d = got - want;
                sum += d * d;
                n += 1;
                if x.abs() < 4.0 * RECEIVER * sigma(fov) {
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
    if n <= 2000 || band_n <= 100 || rows <= 50 {
        return Err(format!(
            "fov {fov}: too few pixels compared ({n} on the receiver, {band_n} in the band, \
             {rows} rows)"
        ));
    }
    let rmse = (sum / f64::from(n)).sqrt();
    let band = (band_sum / f64::from(band_n)).sqrt();
    Ok((rmse, band, worst_line))
}
