//! The `point` family: a soft point light (issue 41) over an opaque half-plane, its penumbra on
//! a wall behind (`convshadow_reference::point_edge`), seen orthographically and in perspective,
//! at two light-grid resolutions; reference: the visibility integrated over the light's 3D
//! Gaussian at the wall point each pixel's ray meets.

use std::path::Path;

use convshadow_common::model::scene::Scene;
use convshadow_reference::point_edge::{View, scene_toml, wall_rmse};
use glam::DVec3;

use super::row::Row;
use crate::pipeline::{RenderRequest, render};

/// The light grid's resolutions (cells per eye pixel) of the family.
pub const LIGHT_RESOLUTIONS: [f64; 2] = [1.0, 4.0];

/// The image (pixels) and the light: its centre and radius (the edge's rays 6° off the view).
const SIZE: (usize, usize) = (128, 16);
const CENTRE: [f64; 3] = [0.2, 0.1, -2.0];
const RADIUS: f64 = 0.1;
/// The perspective camera's vertical field of view (degrees).
const FOV_DEG: f64 = 4.0;

/// One case: the wall seen orthographically or (`perspective`) at a 4° field of view, the light grid at
/// `light_resolution`; its time and the wall's RMSE against the integrated visibility.
pub fn point_row(perspective: bool, light_resolution: f64) -> Result<Row, String> {
    let (camera, view) = if perspective {
        let focal = 0.5 * SIZE.1 as f64 / (0.5 * FOV_DEG).to_radians().tan();
        (
            format!(
                "projection = \"perspective\"\neye = [0.0, 0.0, -4.0]\nlook_at = [0.0, 0.0, \
                 1.0]\nfov_deg = {FOV_DEG:?}"
            ),
            View::Perspective(focal),
        )
    } else {
        (
            "direction = [0.0, 0.0, 1.0]\nview_width = 2.0".to_string(),
            View::Orthographic(2.0),
        )
    };
    let [x, y, z] = CENTRE;
    let light = format!("kind = \"point\"\nposition = [{x:?}, {y:?}, {z:?}]\nradius = {RADIUS:?}");
    let mut scene = Scene::parse(
        &scene_toml(SIZE, &camera, 64, &light),
        "point.toml",
        Path::new("."),
    )
    .map_err(|e| e.to_string())?;
    scene.sweep.light_resolution = light_resolution;
    let rendered = render(&scene, &RenderRequest::default()).map_err(|e| e.to_string())?;
    let (rmse, _) = wall_rmse(
        &rendered.image.data,
        SIZE,
        view,
        DVec3::from(CENTRE),
        RADIUS,
    );
    Ok(Row {
        family: "point".into(),
        kernel: scene.sweep.kernel.to_string(),
        penumbra: scene.sweep.penumbra.to_string(),
        slabs: rendered.slabs_swept,
        variance_level: format!("point r = {RADIUS}"),
        compensation: scene.sweep.variance_compensation,
        width: SIZE.0 as u32,
        height: SIZE.1 as u32,
        time_ms: rendered.seconds_sweep * 1e3,
        rmse_correct: Some(rmse),
        fov_deg: perspective.then_some(FOV_DEG),
        light_resolution: Some(light_resolution),
        note: format!(
            "point light of radius {RADIUS} two units before an opaque half-plane, its penumbra \
             on a wall one unit behind, {}; RMSE over the wall, normalised by the unshadowed \
             light, against the visibility integrated over the light's Gaussian",
            if perspective {
                "perspective camera"
            } else {
                "orthographic camera"
            }
        ),
        ..Row::default()
    })
}
