//! The `direction` family: a directional light at an angle from the view axis (issue 41), an
//! opaque thin half-plane's shadow on a translucent sheet, both perpendicular to the light
//! (`convshadow_reference::half_plane_sheet`); reference: that set-up's closed form along each
//! view ray. Lights at more than 90° cost a second, turned-round pass (how-it-works.md, "Lights
//! from in front of the viewer").

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene};
use convshadow_reference::half_plane_sheet::{
    HEIGHT, SLAB_DISTANCE, SheetLight, W, WIDTH, expected_row, profile_rmse, scene_toml,
};

use super::row::Row;
use crate::pipeline::{RenderRequest, render};

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
    let passes = if rendered.turned_round_lights > 0 {
        "two passes"
    } else {
        "one pass"
    };
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
