//! A point or spot light's grid on the CPU sweep (docs/how-it-works.md, "The sweep's point
//! lights"): a perspective view from the light's centre along the view axis, whose rays are the
//! light's, so its light propagates straight down the grid's columns; the eye's rays read it slab
//! by slab (the eye pass of a perspective camera, with a projective read,
//! `super::perspective::render_perspective_pass`). `super::point_passes` renders each such light
//! in a pass of its own.
//!
//! Built so far: hard lights (`radius = 0`) before every mesh along the view, on the CPU.

use glam::DVec3;

use convshadow_common::model::scene::{
    CameraSpec, GuardBandSpec, MAX_IMAGE_SIDE, Projection, Scene, SceneError, SlabSpec,
};
use convshadow_common::plan::ProjectiveGrid;
use convshadow_common::prepare::camera::Camera;
use convshadow_common::prepare::geometry::SceneGeometry;

use super::RenderError;

/// A point light's grid ([`point_grid`]) and where it lies in the eye's own slab-grid frame.
pub(super) struct PointGrid {
    /// The grid's scene: a perspective camera at the light's centre looking along the view axis,
    /// no guard band, the eye's slab count.
    pub(super) scene: Scene,
    /// The eye's slab-grid frame (`grid_scene`'s camera: cells of the eye's pixel over the light
    /// resolution, centred on the view axis), where the eye pass finds the direction to the light.
    pub(super) frame: Camera,
    /// The light's centre's view depth (the eye's view depths).
    pub(super) depth: f64,
}

/// The grid `scene`'s light `l` (a point or spot light, of a pass that has only it) is swept on,
/// for the eye `eye` whose slab-grid frame is `frame`: a perspective view from the light's centre along the view axis, holding
/// every vertex, its cell at every vertex no coarser than the eye's there (so a shadow edge
/// lands within half an eye cell of where it projects). Refused (naming the key) for a light that is not before every mesh along the
/// view or has a radius, and when the grid would be too large.
pub(super) fn point_grid(
    scene: &Scene,
    eye: &SceneGeometry,
    frame: Camera,
    l: usize,
) -> Result<PointGrid, RenderError> {
    let light = scene.lights[l]
        .point
        .as_ref()
        .expect("a point pass's light is a point light");
    let refuse = |key: &str, message: String| {
        RenderError::Scene(SceneError {
            file: scene.source.clone(),
            key: format!("light[{l}].{key}"),
            message,
        })
    };
    if light.radius > 0.0 {
        return Err(refuse(
            "radius",
            format!(
                "the convolution sweep renders hard point and spot lights only so far (radius \
                 0; this one is {}): `--backend reference` renders a point light's penumbra",
                light.radius
            ),
        ));
    }
    let cam = &eye.camera;
    let at = cam.to_camera(DVec3::from(light.position));
    // Every vertex before the light's centre along the view: the tangents of its rays' angles.
    // And the grid's focal length (its pixels) that makes its cell at every vertex no coarser
    // than the eye's cell there: the eye frame's cell, times view depth over the `look_at`
    // distance in perspective.
    let lr = scene.sweep.light_resolution;
    let (mut near, mut tan_x, mut tan_y) = (f64::INFINITY, 0.0f64, 0.0f64);
    let mut focal = 0.0f64;
    for m in &eye.meshes {
        for v in &m.mesh.positions {
            let view = cam.to_camera(*v);
            let c = view - at;
            near = near.min(c.z);
            if c.z > 0.0 {
                tan_x = tan_x.max(c.x.abs() / c.z);
                tan_y = tan_y.max(c.y.abs() / c.z);
                let eye_cell = cam.pixel_size_at(view.z) / lr;
                if eye_cell > 0.0 {
                    focal = focal.max(c.z / eye_cell);
                }
            }
        }
    }
    if near.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(refuse(
            "position",
            format!(
                "the convolution sweep renders a point or spot light only before every mesh \
                 along the view so far: this light is at view depth {:.6}, the nearest vertex \
                 at {:.6} (move the light towards the camera, or render with `--backend \
                 reference`)",
                at.z,
                at.z + near
            ),
        ));
    }
    let cell = frame.pixel_size;
    // Two cells beyond the outermost vertex: every ray that meets a mesh is in the grid.
    let side = |tan: f64| 2.0 * (tan * focal + 2.0).ceil();
    let (gw, gh) = (side(tan_x), side(tan_y));
    if gw > f64::from(MAX_IMAGE_SIDE) || gh > f64::from(MAX_IMAGE_SIDE) {
        return Err(RenderError::OutOfMemory(format!(
            "{}: light[{l}]'s grid (the scene as the light sees it, at the eye's cell size) \
             would be {gw} × {gh} pixels, more than {MAX_IMAGE_SIDE} a side; lower \
             sweep.light_resolution or move the light away from the meshes",
            scene.source
        )));
    }
    let look_at = DVec3::from(light.position) + cam.forward * (focal * cell);
    let mut grid = scene.clone();
    grid.camera = CameraSpec {
        center: light.position,
        view_width: gw * cell,
        projection: Projection::Perspective {
            look_at: look_at.to_array(),
            fov_deg: 2.0 * (0.5 * gh / focal).atan().to_degrees(),
            near: None,
        },
        ..scene.camera.clone()
    };
    grid.image.width = gw as u32;
    grid.image.height = gh as u32;
    grid.sweep.guard_band = GuardBandSpec::Pixels(0);
    grid.sweep.slabs = SlabSpec::Count(eye.slabs);
    Ok(PointGrid {
        scene: grid,
        frame,
        depth: at.z,
    })
}

/// The cells of a point light's grid `geometry` as its slab-grid coordinates
/// ([`convshadow_common::plan::RenderPlan::projective`]).
pub(super) fn projective(geometry: &SceneGeometry) -> ProjectiveGrid {
    let cam = &geometry.camera;
    let focal = cam
        .focal_px
        .expect("a point light's grid is a perspective view");
    ProjectiveGrid {
        centre: [cam.width as f32 * 0.5, cam.height as f32 * 0.5],
        depth_origin: geometry.z_origin as f32,
        per_depth: (1.0 / (focal * cam.pixel_size)) as f32,
    }
}
