//! The render plan: every table the sweep reads, computed once on the host and
//! shared by the scalar path, the SIMD path and the GPU port.
//!
//! Nothing per pixel calls a transcendental: kernel taps, slab hashes, the slab-thickness opacity
//! correction `α_slab = 1 − (1 − α)^(e/e_ref)`, attenuation factors and specular half vectors are
//! all here.

pub mod depth_scale;
pub mod horizon;
pub mod kernel;
pub mod levels;
pub mod material;
pub mod pattern;
pub mod point_light;
pub mod surface_hold;

use glam::{DAffine3, DVec3};
use rayon::prelude::*;

use crate::contract::files::PlanFiles;
use crate::model::scene::{Media, PatternSpec, Penumbra, Scene};
use crate::pixel::hash::{JITTER_STREAM, slab_hash};
use crate::pixel::texture3d::TextureError;
use crate::plan::kernel::{
    KernelMoments, KernelTable, TableGuard, build_distance_table, build_table,
};
use crate::plan::pattern::Pattern;
use crate::prepare::geometry::SceneGeometry;
use crate::prepare::guard::GuardBand;
use std::sync::Arc;

pub use material::{
    DEFAULT_REFERENCE_LENGTH, MaterialPlan, PI_MIN_STEPS, PI_SIZE, PI_STEPS_PER_UNIT, Passes,
    SpecularPlan, TF_SIZE, TfEntry, preintegrated_entry,
};
use material::{flush_tiny, material_plan};

/// Light values below this are flushed to zero after attenuation (no subnormals, same zeros on
/// CPU and GPU); products with tap weights (≥ 2^-24) then stay far above f32's normal range.
pub const FLUSH_BELOW: f32 = 1.0e-20;

/// Distance penumbra: a pixel whose occluded light (channels − Σ light) is at most this has no
/// mean occluder depth to speak of (D / u would be rounding noise) and gathers through the
/// smallest kernel. 2^-16: the quotient's error from u's rounding stays below 0.1 %.
pub const OCCLUSION_EPS: f32 = 1.0 / 65536.0;

/// Distance penumbra: the level plane's value at a pixel with no occluder (every level is
/// smaller, so a minimum over a footprint ignores it).
pub const LIT_LEVEL: u32 = u32::MAX;

/// The Ashikmin–Shirley constants of a light whose half vector `h` and direction towards the
/// light `to_light` are given (camera space, unit length): with k = l (h·l = h·v), Schlick's
/// F(h·k)/(h·k) = p/(h·k) + f0·(1 − p)/(h·k), p = (1 − h·k)^5; returns [p/(h·k), (1 − p)/(h·k)]
/// (f64 on the host; the shading stage forms `scale · (b + f0·c)` in f32).
pub fn fresnel_terms(h: DVec3, to_light: DVec3) -> [f32; 2] {
    let hk = h.dot(to_light);
    let p = (1.0 - hk).powi(5);
    [(p / hk) as f32, ((1.0 - p) / hk) as f32]
}

/// A light's per-render tables.
#[derive(Clone, Debug)]
pub struct LightPlan {
    /// Linear RGB colour.
    pub color: [f32; 3],
    /// Kernel moments per slab (pixels); for the distance penumbra, those of its smallest level
    /// (an occluder one slab in front).
    pub moments: KernelMoments,
    /// The tap table.
    pub table: KernelTable,
    /// Per slab: hash of (seed, light, slab), the prefix of every per-pixel phase hash.
    pub slab_hash: Vec<u32>,
    /// Blinn–Phong half vector in camera space (towards light + towards viewer, normalised);
    /// negated in a turned-round pass ([`RenderPlan::turned_round`]).
    pub half_vector: [f32; 3],
    /// Unit direction towards the light in camera space, (tan ωx, tan ωy, −1)/‖·‖: the `l` of
    /// the Lambert cosine and of Ashikmin–Shirley (the mean direction of an area light);
    /// negated in a turned-round pass, where the normal the shading faces towards −z is the
    /// viewer's negated.
    pub to_light: [f32; 3],
    /// Ashikmin–Shirley's Fresnel-over-(h·k) constants ([`fresnel_terms`]).
    pub fresnel: [f32; 2],
    /// The light's drift per slab (pixels): `moments.mean` in f32, the exact shift the sweep's
    /// gathers move its light by, on average, from one slab to the next.
    pub drift: [f32; 2],
    /// The light's spread as the horizon reads it ([`horizon::directional_spread`]): the
    /// variance of f·`to_light` over its samples is `a·fx² + b·fx·fy + c·fy² + iso`.
    pub spread: [f32; 4],
    /// The light buffer starts at 1 (no pattern), so its value is the visible part of the light
    /// and the horizon takes the smaller of the two; a pattern's light is multiplied by it.
    pub plain: bool,
    /// Per slab k: how far the sweep has moved the light after slab k's gather beyond its exact
    /// drift, `round((k + 1)·drift) − (k + 1)·drift` per axis where the mean is carried in whole
    /// pixels ([`KernelTable::slab_shift`]), else 0 (pixels). Empty unless
    /// [`RenderPlan::subpixel_meshes`] is.
    pub carry_residual: Vec<[f32; 2]>,
}

/// cos θ of the scattering angle of a distant light with tilt `tilt_deg` towards an orthographic
/// camera: θ is the angle between the light's propagation direction, ∝ (−tan ωx, −tan ωy, 1) in
/// camera space, and the direction to the camera, (0, 0, −1); so cos θ = −1/√(1 + tan²ωx +
/// tan²ωy) (−1 for a light straight behind the viewer: back-scattering). In a turned-round pass
/// (`turned_round`: the viewer at the sweep's far end, along +z) the sign is +: a light in front
/// of the viewer scatters forward towards it.
pub fn scattering_cos(tilt_deg: [f64; 2], turned_round: bool) -> f64 {
    let [mx, my] = tilt_deg.map(|t| t.to_radians().tan());
    let c = 1.0 / (1.0 + mx * mx + my * my).sqrt();
    if turned_round { c } else { -c }
}

/// The Henyey–Greenstein phase function normalised to 1 for an isotropic medium:
/// `(1 − g²) / (1 + g² − 2g·cos θ)^{3/2}` (its 1/4π dropped, so g = 0 gives exactly 1).
pub fn henyey_greenstein(g: f64, cos_theta: f64) -> f64 {
    if g == 0.0 {
        return 1.0;
    }
    (1.0 - g * g) / (1.0 + g * g - 2.0 * g * cos_theta).powf(1.5)
}

/// The phase factor of a medium of asymmetry `g` lit by a light of tilt `tilt_deg`
/// ([`scattering_cos`]).
pub fn phase_factor(g: f64, tilt_deg: [f64; 2], turned_round: bool) -> f64 {
    henyey_greenstein(g, scattering_cos(tilt_deg, turned_round))
}

/// Errors while planning: a material's 3D texture or a light's pattern that cannot be read.
#[derive(Debug, thiserror::Error)]
#[error("{scene}: {what}: {source}")]
pub struct PlanError {
    /// Scene file.
    pub scene: String,
    /// What failed: "material `NAME`" (a 3D texture) or "key `light[i].pattern.path`".
    pub what: String,
    /// The loader's error (names the file).
    pub source: TextureError,
}

/// Everything the sweep needs besides the LDI.
#[derive(Clone, Debug)]
pub struct RenderPlan {
    /// Grid width (image + left and right guard band).
    pub grid_width: u32,
    /// Grid height (image + top and bottom guard band).
    pub grid_height: u32,
    /// Guard band per side, as resolved by the geometry (`geometry.raster.guard`): image pixel
    /// (x, y) is grid pixel (x + left, y + top).
    pub guard: GuardBand,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Slab count.
    pub slabs: u32,
    /// How `slabs = "auto"` chose the count (`None` when the scene gave it).
    pub auto_slabs: Option<crate::prepare::auto_slabs::AutoSlabs>,
    /// Pixel size (world units).
    pub pixel_size: f64,
    /// Slab thickness (world units) as f32.
    pub slab_distance: f32,
    /// `1 / slab_distance` in f32 (the part of a slab a medium fills, one division for all).
    pub inv_slab_distance: f32,
    /// `sweep.media = "second-order"`: a medium's entry and exit slabs count the part inside it
    /// and its shading points are lit by the light at the point (`cpu::parity::slab_part`).
    pub second_order_media: bool,
    /// Front face of each slab (depth relative to the first slab's front).
    pub slab_front: Vec<f32>,
    /// Back face of each slab.
    pub slab_back: Vec<f32>,
    /// Light-buffer channels: 1 when every transport colour is grey, else 3.
    pub channels: u32,
    /// How the kernels grow with depth. With [`Penumbra::Distance`] each light's buffer has one
    /// more plane after its channels: the occlusion-weighted occluder depth D (in slabs), so that
    /// the mean occluder depth is D / (channels − Σ light).
    pub penumbra: Penumbra,
    /// The pass of the lights from in front of the viewer (`Scene::turned_round`): the sweep
    /// runs towards the viewer, so it composites back to front (`C = α·c + (1 − α)·C`) and
    /// never stops early; the lights' shading vectors are negated ([`LightPlan::to_light`]).
    pub turned_round: bool,
    /// Lights.
    pub lights: Vec<LightPlan>,
    /// Materials.
    pub materials: Vec<MaterialPlan>,
    /// Material of each mesh.
    pub mesh_material: Vec<u32>,
    /// Per mesh: (image pixel x, image pixel y, relative depth) → detail coordinates, row-major
    /// 3×4. Image, not grid, pixels (negative inside the left and top guard band): a pixel's
    /// detail value then has the same bits whatever the band (see [`RenderPlan::image_xy`]).
    pub mesh_to_detail: Vec<[f32; 12]>,
    /// Jitter the shading point inside the slab.
    pub jitter: bool,
    /// Per slab: hash of (seed, jitter stream, slab).
    pub jitter_slab_hash: Vec<u32>,
    /// Background colour.
    pub background: [f32; 3],
    /// The light buffer before the first slab (`[row][light][channel][x]`, the sweep's input),
    /// when a light has a pattern; `None`: every light starts at 1.
    pub initial_light: Option<Vec<f32>>,
    /// Per light, a spot light's pattern (a gobo projected through its cone, read where the
    /// light arrives, not a light buffer: the reference's tracer and the sweep's eye pass);
    /// empty when no spot light has one.
    pub spot_patterns: Vec<Option<Arc<Pattern>>>,
    /// Pre-integrated compositing (`sweep.preintegration`): materials with a
    /// [`MaterialPlan::pre`] table are shaded from their detail at the slab's faces, and the
    /// sweep keeps one more float per pixel (the next slab's front value).
    pub preintegration: bool,
    /// Per rasterized triangle (`RasterSetup::triangles`' order), packed
    /// ([`surface_hold::pack_holds`]): how many slabs an opaque crossing of it keeps passing its
    /// pixel's light before removing it ([`surface_hold::surface_hold`]; 0: removed at the
    /// crossing), how many slabs before a pixel leaves a light-blocking mesh through it the
    /// pixel passes its light ([`surface_hold::exit_hold`]), and how many more slabs than one
    /// the pixel keeps removing its light once it removes it ([`surface_hold::barrier`]).
    pub surface_hold: Vec<u32>,
    /// Per rasterized triangle where [`RenderPlan::surface_hold`] is not empty, its depth
    /// gradient in slabs per grid pixel (x, y): a held pixel's surface plane, against which a
    /// neighbour's gather decides whether it reads the held light
    /// ([`surface_hold::HELD_BEHIND_MARGIN`]).
    pub hold_slopes: Vec<[f32; 2]>,
    /// `sweep.held_lit_side`: a gather reads no light from a held pixel behind whose surface it
    /// lies (`surface_hold`, "Who reads the held light"); the sweep then keeps every pixel's
    /// held-plane record.
    pub held_lit_side: bool,
    /// `sweep.served_releases`: a released pixel serves the light it gathered in its release
    /// slab to gathers on its surface (`surface_hold`, "Released light served on its own
    /// surface"); the sweep then keeps it with the held-plane records.
    pub served_releases: bool,
    /// `sweep.horizon`: Φ at [`horizon::HORIZON_STEPS`] + 1 knots ([`horizon::horizon_table`]),
    /// read at every opaque crossing; empty when off.
    pub horizon: Vec<f32>,
    /// `sweep.subpixel_shadows`: per mesh, whether a crossing of its
    /// surface (its material blocks light: [`MaterialPlan::blocks_light`]) is shaded with the
    /// light read at its exact sub-pixel shift from its mean occluder (`cpu::kernels::
    /// exact_shift`), and records the crossing's depth within its slab in the depth plane.
    /// Empty when none is.
    pub subpixel_meshes: Vec<bool>,
    /// A point light's grid (the sweep's point lights, docs/how-it-works.md "Point and spot
    /// lights"): a perspective view from the light's centre, whose cell (x, y) at relative depth
    /// z is the slab-grid point `centre + (x − centre)·(depth_origin + z)·per_depth` that
    /// `mesh_to_detail` maps; `None` for a slab grid (an orthographic view: no change).
    pub projective: Option<ProjectiveGrid>,
    /// A soft point light's grid: the distance penumbra's depth plane and level search in ψ,
    /// the light's φ-distance ([`depth_scale::DepthScale`]); `None`: in slabs.
    pub depth_scale: Option<depth_scale::DepthScale>,
}

/// The cells of a perspective grid as slab-grid coordinates ([`RenderPlan::projective`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectiveGrid {
    /// Where the grid's axis meets its image, image pixels.
    pub centre: [f32; 2],
    /// The view depth (from the grid's eye) of relative depth 0.
    pub depth_origin: f32,
    /// `1 / (focal_px · pixel_size)`: a cell's offset from the centre in slab-grid pixels per
    /// unit of view depth.
    pub per_depth: f32,
}

impl RenderPlan {
    /// Builds all tables for a scene whose geometry is already set up, from its files as the
    /// host read them (`convshadow_io::read_plan_files`).
    pub fn new(
        scene: &Scene,
        geometry: &SceneGeometry,
        files: &PlanFiles,
    ) -> Result<RenderPlan, PlanError> {
        let plan = RenderPlan::new_guarded(scene, geometry, files, &TableGuard::unlimited())?;
        Ok(plan.expect("an unlimited guard never stops the tables"))
    }

    /// [`RenderPlan::new`], with the kernel tables built under `guard`: `Ok(None)` when it
    /// stopped them (cancelled, or past its byte limit; the guard says which).
    pub fn new_guarded(
        scene: &Scene,
        geometry: &SceneGeometry,
        files: &PlanFiles,
        guard: &TableGuard<'_>,
    ) -> Result<Option<RenderPlan>, PlanError> {
        let slabs = geometry.slabs;
        let e = geometry.slab_distance;
        let px = geometry.camera.pixel_size;
        let seed = scene.sweep.seed;
        // Lights are independent (their tables' bits do not depend on the thread count): built
        // in parallel, each with its levels in parallel (`build_distance_table`).
        let lights = scene
            .lights
            .par_iter()
            .enumerate()
            .map(|(l, spec)| {
                let moments_for = |d1: f64| {
                    KernelMoments::for_light(
                        spec.tilt_deg,
                        spec.variance,
                        spec.rotation_deg,
                        e,
                        d1,
                        px,
                    )
                };
                let compensate = scene.sweep.variance_compensation;
                let kernel = scene.sweep.kernel;
                let (moments, table) = match scene.sweep.penumbra {
                    Penumbra::Iterated => {
                        // Scene validation requires d1 with the iterated penumbra.
                        let moments = moments_for(scene.sweep.optimal_distance.unwrap_or(e));
                        if guard.stopped() {
                            return None;
                        }
                        let table = build_table(kernel, &moments, slabs, compensate);
                        let words = table.slab_phase.len() + 2 * table.slab_shift.len();
                        guard.charge(table.taps.len(), words);
                        (moments, table)
                    }
                    Penumbra::Distance => {
                        // A covariance step of f·e²·Σl is d1 = f·e in the iterated formula.
                        let per_e2 = |f: f64| moments_for(f * e);
                        let table =
                            build_distance_table(kernel, &per_e2, slabs, compensate, guard)?;
                        (per_e2(1.0), table)
                    }
                };
                let mu = spec.tilt_deg.map(|t| t.to_radians().tan());
                let to_light = DVec3::new(mu[0], mu[1], -1.0).normalize();
                // The viewer looks along +z, or in a turned-round pass along −z from the sweep's
                // far end: there the normal the shading turns towards −z (`facing`) is the
                // viewer's negated, so the vectors it is dotted with are negated too.
                let (to_viewer, facing) = if scene.turned_round {
                    (DVec3::Z, -1.0)
                } else {
                    (DVec3::NEG_Z, 1.0)
                };
                let h = (to_light + to_viewer).normalize();
                let (shade_h, shade_l) = (h * facing, to_light * facing);
                Some(LightPlan {
                    color: spec.color.map(flush_tiny),
                    moments,
                    table,
                    slab_hash: (0..slabs).map(|k| slab_hash(seed, l as u32, k)).collect(),
                    half_vector: [shade_h.x as f32, shade_h.y as f32, shade_h.z as f32],
                    to_light: [shade_l.x as f32, shade_l.y as f32, shade_l.z as f32],
                    fresnel: fresnel_terms(h, to_light),
                    drift: moments.mean.map(|m| m as f32),
                    spread: horizon::directional_spread(
                        spec.tilt_deg,
                        spec.variance,
                        spec.rotation_deg,
                    ),
                    plain: spec.pattern.is_none(),
                    carry_residual: Vec::new(),
                })
            })
            .collect::<Option<Vec<LightPlan>>>();
        let Some(lights) = lights.filter(|_| !guard.stopped()) else {
            return Ok(None);
        };
        let medium_passes = match scene.sweep.media {
            Media::SecondOrder => Passes::Medium,
            Media::FirstOrder => Passes::Filter,
        };
        let materials = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let texture = files.textures.get(i).cloned().flatten();
                material_plan(m, e, medium_passes, scene.sweep.preintegration, texture).map_err(
                    |source| PlanError {
                        scene: scene.source.clone(),
                        what: format!("material `{}`", m.name),
                        source,
                    },
                )
            })
            .collect::<Result<Vec<_>, PlanError>>()?;
        let mut materials = materials;
        for (plan, spec) in materials.iter_mut().zip(&scene.materials) {
            plan.light_color = scene
                .lights
                .iter()
                .map(|l| {
                    if spec.phase_g == 0.0 {
                        // Bit for bit the colour the shading used before phase functions.
                        l.color.map(flush_tiny)
                    } else {
                        let f = phase_factor(spec.phase_g, l.tilt_deg, scene.turned_round);
                        l.color.map(|c| flush_tiny((f64::from(c) * f) as f32))
                    }
                })
                .collect();
        }
        let mesh_material = shell_materials(scene, geometry, files, &mut materials)?;
        let mesh_to_detail = scene
            .meshes
            .iter()
            .zip(&geometry.meshes)
            .map(|(spec, wm)| {
                // Slab-grid coordinates (an orthographic camera's pixels) → world → object
                // (→ texture).
                let cam = &geometry.camera;
                let origin = cam.grid_to_world(0.0, 0.0, geometry.z_origin);
                let dx = cam.right * cam.pixel_size;
                let dy = cam.down * cam.pixel_size;
                let pixel_to_world = DAffine3::from_cols(dx, dy, cam.forward, origin);
                let mut m = wm.world_to_object * pixel_to_world;
                if scene.materials[spec.material].texture.is_some() {
                    let (mut lo, mut hi) = wm.object_bounds;
                    if let Some(extent) = materials[spec.material].texture_extent {
                        (lo, hi) =
                            crate::prepare::placement::fit_extent(lo, hi, DVec3::from(extent));
                    }
                    let size = (hi - lo).max(DVec3::splat(1e-30));
                    let to_unit = DAffine3::from_scale_rotation_translation(
                        size.recip(),
                        glam::DQuat::IDENTITY,
                        -lo / size,
                    );
                    m = to_unit * m;
                }
                let c = m.matrix3;
                let t = m.translation;
                [
                    c.x_axis.x, c.y_axis.x, c.z_axis.x, t.x, c.x_axis.y, c.y_axis.y, c.z_axis.y,
                    t.y, c.x_axis.z, c.y_axis.z, c.z_axis.z, t.z,
                ]
                .map(|v| v as f32)
            })
            .collect();
        RenderPlan {
            grid_width: geometry.raster.width,
            grid_height: geometry.raster.height,
            guard: geometry.raster.guard,
            width: scene.image.width,
            height: scene.image.height,
            slabs,
            auto_slabs: geometry.auto_slabs.clone(),
            slab_distance: e as f32,
            inv_slab_distance: 1.0 / e as f32,
            second_order_media: scene.sweep.media == Media::SecondOrder,
            slab_front: (0..slabs).map(|k| (f64::from(k) * e) as f32).collect(),
            slab_back: geometry.slab_back_faces(),
            channels: if scene.is_monochrome() { 1 } else { 3 },
            penumbra: scene.sweep.penumbra,
            turned_round: scene.turned_round,
            lights,
            materials,
            mesh_material,
            mesh_to_detail,
            jitter: scene.sweep.jitter,
            jitter_slab_hash: (0..slabs)
                .map(|k| slab_hash(seed, JITTER_STREAM, k))
                .collect(),
            background: scene.image.background,
            pixel_size: px,
            initial_light: None,
            spot_patterns: Vec::new(),
            projective: None,
            depth_scale: None,
            preintegration: scene.sweep.preintegration,
            surface_hold: Vec::new(),
            hold_slopes: Vec::new(),
            held_lit_side: scene.sweep.held_lit_side,
            served_releases: scene.sweep.served_releases,
            horizon: if scene.sweep.horizon {
                horizon::horizon_table()
            } else {
                Vec::new()
            },
            subpixel_meshes: Vec::new(),
        }
        .with_surface_hold(scene, geometry)
        .with_subpixel_shadows(scene)
        .with_patterns(scene, files)
        .map(Some)
    }

    /// Sets [`RenderPlan::subpixel_meshes`] and every light's
    /// [`LightPlan::carry_residual`] (`sweep.subpixel_shadows`). Only where every mesh blocks
    /// light: a medium removes light in every slab it fills, its mean depth falls between slabs
    /// whose whole-pixel carries differ by a pixel, and reading at that mean's drift drew contour
    /// lines across the default scene's wall (measured: its successive-slab-count RMSE doubled).
    /// The correction needs the depth plane's mean occluder depth: with the iterated penumbra the
    /// buffer gains one (see [`RenderPlan::depth_planes`]) and its kernel is copied to every
    /// level ([`KernelTable::with_distance_levels`]), so the light gathered is the iterated
    /// penumbra's, bit for bit.
    fn with_subpixel_shadows(mut self, scene: &Scene) -> RenderPlan {
        let meshes: Vec<bool> = self
            .mesh_material
            .iter()
            .map(|&m| self.materials[m as usize].blocks_light())
            .collect();
        if !scene.sweep.subpixel_shadows || !meshes.iter().all(|&b| b) {
            return self;
        }
        let slabs = self.slabs;
        for light in &mut self.lights {
            if self.penumbra == Penumbra::Iterated {
                light.table = light.table.clone().with_distance_levels(slabs);
            }
            // The same f64 products and rounding as the table's `slab_shift` (`mean_carry`).
            let mean = light.moments.mean;
            let carried = light.table.slab_shift.iter().any(|&s| s != [0, 0]);
            light.carry_residual = (1..=self.slabs)
                .map(|k| {
                    let exact = mean.map(|m| m * f64::from(k));
                    if carried {
                        exact.map(|v| (v.round() - v) as f32)
                    } else {
                        [0.0; 2]
                    }
                })
                .collect();
        }
        self.subpixel_meshes = meshes;
        self
    }

    /// Sets every triangle's surface hold ([`RenderPlan::surface_hold`]) from its depth slopes
    /// and the lights' kernels.
    fn with_surface_hold(mut self, scene: &Scene, geometry: &SceneGeometry) -> RenderPlan {
        self.set_surface_holds(scene, geometry, |t| (t.depth_dx, t.depth_dy));
        self
    }

    /// Sets every rasterized triangle's surface hold ([`RenderPlan::surface_hold`]) and depth
    /// slopes ([`RenderPlan::hold_slopes`]); both empty where none holds. Its depth gradient
    /// (world units per grid pixel, x and y) is given by `gradient`: the raster plane's for a
    /// slab grid, the true depth's for a point light's perspective grid.
    pub fn set_surface_holds(
        &mut self,
        scene: &Scene,
        geometry: &SceneGeometry,
        gradient: impl Fn(&crate::prepare::raster::TriangleSetup) -> (f32, f32),
    ) {
        self.surface_hold = self.surface_holds(scene, geometry, &gradient);
        let e = geometry.slab_distance;
        self.hold_slopes = if self.has_surface_hold() {
            let per_slab = |d: f32| {
                let g = f64::from(d) / e;
                let max = surface_hold::MAX_HOLD_SLOPE;
                if g.is_nan() {
                    0.0
                } else {
                    g.clamp(-max, max) as f32
                }
            };
            let triangles = geometry.raster.triangles.iter();
            triangles
                .map(|t| {
                    let (dx, dy) = gradient(t);
                    [per_slab(dx), per_slab(dy)]
                })
                .collect()
        } else {
            Vec::new()
        };
    }

    /// Every rasterized triangle's surface hold ([`RenderPlan::surface_hold`]; empty where none
    /// holds), its depth gradient given by `gradient` ([`RenderPlan::set_surface_holds`]).
    fn surface_holds(
        &self,
        scene: &Scene,
        geometry: &SceneGeometry,
        gradient: impl Fn(&crate::prepare::raster::TriangleSetup) -> (f32, f32),
    ) -> Vec<u32> {
        let moments: Vec<KernelMoments> = self.lights.iter().map(|l| l.moments).collect();
        let e = geometry.slab_distance;
        let compensation = scene.sweep.variance_compensation;
        // Only surfaces that take out all light at every crossing are held: whether one does is
        // then known from the crossed triangle alone, before shading.
        let blocks: Vec<bool> = self
            .materials
            .iter()
            .map(MaterialPlan::blocks_light)
            .collect();
        let holds: Vec<u32> = geometry
            .raster
            .triangles
            .iter()
            .map(|t| {
                if !blocks[self.mesh_material[t.mesh as usize] as usize] {
                    return 0;
                }
                let (dx, dy) = gradient(t);
                let hold = |f: fn(&[KernelMoments], Penumbra, bool, f32, f32, f64) -> u32| {
                    f(&moments, self.penumbra, compensation, dx, dy, e)
                };
                let entry = hold(surface_hold::surface_hold);
                // Only a shell is one slab thick wherever it is crossed (see `barrier`).
                let shell = geometry.raster.parity_meshes & (1u32 << t.mesh) == 0;
                let barrier = if shell {
                    let gradient = (dx, dy);
                    surface_hold::barrier(&moments, self.penumbra, compensation, gradient, e, entry)
                } else {
                    0
                };
                surface_hold::pack_holds(entry, hold(surface_hold::exit_hold), barrier)
            })
            .collect();
        // No per-pixel hold state where no surface holds (camera-facing receivers).
        if holds.iter().any(|&h| h != 0) {
            holds
        } else {
            Vec::new()
        }
    }

    /// Whether some surface is held ([`RenderPlan::surface_hold`]): the sweep then keeps one
    /// hold state per pixel.
    #[inline(always)]
    pub fn has_surface_hold(&self) -> bool {
        !self.surface_hold.is_empty()
    }

    /// Samples every light's pattern into the initial light buffer (`None` without patterns);
    /// errors name the key and the file.
    pub fn with_patterns(
        mut self,
        scene: &Scene,
        files: &PlanFiles,
    ) -> Result<RenderPlan, PlanError> {
        // Light l's loaded pattern image, `p` its spec.
        let loaded = |l: usize, p: &PatternSpec| {
            files
                .patterns
                .get(l)
                .and_then(Option::as_ref)
                .ok_or_else(|| PlanError {
                    scene: scene.source.clone(),
                    what: format!("key `light[{l}].pattern.path`"),
                    source: TextureError::NotRead {
                        path: p.path.clone(),
                    },
                })
        };
        for (l, spec) in scene.lights.iter().enumerate() {
            if let (Some(p), Some(_)) = (&spec.pattern, spec.point) {
                self.spot_patterns.resize(scene.lights.len(), None);
                self.spot_patterns[l] = Some(Arc::new(loaded(l, p)?.clone()));
            }
        }
        if scene
            .lights
            .iter()
            .all(|l| l.pattern.is_none() || l.point.is_some())
        {
            return Ok(self);
        }
        let w = self.grid_width as usize;
        let h = self.grid_height as usize;
        let ch = self.channels as usize;
        let row_len = self.light_row_len();
        let mut buf = self.unlit_light_buffer();
        for (l, spec) in scene.lights.iter().enumerate() {
            let Some(p) = spec.pattern.as_ref().filter(|_| spec.point.is_none()) else {
                continue;
            };
            let pattern = loaded(l, p)?;
            let (tw, th) = (f64::from(pattern.width), f64::from(pattern.height));
            let (left, top) = (f64::from(self.guard.left), f64::from(self.guard.top));
            // A turned-round pass's camera x is the scene camera's reversed; `center` is the
            // scene camera's.
            let x_sign = if scene.turned_round { -1.0 } else { 1.0 };
            for y in 0..h {
                // Camera-space y of the grid pixel centre, from the view's centre.
                let cy = (y as f64 - top + 0.5 - f64::from(self.height) * 0.5) * self.pixel_size;
                let ty = ((cy - p.center[1]) / p.size[1] + 0.5) * th;
                for c in 0..ch {
                    let row = &mut buf[y * row_len + self.light_plane(l, c) * w..][..w];
                    for (x, v) in row.iter_mut().enumerate() {
                        let cx = x_sign
                            * ((x as f64 - left + 0.5 - f64::from(self.width) * 0.5)
                                * self.pixel_size);
                        let tx = ((cx - p.center[0]) / p.size[0] + 0.5) * tw;
                        let s = pattern.sample(tx, ty, c) as f32;
                        *v = if s < FLUSH_BELOW { 0.0 } else { s };
                    }
                }
            }
        }
        self.initial_light = Some(buf);
        Ok(self)
    }

    /// The column every per-pixel hash (kernel phase, jitter) is keyed by for grid column `x`:
    /// the image column, wrapping below 0 in the left guard band. The random pattern of an image
    /// pixel then does not depend on the band, so widening or narrowing it (as `auto` does when
    /// the scene moves) changes only what the band adds, not the noise.
    #[inline(always)]
    pub fn hash_x(&self, x: u32) -> u32 {
        x.wrapping_sub(self.guard.left)
    }

    /// The row every per-pixel hash is keyed by for grid row `y` (see [`RenderPlan::hash_x`]).
    #[inline(always)]
    pub fn hash_y(&self, y: u32) -> u32 {
        y.wrapping_sub(self.guard.top)
    }

    /// The image pixel coordinates, as f32, of grid column `x` and row `y` (negative inside the
    /// left and top guard band): what the detail affine `mesh_to_detail` is applied to.
    #[inline(always)]
    pub fn image_xy(&self, x: usize, y: usize) -> (f32, f32) {
        (
            (x as i64 - i64::from(self.guard.left)) as f32,
            (y as i64 - i64::from(self.guard.top)) as f32,
        )
    }

    /// Floats per light-buffer row: lights × planes per light × grid width.
    pub fn light_row_len(&self) -> usize {
        self.lights.len() * self.planes_per_light() * self.grid_width as usize
    }

    /// Entries per row of the level plane (distance penumbra: one per light and grid column; else
    /// 1, unused).
    pub fn level_row_len(&self) -> usize {
        if self.depth_planes() > 0 {
            self.lights.len() * self.grid_width as usize
        } else {
            1
        }
    }

    /// Depth planes per light: 1 (the occluder depth D) with the distance penumbra or sub-pixel
    /// shadows ([`RenderPlan::subpixel_meshes`]), else 0.
    pub fn depth_planes(&self) -> usize {
        usize::from(self.penumbra == Penumbra::Distance || !self.subpixel_meshes.is_empty())
    }

    /// Whether every level of every light's table is one kernel: the iterated penumbra keeping a
    /// depth plane for sub-pixel shadows (`KernelTable::with_distance_levels`). The gather then
    /// reads the same bits through any level, so it needs no level search; the sub-pixel read at
    /// a crossing still searches (its level tells occluder depths apart).
    pub fn levels_share_one_kernel(&self) -> bool {
        self.penumbra == Penumbra::Iterated && self.depth_planes() > 0
    }

    /// Planes per light in the light buffer: its channels, then its depth plane if any.
    pub fn planes_per_light(&self) -> usize {
        self.channels as usize + self.depth_planes()
    }

    /// Index of light `l`'s plane `c` within a light-buffer row, in units of the grid width
    /// (`c == channels` is its depth plane).
    pub fn light_plane(&self, l: usize, c: usize) -> usize {
        l * self.planes_per_light() + c
    }

    /// Whether plane `p` of a light-buffer row is a depth plane (whose unlit value is 0, not 1).
    pub fn is_depth_plane(&self, p: usize) -> bool {
        p % self.planes_per_light() >= self.channels as usize
    }

    /// The light buffer before the first slab without patterns: light 1, occluder depth 0.
    pub fn unlit_light_buffer(&self) -> Vec<f32> {
        let w = self.grid_width as usize;
        let row_len = self.light_row_len();
        let mut buf = vec![1.0f32; row_len * self.grid_height as usize];
        if self.depth_planes() > 0 {
            for row in buf.chunks_mut(row_len) {
                for (p, plane) in row.chunks_mut(w).enumerate() {
                    if self.is_depth_plane(p) {
                        plane.fill(0.0);
                    }
                }
            }
        }
        buf
    }
}

/// The material of each mesh; an open mesh (a thin shell, out of the parity test) gets its
/// material's shell variant, appended to `materials` once per material: the same material with
/// its tables built for one reference length instead of one slab, so a crossing of the shell
/// takes out the material's own opacity (`opacity` per `reference_length`, the transfer
/// function's at the crossing's detail value), whatever the slab count, and no pre-integration
/// (a shell has no slab of medium behind its crossing). Closed meshes keep their materials.
fn shell_materials(
    scene: &Scene,
    geometry: &SceneGeometry,
    files: &PlanFiles,
    materials: &mut Vec<MaterialPlan>,
) -> Result<Vec<u32>, PlanError> {
    let mut shell_of: Vec<Option<u32>> = vec![None; scene.materials.len()];
    let mut mesh_material = Vec::with_capacity(scene.meshes.len());
    for (i, mesh) in scene.meshes.iter().enumerate() {
        let m = mesh.material;
        if geometry.raster.parity_meshes & (1u32 << i) != 0 {
            mesh_material.push(m as u32);
            continue;
        }
        if shell_of[m].is_none() {
            let spec = &scene.materials[m];
            let texture = files.textures.get(m).cloned().flatten();
            let length = spec.reference_length.unwrap_or(DEFAULT_REFERENCE_LENGTH);
            let mut shell =
                material_plan(spec, length, Passes::Filter, false, texture).map_err(|source| {
                    PlanError {
                        scene: scene.source.clone(),
                        what: format!("material `{}`", spec.name),
                        source,
                    }
                })?;
            shell.light_color = materials[m].light_color.clone();
            shell_of[m] = Some(materials.len() as u32);
            materials.push(shell);
        }
        mesh_material.push(shell_of[m].unwrap_or(m as u32));
    }
    Ok(mesh_material)
}
