//! The `direction` family: a directional light at an angle from the view axis (issue 41), an
//! opaque thin half-plane's shadow on a translucent sheet, both perpendicular to the light
//! (`convshadow_reference::half_plane_sheet`); reference: that set-up's closed form along each
//! view ray. Lights at more than 90° cost a second, turned-round pass (how-it-works.md, "Lights
//! from in front of the viewer"). The same set-up with a soft point light on the light's axis
//! (its distance per angle: `POINT_SETUPS`), against the visibility integrated over its
//! Gaussian, distance penumbra only (the sweep gives a soft point light no other).

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_reference::half_plane_sheet::{
    HEIGHT, POINT_SETUPS, SLAB_DISTANCE, SheetLight, W, WIDTH, expected_row, expected_row_point,
    point_light_at, point_profile_rmse, point_scene_toml, profile_rmse, scene_toml,
};

use super::row::Row;
use crate::pipeline::{RenderRequest, Rendered, render};

/// The angles (degrees) between the light's travel and the view direction of the full report.
pub const VIEW_ANGLES: [f64; 6] = [0.0, 45.0, 80.0, 100.0, 135.0, 180.0];
/// The angles of the quick report: along the view, beside and behind the objects, against it.
pub const QUICK_VIEW_ANGLES: [f64; 3] = [0.0, 100.0, 180.0];

/// The lights (name, light) of the family: isotropic, and (full report) rotated anisotropic.
pub fn lights(quick: bool) -> Vec<(&'static str, SheetLight)> {
    let mut v = vec![("isotropic", SheetLight::ISOTROPIC)];
    if !quick {
        v.push(("rotated", SheetLight::ROTATED));
    }
    v
}

/// One case: the light `light` (named `level`) at `theta` degrees from the view, swept with
/// `penumbra` and the default kernel; its time and its profile's RMSE against the closed form.
pub fn direction_row(
    theta: f64,
    (level, light): (&str, SheetLight),
    penumbra: Penumbra,
) -> Result<Row, String> {
    // The iterated penumbra is right at d1: the sheet's distance behind the half-plane.
    let sweep = match penumbra {
        Penumbra::Iterated => format!("penumbra = \"iterated\"\noptimal_distance = {W}"),
        Penumbra::Distance => "penumbra = \"distance\"".to_string(),
    };
    let text = scene_toml(theta, light, &sweep);
    let scene = Scene::parse(&text, "direction.toml", Path::new(".")).map_err(|e| e.to_string())?;
    let rendered = render(&scene, &RenderRequest::default()).map_err(|e| e.to_string())?;
    let (rmse, pixels) = profile_rmse(&rendered.image.data, &expected_row(theta, light))
        .map_err(|e| format!("direction {theta}°: {e}"))?;
    let passes = passes(&rendered);
    Ok(Row {
        family: "direction".into(),
        kernel: scene.sweep.kernel.to_string(),
        penumbra: penumbra.to_string(),
        slabs: rendered.slabs_swept,
        variance_level: level.into(),
        variance: Some(light.var_x()),
        compensation: scene.sweep.variance_compensation,
        width: WIDTH,
        height: HEIGHT,
        time_ms: rendered.seconds_sweep * 1e3,
        rmse_correct: Some(rmse),
        view_angle_deg: Some(theta),
        note: format!(
            "half-plane over a translucent sheet, both perpendicular to the light; \
             view_angle_deg from the light's travel to the view direction; slab distance \
             {SLAB_DISTANCE}, slabs = every pass's; variance = the light's σ² across the edge; \
             RMSE of the sheet's profile normalised by its lit level over {pixels} penumbra \
             pixels against the closed form; {passes}"
        ),
        ..Row::default()
    })
}

/// The point light's case at `theta` degrees from the view (one of `POINT_SETUPS`' angles): its
/// time and its profile's RMSE, each pixel normalised by its own unshadowed light, against the
/// visibility integrated over the light's Gaussian.
pub fn point_direction_row(theta: f64) -> Result<Row, String> {
    let (_, distance, resolution) = POINT_SETUPS
        .into_iter()
        .find(|s| s.0 == theta)
        .ok_or_else(|| format!("no point-light set-up at {theta}°"))?;
    let (position, radius) = point_light_at(distance);
    let text = point_scene_toml(theta, position, radius, "");
    let mut scene =
        Scene::parse(&text, "direction_point.toml", Path::new(".")).map_err(|e| e.to_string())?;
    scene.sweep.light_resolution = resolution;
    let rendered = render(&scene, &RenderRequest::default()).map_err(|e| e.to_string())?;
    let (rmse, pixels) = point_profile_rmse(
        &rendered.image.data,
        &expected_row_point(theta, position, radius),
    )
    .map_err(|e| format!("point light at {theta}°: {e}"))?;
    let passes = passes(&rendered);
    Ok(Row {
        family: "direction".into(),
        kernel: scene.sweep.kernel.to_string(),
        penumbra: scene.sweep.penumbra.to_string(),
        slabs: rendered.slabs_swept,
        variance_level: "point".into(),
        compensation: scene.sweep.variance_compensation,
        width: WIDTH,
        height: HEIGHT,
        time_ms: rendered.seconds_sweep * 1e3,
        rmse_correct: Some(rmse),
        view_angle_deg: Some(theta),
        light_resolution: Some(resolution),
        note: format!(
            "soft point light of radius {radius} on the axis, {distance} before the half-plane \
             (as near as the sweep allows at this angle: before or behind every mesh along the \
             view), over a translucent sheet; light grid at {resolution} cells per pixel; \
             view_angle_deg from the light's axis to the view direction; slab distance \
             {SLAB_DISTANCE}; RMSE of the sheet's profile, each pixel over its own unshadowed \
             light and normalised by the lit level, over {pixels} penumbra pixels against the \
             visibility integrated over the light's Gaussian; {passes}"
        ),
        ..Row::default()
    })
}

/// How many passes the render swept: a light towards the viewer adds a turned-round one.
fn passes(rendered: &Rendered) -> &'static str {
    if rendered.turned_round_lights > 0 {
        "two passes"
    } else {
        "one pass"
    }
}
