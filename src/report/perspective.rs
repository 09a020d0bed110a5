//! The `perspective` family: a perspective camera (issue 42) over an opaque half-plane's shadow
//! on a receiver, the light along the view (`convshadow_reference::perspective_edge`);
//! reference: the closed form where each pixel's ray meets the receiver.

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_reference::perspective_edge::{HEIGHT, RECEIVER, WIDTH, measure, scene_toml, sigma};

use super::row::Row;
use crate::pipeline::{RenderRequest, render};

/// The vertical fields of view (degrees) of the family.
pub const FIELDS_OF_VIEW: [f64; 2] = [30.0, 90.0];

/// One case: the edge seen at `fov` degrees, swept with `penumbra` and the default kernel; its
/// time, the receiver's RMSE against the closed form, and the half-shadow line's offset.
pub fn perspective_row(fov: f64, penumbra: Penumbra) -> Result<Row, String> {
    // The scene's d1 is the receiver's distance behind the half-plane, where the iterated
    // penumbra is right.
    debug_assert!(scene_toml(fov, "").contains(&format!("optimal_distance = {RECEIVER}")));
    let text = scene_toml(fov, &format!("penumbra = \"{penumbra}\""));
    let scene =
        Scene::parse(&text, "perspective.toml", Path::new(".")).map_err(|e| e.to_string())?;
    let rendered = render(&scene, &RenderRequest::default()).map_err(|e| e.to_string())?;
    let (rmse, band, line) = measure(fov, &rendered.image.data)?;
    Ok(Row {
        family: "perspective".into(),
        kernel: scene.sweep.kernel.to_string(),
        penumbra: penumbra.to_string(),
        slabs: rendered.slabs_swept,
        variance_level: "edge".into(),
        variance: Some(sigma(fov) * sigma(fov)),
        compensation: scene.sweep.variance_compensation,
        width: WIDTH,
        height: HEIGHT,
        time_ms: rendered.seconds_sweep * 1e3,
        rmse_correct: Some(rmse),
        isoline_err_px: Some(line),
        fov_deg: Some(fov),
        note: format!(
            "perspective camera: half-plane 0.5 before a receiver, the light along the view, \
             the eye off the edge's axis; RMSE over the receiver against the closed form along \
             each pixel's ray ({band:.2e} over the penumbra band); isoline_err_px: the \
             half-shadow line's largest offset from the projected geometric line"
        ),
        ..Row::default()
    })
}
