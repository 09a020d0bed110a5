//! Scenes with point or spot lights (docs/how-it-works.md, "The sweep's point lights"): the
//! directional lights rendered as without them, each point or spot light in a pass of its own on
//! its own grid (`super::point`), the images added — the image is linear in each light. A light
//! amid the meshes is two passes, one per side, the far side's image seen through the near one's.

use super::passes::{add_pass, composite_over};
use super::perspective::{eye_geometry, render_perspective_pass};
use super::point::{Placement, placement, visible_points};
use super::{Aov, RenderError, RenderRequest, Rendered, image_fingerprint};
use convshadow_common::model::scene::{Scene, SlabSpec};
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_cpu::composite::finish;
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
    // Each pass: the scene's lights it has, and how it is rendered.
    let mut passes: Vec<(Vec<usize>, Pass)> = Vec::new();
    if !directional.is_empty() {
        passes.push((
            directional.clone(),
            Pass::Directional(with_lights(scene, &directional)),
        ));
    }
    let eye = eye_geometry(scene)?;
    for l in (0..scene.lights.len()).filter(|&l| is_point(l)) {
        let pass = with_lights(scene, &[l]);
        let pass = match placement(scene, &eye, l)? {
            Placement::Before => Pass::Point(pass),
            // Its light travels towards the viewer: swept from the far end, looking back.
            Placement::Behind => Pass::Point(turned_round(pass)),
            Placement::Amid { front, back } => {
                // Each side on the whole scene's slab thickness.
                let on_scenes_slabs = |meshes: &[usize]| {
                    let mut side = with_meshes(&pass, meshes);
                    side.sweep.slabs = SlabSpec::Distance(eye.slab_distance);
                    side
                };
                Pass::Amid {
                    front: Box::new(on_scenes_slabs(&front)),
                    back: Box::new(on_scenes_slabs(&back)),
                }
            }
        };
        passes.push((vec![l], pass));
    }
    // Where the eye's rays meet the meshes, which bounds the grid of every light before or
    // behind every mesh (the eye's LDI once more; each pass builds its own within its budget;
    // a light amid the meshes has one per side instead).
    let visible = if passes.iter().any(|(_, p)| matches!(p, Pass::Point(_))) {
        eye_rays_among_meshes(&eye, req)?
    } else {
        Vec::new()
    };
    let mut total: Option<Rendered> = None;
    let mut layers = Vec::new();
    for (i, (lights, pass)) in passes.into_iter().enumerate() {
        // The background once, in the first pass.
        let background = if i == 0 {
            scene.image.background
        } else {
            [0.0; 3]
        };
        // The pass's layers: the depth in the first, each light's where it is (renumbered).
        let aovs: Vec<Aov> = requested
            .iter()
            .filter_map(|aov| match *aov {
                Aov::Depth => (i == 0).then_some(Aov::Depth),
                Aov::Light(l) => lights.iter().position(|&k| k == l).map(Aov::Light),
            })
            .collect();
        let mut rendered = match pass {
            Pass::Directional(mut pass) => {
                pass.image.background = background;
                super::render(&pass, &RenderRequest { aovs, ..*req })?
            }
            Pass::Point(mut pass) => {
                pass.image.background = background;
                render_perspective_pass(&pass, &eye, req, &aovs, Some(&visible))?
            }
            Pass::Amid { front, back } => {
                // Each side with its own eye (its meshes alone), on black.
                let side = |pass: Scene, turn: bool| -> Result<Rendered, RenderError> {
                    let side_eye = eye_geometry(&pass)?;
                    let side_visible = eye_rays_among_meshes(&side_eye, req)?;
                    let mut pass = if turn { turned_round(pass) } else { pass };
                    pass.image.background = [0.0; 3];
                    render_perspective_pass(&pass, &side_eye, req, &aovs, Some(&side_visible))
                };
                let mut near = side(*front, true)?;
                composite_over(&mut near, side(*back, false)?);
                add_background(&mut near, background);
                near
            }
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

/// How one pass of [`render_with_point_lights`] is rendered.
enum Pass {
    /// The directional lights, on the slab grid ([`super::render`]).
    Directional(Scene),
    /// A point or spot light before every mesh, or behind every mesh (turned round), on its own
    /// grid.
    Point(Scene),
    /// A point or spot light amid the meshes ([`Placement::Amid`]): the meshes in front of it
    /// lit by a turned-round pass, those behind it by an ordinary one, each with its own eye;
    /// the image is the front's composited over the back's (`C_f + (1 − A_f)·C_b`).
    Amid {
        /// The meshes nearer the camera than the light (turned round when rendered).
        front: Box<Scene>,
        /// The meshes farther than it.
        back: Box<Scene>,
    },
}

/// `pass` turned round: its camera looks back along the view, its light swept from the far end.
fn turned_round(mut pass: Scene) -> Scene {
    pass.camera = pass.camera.turned_round();
    pass.turned_round = true;
    pass
}

/// `scene` with only its meshes `meshes` (scene indices, in that order).
fn with_meshes(scene: &Scene, meshes: &[usize]) -> Scene {
    let mut side = scene.clone();
    side.meshes = meshes.iter().map(|&i| scene.meshes[i].clone()).collect();
    side
}

/// Where the rays of the eye `eye` meet its meshes ([`visible_points`], from its LDI built
/// within the request's budget): what bounds a point light's grid.
fn eye_rays_among_meshes(
    eye: &SceneGeometry,
    req: &RenderRequest<'_>,
) -> Result<Vec<glam::DVec3>, RenderError> {
    let ldi = Ldi::build(&eye.raster, req.memory_budget)?;
    Ok(visible_points(eye, &ldi))
}

/// The background `background` composited behind `pass`'s image (rendered on black), where its
/// opacity leaves it visible: the sweep's own `C + (1 − A)·background` (`finish`).
fn add_background(pass: &mut Rendered, background: [f32; 3]) {
    if background == [0.0; 3] {
        return;
    }
    for (pixel, &a) in pass.image.data.chunks_exact_mut(3).zip(&pass.alpha) {
        finish(pixel.try_into().expect("three channels"), a, background);
    }
}

/// `scene` with only its lights `lights` (in that order).
fn with_lights(scene: &Scene, lights: &[usize]) -> Scene {
    let mut pass = scene.clone();
    pass.lights = lights.iter().map(|&l| scene.lights[l].clone()).collect();
    pass
}
