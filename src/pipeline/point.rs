//! A point or spot light's grid on the CPU sweep (docs/how-it-works.md, "The sweep's point
//! lights"): a perspective view from the light's centre along the view axis, whose rays are the
//! light's, so its light propagates straight down the grid's columns; the eye's rays read it slab
//! by slab (the eye pass of a perspective camera, with a projective read,
//! `super::perspective::render_perspective_pass`). `super::point_passes` renders each such light
//! in a pass of its own.
//!
//! A light before every mesh along the view is one pass, one behind every mesh a turned-round
//! pass (the grid looks back along the view from the light, the eye composites back to front),
//! and one amid the meshes both, each over the meshes on its side ([`placement`]); a soft one
//! (`radius` > 0) with the distance penumbra in φ.

use glam::DVec3;

use convshadow_common::contract::ldi::Ldi;
use convshadow_common::model::scene::{
    CameraSpec, GuardBandSpec, MAX_IMAGE_SIDE, Penumbra, Projection, Scene, SceneError, SlabSpec,
};
use convshadow_common::plan::depth_scale::DepthScale;
use convshadow_common::plan::{ProjectiveGrid, RenderPlan};
use convshadow_common::prepare::camera::Camera;
use convshadow_common::prepare::geometry::SceneGeometry;
use convshadow_common::prepare::guard::AUTO_GUARD_SIGMAS;
use convshadow_common::prepare::raster::{FIXED_ONE, TriangleSetup};

use super::RenderError;

/// The margin (cells) a soft light's grid may take past what the eye sees on each side, whatever
/// the eye's extent: enough for a short image's penumbrae (a 128 × 8 wall needs 14 at light
/// resolution 1), where the unoccluded light read beyond the grid brightened the shadows.
const MIN_MARGIN: f64 = 16.0;
/// Beyond [`MIN_MARGIN`], the largest margin as a share of what the eye sees from the axis: a
/// wide view's penumbrae near its edges are a small part of it, and a grazing light's reach is
/// thousands of cells (the margin's cost: 1.0 → 2.3 s at 135°, 17 → 30 s at 80°, 128 × 8 px).
const MAX_MARGIN_SHARE: f64 = 0.25;

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
    /// The grid's first slab plane's distance from the light along its axis.
    pub(super) origin: f64,
    /// The depth in `frame` of the grid's relative depth 0: the eye's origin, or turned round
    /// (`frame` the turned camera's, depths the view's negated) the first plane's.
    pub(super) frame_z_origin: f64,
}

/// The grid `scene`'s light `l` (a point or spot light, of a pass that has only it) is swept on,
/// for the eye `eye` whose slab-grid frame is `frame` and whose rays meet the meshes between the
/// points `visible` ([`visible_points`]): a perspective view from the light's centre along the
/// view axis, holding every vertex the eye's rays pass, its cell at every vertex no coarser than
/// the eye's there (so a shadow edge lands within half an eye cell of where it projects), a
/// soft light's spread in its variance. Refused (naming the key) for a light that is not before
/// every mesh along the view, a soft one with the iterated penumbra, and a grid too large.
pub(super) fn point_grid(
    scene: &Scene,
    eye: &SceneGeometry,
    frame: Camera,
    visible: &[DVec3],
    l: usize,
) -> Result<PointGrid, RenderError> {
    let light = scene.lights[l]
        .point
        .as_ref()
        .expect("a point pass's light is a point light");
    let refuse = |key: &str, message: String| refused(scene, format!("light[{l}].{key}"), message);
    if light.radius > 0.0 && scene.sweep.penumbra == Penumbra::Iterated {
        return Err(refused(
            scene,
            "sweep.penumbra".to_string(),
            format!(
                "light[{l}] is a point light with a radius: the convolution sweep gives its \
                 penumbra with the distance penumbra only (\"distance\", the default), whose \
                 depths it measures from the light; `--backend reference` renders it either way"
            ),
        ));
    }
    let cam = &eye.camera;
    let at = cam.to_camera(DVec3::from(light.position));
    // A turned-round pass (a light behind every mesh) looks back along the view: its grid's x
    // and depth axes are the camera's reversed.
    let turned = scene.turned_round;
    let sign = if turned { -1.0 } else { 1.0 };
    let to_light_frame = |c: DVec3| DVec3::new(sign * c.x, c.y, sign * c.z);
    // Every vertex before the light's centre along its grid's axis (the view, or turned round
    // the view reversed): the tangents of its rays' angles.
    // And the grid's focal length (its pixels) that makes its cell at every vertex no coarser
    // than the eye's cell there: the eye frame's cell, times view depth over the `look_at`
    // distance in perspective.
    let lr = scene.sweep.light_resolution;
    let (mut near, mut tan_x, mut tan_y) = (f64::INFINITY, 0.0f64, 0.0f64);
    let mut focal = 0.0f64;
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for m in &eye.meshes {
        for v in &m.mesh.positions {
            let view = cam.to_camera(*v);
            let c = to_light_frame(view - at);
            (lo, hi) = (lo.min(c), hi.max(c));
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
                "this pass's point or spot light is at view depth {:.6}, amid its meshes' \
                 vertices: a pass lights only meshes wholly behind the light's centre (its \
                 turned-round pass, wholly in front); please report this",
                at.z,
            ),
        ));
    }
    // Only what the eye samples needs the light, and whatever shadows a sample lies on its ray
    // from the light, in the same grid column: the grid need not reach beyond the eye's rays'
    // stretches through the meshes (`visible`) as the light sees them.
    let mut seen = [0.0f64; 2];
    for v in visible {
        let c = to_light_frame(*v - at);
        if c.z > 0.0 {
            seen[0] = seen[0].max(c.x.abs() / c.z);
            seen[1] = seen[1].max(c.y.abs() / c.z);
        }
    }
    // The light's depth extent blurs its penumbra along the ray's slope m = (x, y)/z too, by
    // r·|m| per unit φ·focal: a covariance `spread²·(I + m·mᵀ)` that changes across the grid.
    // The grid's light takes it at one slope (a spot's axis, else the middle of what the light
    // sees): exact there, off by √((1 + m²)/(1 + m̄²)) in the width elsewhere
    // (docs/how-it-works.md).
    let middle = 0.5 * (lo + hi);
    let axis = light
        .spot
        .map(|s| to_light_frame(cam.to_camera(cam.center + DVec3::from(s.direction))))
        .filter(|d| d.z > 0.1 * d.length())
        .unwrap_or(middle);
    let slope = [axis.x / axis.z, axis.y / axis.z];
    let along = 1.0 + slope[0] * slope[0] + slope[1] * slope[1];
    // A read beyond the grid is unoccluded light, so a soft light's grid reaches past what the
    // eye sees by its penumbra's reach where the meshes do: an occluder at φ₀ blurs a receiver at
    // φ₁ by `focal·radius·(φ₁ − φ₀)` cells (std), at most from the nearest vertex to the
    // farthest (wider along the slope above); [`AUTO_GUARD_SIGMAS`] of it and the bilinear
    // read's cell, as the eye's automatic guard band, capped for its cost ([`MIN_MARGIN`]).
    let penumbra = light.radius * focal * (1.0 / near - 1.0 / hi.z.max(near)).max(0.0);
    // Along an axis of slope m the covariance `penumbra²·(I + m·mᵀ)` has variance
    // `penumbra²·(1 + m²)`; a hard light's gather reads no neighbour and needs no margin.
    let margin = |m: f64, seen: f64| {
        if light.radius == 0.0 {
            return 0.0;
        }
        let reach = (AUTO_GUARD_SIGMAS * penumbra * (1.0 + m * m).sqrt() + 1.0) / focal;
        reach.min((MAX_MARGIN_SHARE * seen).max(MIN_MARGIN / focal))
    };
    let (tan_x, tan_y) = (
        tan_x.min(seen[0] + margin(slope[0], seen[0])),
        tan_y.min(seen[1] + margin(slope[1], seen[1])),
    );
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
    let look_at = DVec3::from(light.position) + cam.forward * (sign * focal * cell);
    let mut grid = scene.clone();
    // A soft light spreads by `focal·radius` grid pixels per unit of φ = −1/(depth from the
    // light): its first slab's spread, the covariance step every level scales
    // (`DepthScale`), is a directional light's of this variance at this pixel size.
    let e = eye.slab_distance;
    // The grid's first slab plane, its distance from the light: the eye's first plane; turned
    // round, the eye's last (the slabs mirrored), moved towards the eye where that is not
    // beyond the light, to half way between the light and the farthest vertex (the slabs then
    // still reach the eye's first plane, and no vertex lies beyond the first).
    let origin = if turned {
        let far = eye.z_origin + f64::from(eye.slabs) * e;
        (at.z - far).max(0.5 * near)
    } else {
        eye.z_origin - at.z
    };
    let first = 1.0 / origin - 1.0 / (origin + e);
    let spread = light.radius * first * focal * cell / e;
    grid.lights[l].variance = [spread * spread * along, spread * spread];
    grid.lights[l].rotation_deg = slope[1].atan2(slope[0]).to_degrees();
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
        origin,
        frame_z_origin: if turned { origin - at.z } else { eye.z_origin },
    })
}

/// `plan`, built for the point light's grid `grid` and its `geometry`, as that grid needs it:
/// the material read at each cell's own point (`projective`), no sub-pixel shadows (the light's
/// rays are the grid's columns: nothing to shift), and for a soft light the distance penumbra in
/// ψ (`depth_scale`) with holds from the grid's true depth gradients; a hard light holds no
/// surface (its gather reads no neighbour, so no surface shadows itself; a hold would let light
/// past it).
pub(super) fn on_point_grid(plan: &mut RenderPlan, grid: &Scene, geometry: &SceneGeometry) {
    plan.projective = Some(projective(geometry));
    plan.subpixel_meshes = Vec::new();
    let soft = grid.lights[0].point.is_some_and(|p| p.radius > 0.0);
    if soft {
        plan.depth_scale = Some(DepthScale::new(
            geometry.z_origin,
            geometry.slab_distance,
            geometry.slabs,
        ));
        plan.set_surface_holds(grid, geometry, perspective_gradient);
    } else {
        plan.surface_hold = Vec::new();
        plan.hold_slopes = Vec::new();
    }
}

/// The cells of a point light's grid `geometry` as its slab-grid coordinates
/// ([`convshadow_common::plan::RenderPlan::projective`]).
fn projective(geometry: &SceneGeometry) -> ProjectiveGrid {
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

/// A triangle's depth gradient on a point light's perspective grid (world units of view depth
/// per grid pixel, x and y) for the surface hold: the raster's plane is the inverse depth w, so
/// `dz = −z²·dw`, taken at the triangle's vertex farthest from the light (the largest).
fn perspective_gradient(t: &TriangleSetup) -> (f32, f32) {
    let one = FIXED_ONE as f64;
    let corner = [f64::from(t.bbox[0]) + 0.5, f64::from(t.bbox[1]) + 0.5];
    let w_at = |v: [i32; 2]| {
        f64::from(t.depth_ref)
            + f64::from(t.depth_dx) * (f64::from(v[0]) / one - corner[0])
            + f64::from(t.depth_dy) * (f64::from(v[1]) / one - corner[1])
    };
    let w = t.v.iter().map(|&v| w_at(v)).fold(f64::INFINITY, f64::min);
    let z2 = if w > 0.0 { 1.0 / (w * w) } else { 0.0 };
    (
        (-z2 * f64::from(t.depth_dx)) as f32,
        (-z2 * f64::from(t.depth_dy)) as f32,
    )
}

/// Where a point or spot light's centre lies among the meshes along the view
/// ([`placement`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Placement {
    /// Before every mesh (every vertex farther from the camera than the centre): one pass.
    Before,
    /// Behind every mesh (every vertex nearer): one turned-round pass ([`point_grid`]).
    Behind,
    /// Amid them: the meshes `front` (scene indices) wholly nearer the camera than the centre,
    /// `back` wholly farther. No ray from the centre to a point of one set crosses the other
    /// (it stays between the two depths), so each set is lit on its own — `front` by a
    /// turned-round pass, `back` by an ordinary one — and the eye sees `back` through `front`.
    Amid {
        /// Meshes nearer the camera than the light's centre.
        front: Vec<usize>,
        /// Meshes farther than it.
        back: Vec<usize>,
    },
}

/// A refusal of `scene` naming `key` (exit code 3).
fn refused(scene: &Scene, key: String, message: String) -> RenderError {
    RenderError::Scene(SceneError {
        file: scene.source.clone(),
        key,
        message,
    })
}

/// Where point light `l` of `scene` lies among the meshes of `eye` (its geometry, meshes in
/// scene order) along the view: [`Placement`]. A mesh whose vertices lie on both sides of the
/// light's view depth (or on it) cannot be split and is refused, naming the light and the mesh.
pub(super) fn placement(
    scene: &Scene,
    eye: &SceneGeometry,
    l: usize,
) -> Result<Placement, RenderError> {
    let point = scene.lights[l]
        .point
        .as_ref()
        .expect("a point pass's light is a point light");
    let cam = &eye.camera;
    let at = cam.to_camera(DVec3::from(point.position)).z;
    let (mut front, mut back) = (Vec::new(), Vec::new());
    for (i, m) in eye.meshes.iter().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in &m.mesh.positions {
            let z = cam.to_camera(*v).z;
            (lo, hi) = (lo.min(z), hi.max(z));
        }
        if hi < at {
            front.push(i);
        } else if lo > at {
            back.push(i);
        } else if lo <= hi {
            return Err(refused(
                scene,
                format!("light[{l}].position"),
                format!(
                    "the light's centre lies at view depth {at:.6}, within mesh[{i}]'s depth \
                     range [{lo:.6}, {hi:.6}]: the convolution sweep lights the meshes in front \
                     of a point or spot light and those behind it in two passes, so every mesh \
                     must lie wholly on one side (move the light, or render with `--backend \
                     reference`)"
                ),
            ));
        }
    }
    Ok(match (front.is_empty(), back.is_empty()) {
        (_, true) => Placement::Behind,
        (true, false) => Placement::Before,
        (false, false) => Placement::Amid { front, back },
    })
}

/// Where the eye's rays are among the meshes: each image pixel's ray at its first and last
/// fragment of `ldi` (the eye's LDI), camera coordinates. Every sample the eye takes lies
/// between the two on its ray.
pub(super) fn visible_points(eye: &SceneGeometry, ldi: &Ldi) -> Vec<DVec3> {
    let cam = &eye.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut points = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let p = y * w + x;
            let (first, end) = (ldi.offsets[p] as usize, ldi.offsets[p + 1] as usize);
            if first == end {
                continue;
            }
            for d in [ldi.depth[first], ldi.depth[end - 1]] {
                let depth = eye.z_origin + f64::from(d);
                let s = cam.pixel_size_at(depth);
                points.push(DVec3::new(
                    (x as f64 + 0.5 - 0.5 * w as f64) * s,
                    (y as f64 + 0.5 - 0.5 * h as f64) * s,
                    depth,
                ));
            }
        }
    }
    points
}
