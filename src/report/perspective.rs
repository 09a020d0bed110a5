//! The `perspective` family: a perspective camera (issue 42) over an opaque half-plane's shadow
//! on a receiver, the light along the view (`convshadow_reference::perspective_edge`);
//! reference: the closed form where each pixel's ray meets the receiver.

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_reference::perspective_edge::{
    HEIGHT, RECEIVER, WIDTH, grid_pixel, measure_with_edge, scene_toml, scene_toml_with_edge, sigma,
};

use super::row::Row;
use crate::pipeline::{RenderRequest, render};

/// The vertical fields of view (degrees) of the family.
pub const FIELDS_OF_VIEW: [f64; 2] = [30.0, 90.0];

/// The light grid's resolutions (cells per eye pixel) × the edge's offset from the default
/// grid's pixel boundaries (its pixels) of the family's resolution rows (distance penumbra).
pub const LIGHT_RESOLUTIONS: [(f64, f64); 5] =
    [(0.5, 0.0), (1.0, 0.3), (0.5, 0.3), (2.0, 0.3), (4.0, 0.3)];

/// One case: the edge seen at `fov` degrees, `off` pixels of the default light grid off its
/// pixel boundaries, swept with `penumbra`, the default kernel and `light_resolution`; its
/// time, the receiver's RMSE against the closed form, and the half-shadow line's offset.
pub fn perspective_row(
    fov: f64,
    penumbra: Penumbra,
    light_resolution: f64,
    off: f64,
) -> Result<Row, String> {
    // The scene's d1 is the receiver's distance behind the half-plane, where the iterated
    // penumbra is right.
    debug_assert!(scene_toml(fov, "").contains(&format!("optimal_distance = {RECEIVER}")));
    let edge = off / grid_pixel(fov);
    let text = scene_toml_with_edge(
        fov,
        &format!("penumbra = \"{penumbra}\"\nlight_resolution = {light_resolution:?}"),
        edge,
    );
    let scene =
        Scene::parse(&text, "perspective.toml", Path::new(".")).map_err(|e| e.to_string())?;
    let rendered = render(&scene, &RenderRequest::default()).map_err(|e| e.to_string())?;
    let (rmse, band, line) = measure_with_edge(fov, &rendered.image.data, edge)?;
    Ok(Row {
        family: "perspective".into(),
        kernel: scene.sweep.kernel.to_string(),
        penumbra: penumbra.to_string(),
        slabs: rendered.slabs_swept,
        variance_level: if off == 0.0 {
            "edge".into()
        } else {
            format!("edge {off} px off")
        },
        variance: Some(sigma(fov) * sigma(fov)),
        compensation: scene.sweep.variance_compensation,
        width: WIDTH,
        height: HEIGHT,
        time_ms: rendered.seconds_sweep * 1e3,
        rmse_correct: Some(rmse),
        isoline_err_px: Some(line),
        fov_deg: Some(fov),
        light_resolution: Some(light_resolution),
        note: format!(
            "perspective camera: half-plane 0.5 before a receiver, the light along the view, \
             the eye off the edge's axis; RMSE over the receiver against the closed form along \
             each pixel's ray ({band:.2e} over the penumbra band); isoline_err_px: the \
             half-shadow line's largest offset from the projected geometric line"
        ),
        ..Row::default()
    })
}
