//! A material's look converges as the slabs grow (issue 40 item 3): with opacity per world unit
//! (`reference_length` defaults to 1), the RMSE between renders at successive slab counts falls
//! at least 1.6× per doubling on a thin translucent plate (measured 1.84×, 2.15×; with the old
//! default, opacity per slab, the successive RMSE was 0.029, 0.034, 0.025: no convergence).

use std::path::Path;

use convshadow::common::model::scene::Scene;
use convshadow::pipeline::{RenderRequest, render};

/// A thin green translucent plate turned 30° over a white wall, at `slabs` slabs.
fn thin_plate(slabs: u32) -> Scene {
    let text = format!(
        r#"
[image]
width = 128
height = 128
[camera]
view_width = 4.0
[sweep]
slabs = {slabs}
seed = 1
[[light]]
tilt_deg = [-30.0, -20.0]
variance = [0.01, 0.01]
[[mesh]]
shape = "box"
size = [2.0, 2.0, 0.03]
rotate_deg = [30.0, 0.0, 0.0]
translate = [0.3, 0.0, -0.5]
material = "green"
[[mesh]]
shape = "box"
size = [6.0, 6.0, 0.1]
translate = [0.0, 0.0, 1.0]
material = "wall"
[material.green]
color = [0.2, 0.9, 0.3]
opacity = 0.999
transport = [0.1, 0.9, 0.2]
[material.wall]
color = [0.9, 0.9, 0.9]
"#
    );
    Scene::parse(&text, "thin.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_thin_translucent_plate_converges_as_the_slabs_double() {
    let images: Vec<Vec<f32>> = [256, 512, 1024, 2048]
        .iter()
        .map(|&n| {
            render(&thin_plate(n), &RenderRequest::default())
                .unwrap_or_else(|e| panic!("{e}"))
                .image
                .data
        })
        .collect();
    let rmse = |a: &[f32], b: &[f32]| {
        let sq: f64 = a
            .iter()
            .zip(b)
            .map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2))
            .sum();
        (sq / a.len() as f64).sqrt()
    };
    let steps: Vec<f64> = images.windows(2).map(|w| rmse(&w[0], &w[1])).collect();
    println!("successive RMSE 256→512→1024→2048: {steps:?}");
    for w in steps.windows(2) {
        assert!(
            w[0] >= 1.6 * w[1],
            "falls less than 1.6× per doubling: {steps:?}"
        );
    }
}
