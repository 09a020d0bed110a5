//! Scenes with point or spot lights (docs/how-it-works.md, "The sweep's point lights"): the
//! directional lights rendered as without them, each point or spot light in a pass of its own on
//! its own grid (`super::point`), the images added — the image is linear in each light.

use super::passes::add_pass;
use super::perspective::{eye_geometry, render_perspective_pass};
use super::point::{behind_every_mesh, visible_points};
use super::{Aov, RenderError, RenderRequest, Rendered, image_fingerprint};
use convshadow_common::model::scene::Scene;
use convshadow_cpu::ldi::{BuildLdi, Ldi};

/// [`super::render`] for a scene with point or spot lights: its directional lights rendered as
/// without them (one scene, [`super::render`]), each point or spot light in a pass of its own
/// ([`render_perspective_pass`] on its grid, `super::point::point_grid`), the images added with
/// the background once (the first pass's). The depth layer is the first pass's; each light layer
/// the pass's that has the light. Every pass on the request's backend (the GPU port runs the
/// point grids' sweep and eye pass as the CPU does: `gpu/src/shaders/eye.wgsl` `point_terms`).
pub(super) fn render_with_point_lights(
    scene: &Scene,
    req: &RenderRequest<'_>,
) -> Result<Rendered, RenderError> {
    let is_point = |l: usize| scene.lights[l].point.is_some();
    let requested = req.aovs.clone();
    let req = &RenderRequest {
        aovs: Vec::new(),
        ..*req
    };
    let directional: Vec<usize> = (0..scene.lights.len()).filter(|&l| !is_point(l)).collect();
    // Each pass: the scene's lights it has, and the scene with just those.
    let mut passes: Vec<(Vec<usize>, Scene)> = Vec::new();
    if !directional.is_empty() {
        passes.push((directional.clone(), with_lights(scene, &directional)));
    }
    let eye = eye_geometry(scene)?;
    for l in (0..scene.lights.len()).filter(|&l| is_point(l)) {
        let mut pass = with_lights(scene, &[l]);
        if behind_every_mesh(&eye, &scene.lights[l]) {
            // Its light travels towards the viewer: swept from the far end, looking back.
            pass.camera = pass.camera.turned_round();
            pass.turned_round = true;
        }
        passes.push((vec![l], pass));
    }
    // Where the eye's rays meet the meshes, which bounds every point light's grid (the eye's
    // LDI once more; each pass builds its own within its budget).
    let visible = {
        let ldi = Ldi::build(&eye.raster, req.memory_budget)?;
        visible_points(&eye, &ldi)
    };
    let mut total: Option<Rendered> = None;
    let mut layers = Vec::new();
    for (i, (lights, mut pass)) in passes.into_iter().enumerate() {
        if i > 0 {
            // The background once, in the first pass.
            pass.image.background = [0.0; 3];
        }
        // The pass's layers: the depth in the first, each light's where it is (renumbered).
        let aovs: Vec<Aov> = requested
            .iter()
            .filter_map(|aov| match *aov {
                Aov::Depth => (i == 0).then_some(Aov::Depth),
                Aov::Light(l) => lights.iter().position(|&k| k == l).map(Aov::Light),
            })
            .collect();
        let mut rendered = if is_point(lights[0]) {
            render_perspective_pass(&pass, &eye, req, &aovs, Some(&visible))?
        } else {
            super::render(&pass, &RenderRequest { aovs, ..*req })?
        };
        for (index, layer) in std::mem::take(&mut rendered.light_layers) {
            layers.push((lights[index], layer));
        }
        match &mut total {
            None => total = Some(rendered),
            Some(t) => add_pass(t, rendered),
        }
    }
    let mut total = total.expect("a scene has at least one light");
    total.image_hash = image_fingerprint(&total.image.data);
    // The light layers in request order.
    total.light_layers = requested
        .iter()
        .filter_map(|aov| match *aov {
            Aov::Light(l) => layers.iter().find(|(k, _)| *k == l).cloned(),
            Aov::Depth => None,
        })
        .collect();
    Ok(total)
}

/// `scene` with only its lights `lights` (in that order).
fn with_lights(scene: &Scene, lights: &[usize]) -> Scene {
    let mut pass = scene.clone();
    pass.lights = lights.iter().map(|&l| scene.lights[l].clone()).collect();
    pass
}
