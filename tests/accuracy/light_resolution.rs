//! `sweep.light_resolution` with an orthographic camera (its eye then reads a light grid of its
//! own, as a perspective eye does): an opaque thin plate's edge over a receiver, the light
//! tilted so that the shadow line falls where the receiver is seen, the edge on a pixel boundary
//! and 0.3 and 0.7 of a pixel off one. Reference: the closed form at each pixel centre,
//! V = Φ(−(x − e)/(w·σ)), e = X_e − w·tan ω the shadow line (the light's slopes are N(tan ω, σ²)
//! per unit depth on the slab plane, exactly the scene's light), w the receiver's distance from
//! the plate's front face.

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{RenderRequest, render};
use convshadow::reference::edge::phi;

const WIDTH: u32 = 128;
const VIEW: f64 = 2.0;
const PX: f64 = VIEW / WIDTH as f64;
/// The receiver's front face and the plate's front face (depth).
const RECEIVER: f64 = 0.5;
const PLATE_FRONT: f64 = -0.001;
const TILT_DEG: f64 = 20.0;

/// σ of the light's slopes: a penumbra σ·w of 1.5 pixels.
fn sigma() -> f64 {
    1.5 * PX / (RECEIVER - PLATE_FRONT)
}

/// The plate covers camera x ≥ `edge` (world x ≤ −edge: the camera looks along +z, its x axis
/// is world −x), the receiver every x.
fn scene(edge: f64, light_resolution: f64) -> Scene {
    let text = format!(
        r#"
[image]
width = {WIDTH}
height = 8
[camera]
direction = [0.0, 0.0, 1.0]
view_width = {VIEW}
[sweep]
slabs = 256
light_resolution = {light_resolution:?}
[[light]]
tilt_deg = [{TILT_DEG}, 0.0]
variance = [{v:e}, {v:e}]
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.2]
translate = [0.0, 0.0, {r:e}]
material = "receiver"
[[mesh]]
shape = "box"
size = [3.0, 6.0, 0.002]
translate = [{x:e}, 0.0, 0.0]
material = "plate"
[material.receiver]
surface = "flat"
[material.plate]
color = [0.0, 0.0, 0.0]
"#,
        v = sigma() * sigma(),
        r = RECEIVER + 0.1,
        x = -edge - 1.5,
    );
    Scene::parse(&text, "light-resolution.toml", Path::new(".")).unwrap()
}

/// RMSE of the middle rows' receiver pixels within 4 penumbra widths of the shadow line, and the
/// half-shadow line's offset (pixels) from the closed form's.
fn measure(edge: f64, image: &[f32]) -> (f64, f64) {
    let w = RECEIVER - PLATE_FRONT;
    let line = edge - w * TILT_DEG.to_radians().tan();
    let (mut sum, mut n) = (0.0, 0);
    let mut worst_line: f64 = 0.0;
    for j in 2..6u32 {
        let mut row = Vec::new();
        for i in 0..WIDTH {
            let x = (f64::from(i) + 0.5 - f64::from(WIDTH) * 0.5) * PX;
            if x >= edge - PX || (x - line).abs() > 4.0 * w * sigma() {
                continue; // the plate is seen there, or the receiver is fully lit or dark
            }
            let want = phi(-(x - line) / (w * sigma()));
            let got = f64::from(image[3 * (j * WIDTH + i) as usize]);
            sum += (got - want).powi(2);
            n += 1;
            row.push((x, got, want));
        }
        // Each profile's ½ crossing, interpolated between neighbouring pixels.
        let cross = |pick: fn(&(f64, f64, f64)) -> f64| {
            row.windows(2).find_map(|w| {
                let (a, b) = (pick(&w[0]), pick(&w[1]));
                ((a - 0.5) * (b - 0.5) <= 0.0 && a != b)
                    .then(|| w[0].0 + (0.5 - a) / (b - a) * (w[1].0 - w[0].0))
            })
        };
        let (got, want) = (cross(|t| t.1), cross(|t| t.2));
        let (got, want) = (got.expect("a shadow line"), want.expect("its closed form"));
        worst_line = worst_line.max((got - want).abs() / PX);
    }
    assert!(n > 40, "{n} pixels compared");
    ((sum / f64::from(n)).sqrt(), worst_line)
}

/// Measured 2026-12-06, RMSE over the penumbra (the line's offset in pixels), the edge 0 / 0.3 /
/// 0.7 px off a pixel boundary: light_resolution 1 (the plain sweep, sub-pixel shadows) 3.6e-3
/// (0.02) / 3.9e-2 (0.34) / 4.0e-2 (0.31); 0.5: 4.3e-2 (0.33) / 7.9e-2 (0.64) / 1.3e-1 (1.03); 2: 2.2e-2
/// (0.19) / 4.6e-2 (0.36) / 4.6e-3 (0.04); 4: 2.2e-2 (0.18) / 1.5e-2 (0.12) / 2.8e-2 (0.22). The eye's read of another grid does
/// not correct the whole-cell carry of a tilted light's drift (sub-pixel shadows are the plain
/// sweep's): its shadow lines lie within a grid cell, not a few hundredths of a pixel, so a finer
/// grid does not sharpen an orthographic view's tilted shadows reliably; a coarser one is the
/// speed lever (docs/performance.md).
#[test]
fn an_orthographic_light_grid_of_its_own_keeps_shadow_lines_within_a_cell() {
    for off in [0.0, 0.3, 0.7] {
        let edge = off * PX;
        for s in [1.0, 0.5, 2.0, 4.0] {
            let r = render(&scene(edge, s), &RenderRequest::default()).unwrap();
            let (rmse, line) = measure(edge, &r.image.data);
            eprintln!(
                "edge {off} px off, light_resolution {s}: RMSE {rmse:.2e}, line {line:.3} px"
            );
            // The shadow line within one cell of the light's grid (1/s pixels); the plain
            // sweep's within half a pixel (its LDI covers pixel centres: issue 46).
            let bound = if s == 1.0 { 0.5 } else { 1.0 / s + 0.05 };
            assert!(line <= bound, "edge {off}, s {s}: line {line}");
            assert!(rmse <= 0.15, "edge {off}, s {s}: RMSE {rmse}");
            if s == 1.0 && off == 0.0 {
                assert!(rmse <= 5e-3, "the plain sweep on a pixel boundary: {rmse}");
            }
        }
    }
}
