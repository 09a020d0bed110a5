//! Pure-convolution harness: an "empty" scene whose grid sees only the kernel (a marker box far
//! outside the view sets the depth range), and the moments of a light buffer. Shared by
//! `tests/accuracy/sweep_accuracy.rs` and `tests/accuracy/hard_cases.rs`.

use std::path::Path;

use convshadow_common::model::scene::{Scene, SceneError};
use convshadow_common::plan::RenderPlan;
use convshadow_cpu::sweep::SweepOutput;

use crate::edge::light_at;

/// `n` slabs of thickness exactly 1 with d1 = 1 and pixel size 1 on a `grid`² image, so that
/// in pixel units μκ = −tan ω and Σκ = R diag(σ²) Rᵀ.
pub fn empty_scene(
    n: u32,
    grid: u32,
    tilt: [f64; 2],
    variance: [f64; 2],
    rotation: f64,
    kernel: &str,
    compensate: bool,
) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
[image]
width = {grid}
height = {grid}
[camera]
view_width = {grid}.0
[sweep]
guard_band = 0  # the impulse response is read on the grid as the image
slab_distance = 1.0
optimal_distance = 1.0
penumbra = "iterated"  # the iterated kernel's impulse response
subpixel_shadows = false  # the bare kernel: no depth plane, no levels
kernel = "{kernel}"
variance_compensation = {compensate}
[[light]]
tilt_deg = [{}, {}]
variance = [{:e}, {:e}]
rotation_deg = {rotation}
[[mesh]]
shape = "box"
size = [1.0, 1.0, {}]
translate = [100000.0, 0.0, 0.0]
material = "m"
[material.m]
"#,
        tilt[0],
        tilt[1],
        variance[0],
        variance[1],
        f64::from(n) - 0.5
    );
    Scene::parse(&text, "<empty scene>", Path::new("."))
}

/// Mass, mean and covariance (pixels) of light channel 0 of light 0 inside the square window
/// of half-side `radius` around `center`.
pub fn moments(
    plan: &RenderPlan,
    out: &SweepOutput,
    center: [f64; 2],
    radius: f64,
) -> (f64, [f64; 2], [[f64; 2]; 2]) {
    let (mut m0, mut mx, mut my, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for y in 0..plan.grid_height as usize {
        for x in 0..plan.grid_width as usize {
            let (fx, fy) = (x as f64, y as f64);
            if (fx - center[0]).abs() > radius || (fy - center[1]).abs() > radius {
                continue;
            }
            let w = light_at(plan, out, x, y);
            m0 += w;
            mx += w * fx;
            my += w * fy;
            sxx += w * fx * fx;
            sxy += w * fx * fy;
            syy += w * fy * fy;
        }
    }
    let (ux, uy) = (mx / m0, my / m0);
    let cov = [
        [sxx / m0 - ux * ux, sxy / m0 - ux * uy],
        [sxy / m0 - ux * uy, syy / m0 - uy * uy],
    ];
    (m0, [ux, uy], cov)
}

/// A light buffer that is 1 at grid pixel (c, c) and 0 elsewhere.
pub fn impulse(plan: &RenderPlan, c: usize) -> Vec<f32> {
    let mut v = vec![0.0f32; plan.light_row_len() * plan.grid_height as usize];
    v[c * plan.light_row_len() + c] = 1.0;
    v
}
